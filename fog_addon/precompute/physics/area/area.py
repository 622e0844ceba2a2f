"""Area lights in fog: Blender's square, rectangle, disk and ellipse emitters, their glow by the solid angle.

An area light is a flat Lambertian emitter of uniform radiance L on one side (the light's local -Z, as a
spot's axis), of area A.  Far from it, it is a point light of radiant intensity I_n cos(theta), I_n = L A
its intensity along the normal.  Near it (within a few sizes) the light a fog point x receives is L times
the solid angle Omega(x) the emitter fills there (uniform radiance: the irradiance-free in-scattering of an
isotropic medium, Sun et al. 2005 Eq. 3 summed over the emitter), dimmed by e^{-beta r}, r the distance to
its centre.  Written as a point light's intensity towards x,

    I(x) = I_n f(x),   f(x) = Omega(x) r^2 / A,

f is Lambert's cos(theta) far away (Omega -> A cos(theta) / r^2) and stays bounded as x nears the emitter
(Omega <= 2 pi), where the point light's 1/r^2 would not.  The glow along a camera ray is the point light's
airlight integral (Sun et al. 2005 Eq. 5) with f inside it (``spot.ray_quadrature``: Gauss-Legendre in
Sun's angle, as a spot's blend rim), over the part of the ray in front of the emitter (``front_interval``).
Two approximations, both measured in tests/test_area.py against quadrature over the emitter's area:

* the extinction e^{-beta r} and the phase function are taken from the emitter's centre (exact as the
  emitter shrinks; its size s changes them by about beta s / 2 across it, first order cancelling);
* a disk or an ellipse is the rectangle of the same area and aspect (its solid angle differs only within
  about its size of it).

Omega of the rectangle [-a, a] x [-b, b] in the plane z = 0 from (x, y, z) is a signed sum over its corners
of atan2(X Y, |z| R), X = +-a - x, Y = +-b - y, R = sqrt(X^2 + Y^2 + z^2) (the rectangle from the foot point
to one corner subtends atan(X Y / (z R)); four of them, signed, give any rectangle).  atan2 keeps it finite
in the emitter's plane: 2 pi inside the rectangle, 0 outside.

The kernels take the spot kernels' arguments (``rungs.area_rungs``): the point light's ray geometry (d_sv,
along, h), the ray in the light's space as ``spot.light_space_ray`` gives it (rows: any positive multiple of
the inverse of a rotation times a uniform scale: the kernels divide by |direction| to get metres), and the
emitter's half sizes in metres (``half_sizes``).
"""
import functools
import math

from ..point import model
from ..spot import spot

NODES = 8    # Gauss-Legendre points along the ray (tests/test_area.py: converged within 1e-3 of the glow)
SPLIT = 2    # the emitter as SPLIT x SPLIT cells, each with its own centre's phase and extinction (tests/test_area.py)
SPLIT_ANISOTROPIC = 3   # ... in fog of |g| >= ANISOTROPIC_G, whose phase peak varies across a cell (the area
ANISOTROPIC_G = 0.3     # scene at g 0.7: 5.3 % relative RMSE with 2 x 2 cells, 3.7 % with 3 x 3, 3.3 % with 4 x 4)


def split_for(g):
    """The emitter's cells a side for anisotropy g (SPLIT, SPLIT_ANISOTROPIC)."""
    return SPLIT_ANISOTROPIC if abs(float(g)) >= ANISOTROPIC_G else SPLIT
# I_n / P of Blender's area lights (W/sr per W): a Lambertian emitter of total flux P, radiance P / (pi A)
# (docs/measurements/2026-11-27-area-light-references.md); a point light's I / P is 1 / (4 pi)
NORMAL_INTENSITY_PER_WATT = 1.0 / math.pi
DISK_TO_SQUARE = math.sqrt(math.pi) / 2.0   # a disk of diameter s has the area of a square of side s sqrt(pi) / 2


def intensity_per_watt(light_type):
    """The radiant intensity I0 per watt of power (W/sr/W) of a Blender light of type ``light_type``: 1 / (4 pi)
    for point and spot lights (a spot's inside its cone), an area light's along its normal."""
    return NORMAL_INTENSITY_PER_WATT if light_type == "AREA" else 1.0 / (4.0 * math.pi)


def half_sizes(shape, size_x, size_y, scale=1.0):
    """(a, b) half sizes in metres of the rectangle the kernels integrate for Blender's area light ``shape``
    ('SQUARE', 'RECTANGLE', 'DISK', 'ELLIPSE'), sizes ``size_x``, ``size_y`` (m) and a uniform object
    ``scale``: a disk or an ellipse becomes the rectangle of its area and aspect."""
    if shape in ("SQUARE", "DISK"):
        size_y = size_x
    k = 0.5 * scale * (DISK_TO_SQUARE if shape in ("DISK", "ELLIPSE") else 1.0)
    return k * size_x, k * size_y


def _corner_terms(m, x, y, z, a, b, split):
    """atan2(X Y, |z| R) at the (split + 1)^2 corners of the emitter's split x split grid of cells, (X, Y) the
    corner less (x, y), R = sqrt(X^2 + Y^2 + z^2)."""
    zz, z2 = m.abs(z), z * z
    xs = [a - x if i == split else -a - x if i == 0 else m.mul_add(a, 2.0 * i / split - 1.0, -x)
          for i in range(split + 1)]
    ys = [b - y if j == split else -b - y if j == 0 else m.mul_add(b, 2.0 * j / split - 1.0, -y)
          for j in range(split + 1)]
    return [[m.atan2(bx * by, zz * m.sqrt(m.mul_add(bx, bx, m.mul_add(by, by, z2)))) for by in ys] for bx in xs]


def _cell_solid_angle(corners, i, j):
    return corners[i + 1][j + 1] - corners[i][j + 1] - corners[i + 1][j] + corners[i][j]


def solid_angle_rectangle(m, x, y, z, a, b):
    """Omega (sr) of the rectangle [-a, a] x [-b, b] at z = 0 seen from (x, y, z), any side (module
    docstring): 2 pi on the rectangle itself, 0 elsewhere in its plane."""
    return _cell_solid_angle(_corner_terms(m, x, y, z, a, b, 1), 0, 0)


def lambert_falloff(m, c_axis):
    """The light's direct intensity towards a point at cosine ``c_axis`` from its axis over I_n: Lambert's
    max(c, 0) (the shading's weight of its direct light, and of the fog light it sends onto surfaces)."""
    return m.maximum(c_axis, 0.0)


def shaft_falloff(m, u, d, *rows):
    """An area light's factor in its shafts' weights (``shafts.lit_share``, ``surface_share``) at the fog point
    light + u, d = |u| (m): Lambert's cos(theta) about its normal, ``lambert_falloff`` (its far field, which its
    solid angle factor Omega r^2 / A tends to).  ``rows``: the 9 components of the inverse of the light's 3x3 world
    matrix, row by row (a spot's driven rows, ``spot.light_space``); the third is normal to the emitter's plane
    under any scale, pointing away from the side that emits.  The shares are ratios of lit to all fog, which the
    light's own glow then scales: its shape near the emitter (the solid angle) is left to the glow."""
    normal = m.combine(*rows[6:9])
    return lambert_falloff(m, m.dot(normal, u) * -1.0 / m.maximum(m.length(normal) * d, 1e-30))


def _metres(m, dx, dy, dz):
    """1 / |d|: the light-space ray's scale (``spot.light_space_ray`` of a unit world direction)."""
    return 1.0 / m.maximum(m.sqrt(m.mul_add(dx, dx, m.mul_add(dy, dy, dz * dz))), 1e-30)


def front_interval(m, pz, dz, t_end):
    """[lo, hi] (lo >= hi: empty) of t in [0, t_end] where the light-space ray point's z = pz + t dz is below
    0 (in front of the emitter)."""
    safe = m.select(m.less(m.abs(dz), 1e-30), 1e-30, dz)
    cross = -pz / safe
    heads_out = m.less(0.0, dz)   # z grows along the ray: in front until it crosses
    lo = m.select(heads_out, 0.0, m.select(m.less(dz, 0.0), cross, m.select(m.less(pz, 0.0), 0.0, t_end)))
    hi = m.select(heads_out, cross, t_end)
    lo = m.maximum(lo, 0.0)
    hi = m.minimum(hi, t_end)
    return lo, m.maximum(hi, lo)


def front_hit(m, px, py, pz, dx, dy, dz, t_end):
    """1 if the ray (light space) has a piece in front of the emitter before ``t_end``, else 0: elsewhere the
    light's glow is 0 (``shading.Gated``)."""
    lo, hi = front_interval(m, pz, dz, t_end)
    return m.less(lo, hi)


def smeared_phase(m, g, cos_theta, omega):
    """4 pi p: the Henyey-Greenstein phase weight (1 for isotropic fog) of light arriving from an emitter
    that fills the solid angle ``omega`` (sr), at the scattering angle's cosine ``cos_theta`` from its centre.
    The phase function averaged over a cap of that solid angle has Legendre coefficients g^l c_l, c_l the
    cap's; keeping the first, it is Henyey-Greenstein's of g c_1, c_1 = (1 + cos alpha) / 2 the cap's mean
    cosine, cos alpha = 1 - omega / (2 pi): the centre's phase as the emitter shrinks, flattened where it
    fills the view of the fog point (measured in tests/test_area.py)."""
    if not g:
        return 1.0
    g_eff = g * m.clamp01(1.0 - omega * (0.25 / math.pi))
    return (1.0 - g_eff * g_eff) * m.power(m.maximum(1.0 + g_eff * g_eff - 2.0 * g_eff * cos_theta, 1e-12), -1.5)


def _profile(m, t, px, py, pz, dx, dy, dz, a, b, beta, *, g, split):
    """f at the ray's point t (light space in metres): the cells' solid angles times their extinction over the
    centre's and their smeared phase (``smeared_phase``), times r^2 / A (in front of the emitter: the callers
    integrate over ``front_interval``)."""
    x, y, z = m.mul_add(t, dx, px), m.mul_add(t, dy, py), m.mul_add(t, dz, pz)
    r2 = m.mul_add(x, x, m.mul_add(y, y, z * z))
    r = m.sqrt(r2)
    corners = _corner_terms(m, x, y, z, a, b, split)
    f = 0.0
    for i in range(split):
        for j in range(split):
            omega = _cell_solid_angle(corners, i, j)
            if split == 1:
                cx, cy, rk, w = x, y, r, omega
            else:
                cx = x - a * ((2.0 * i + 1.0) / split - 1.0)
                cy = y - b * ((2.0 * j + 1.0) / split - 1.0)
                rk = m.sqrt(m.mul_add(cx, cx, m.mul_add(cy, cy, z * z)))
                w = omega * m.exp(beta * (r - rk))   # the cell's extinction over the centre's
            if g:   # the light leaves the cell along (cx, cy, z) / rk and scatters towards the camera, -d
                cos_theta = -m.mul_add(cx, dx, m.mul_add(cy, dy, z * dz)) / m.maximum(rk, 1e-30)
                w = w * smeared_phase(m, g, cos_theta, omega)
            f = f + w
    return f * r2 / m.maximum(4.0 * a * b, 1e-30)


def _glow(m, beta, d_sv, along, h, t0, t1, px, py, pz, dx, dy, dz, a, b, g, nodes, split=None):
    """f times the point light's airlight over [t0, t1] (1/m^2 per unit I_n): ``spot.ray_quadrature`` with
    ``_profile`` (one shared sub-program, ``m.group``, called at each of its points)."""
    k = _metres(m, dx, dy, dz)
    ray = tuple(v * k for v in (px, py, pz, dx, dy, dz))
    split = split_for(g) if split is None else int(split)
    fn = functools.partial(_profile, g=float(g), split=split)
    name = f"Area Profile [g {float(g):+.3f}, {int(split)}x{int(split)}]"
    h = m.maximum(h, model.MIN_ANGLE * model.MIN_DISTANCE)   # a camera on the emitter's centre: d_sv = h = 0
    d_sv = m.maximum(d_sv, h)
    return spot.ray_quadrature(m, beta, d_sv, along, h, t0, t1, lambda t: m.group(name, fn, t, *ray, a, b, beta),
                               0.0, nodes)


def _airlight(m, beta, d_sv, along, h, d_vp, px, py, pz, dx, dy, dz, a, b, *, g, nodes, split=None):
    lo, hi = front_interval(m, pz, dz, d_vp)
    return _glow(m, beta, d_sv, along, h, lo, hi, px, py, pz, dx, dy, dz, a, b, g, nodes, split)


def _kernel_keywords(g, nodes):
    return dict(g=float(g), nodes=int(nodes))


def airlight(m, beta, d_sv, along, h, d_vp, px, py, pz, dx, dy, dz, a, b, *, g=0.0, nodes=NODES):
    """Airlight of an area light per unit normal intensity I_n, 1/m^2, along a camera ray to a surface at
    ``d_vp`` (m; model.FAR for the sky): Sun et al. 2005 Eq. 5 with the emitter's profile f inside (module
    docstring).  (a, b): ``half_sizes``; g: Henyey-Greenstein anisotropy (Python float)."""
    fn = functools.partial(_airlight, **_kernel_keywords(g, nodes))
    return m.group(f"Area Airlight [g {float(g):+.3f}, {int(nodes)} points]", fn, beta, d_sv, along, h, d_vp,
                   px, py, pz, dx, dy, dz, a, b)


def airlight_background(m, beta, d_sv, along, h, px, py, pz, dx, dy, dz, a, b, *, g=0.0, nodes=NODES):
    """:func:`airlight` of a ray that meets no surface (Sun et al. 2005 Eq. 12), 1/m^2."""
    return airlight(m, beta, d_sv, along, h, model.FAR, px, py, pz, dx, dy, dz, a, b, g=g, nodes=nodes)


def _airlight_pair(m, beta, d_sv, along, h, d_vp, px, py, pz, dx, dy, dz, a, b, *, g, nodes):
    lo, hi = front_interval(m, pz, dz, model.FAR)
    background = _glow(m, beta, d_sv, along, h, lo, hi, px, py, pz, dx, dy, dz, a, b, g, nodes)
    cut = m.minimum(hi, d_vp)
    surface = _glow(m, beta, d_sv, along, h, lo, m.maximum(cut, lo), px, py, pz, dx, dy, dz, a, b, g, nodes)
    return surface, background


def airlight_pair(m, beta, d_sv, along, h, d_vp, px, py, pz, dx, dy, dz, a, b, *, g=0.0, nodes=NODES):
    """(:func:`airlight` to the surface at ``d_vp``, :func:`airlight_background`) of one ray, 1/m^2, for the
    compositor (a pixel partly covered mixes the two)."""
    fn = functools.partial(_airlight_pair, **_kernel_keywords(g, nodes))
    return m.group(f"Area Airlight Pair [g {float(g):+.3f}, {int(nodes)} points]", fn, beta, d_sv, along, h,
                   d_vp, px, py, pz, dx, dy, dz, a, b)


def scatter(m, beta, d_sp, cos_n, cos_r, level, c_axis, a, b, cos_n_axis, cos_r_axis, *, point, g=0.0):
    """(diffuse, glossy): the fog light an area light scatters onto a surface per unit albedo and unit I_n
    (1/m^2): the emitter taken as a point with Lambert's cosine about its axis (its size left out), the spot's
    mean-direction model with the cosine-weighted share (``spot.lambert_scatter``, Sun et al. 2005 Eq. 15
    over the fog the emitter lights)."""
    return spot.lambert_scatter(m, beta, d_sp, cos_n, cos_r, level, c_axis, cos_n_axis, cos_r_axis, point=point,
                                g=g)
