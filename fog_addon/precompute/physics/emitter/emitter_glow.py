"""Glows of glowing objects (emissive surfaces) by depth-dependent convolution, as a sum of Gaussian blurs.

Narasimhan, Ramamoorthi, Nayar §7.2-7.3: a source of any shape glows as its image convolved with the point
spread function of its depth.  A pixel q of an emitter of radiance L_q at optical depth T_q = beta z_q is a
source of intensity L_q Omega_px z_q^2; its glow at a pixel p an angle gamma away is (``weather.py``)

    L_q K(T_q, gamma),   K(T, gamma) = Omega_px T^2 W0 I_1(T, cos gamma),

I_1 the single-scattering field of an endless ray at extinction 1 (Sun et al. 2005 Eq. 12, per unit
intensity).  Summing over q is a convolution whose kernel changes with q's depth.  The compositor has
Gaussian blurs of any size (Blender's Blur node: a separable Gaussian of sigma = size / 3, cut at the size,
``blur_weights``), so the kernel is written, for every T, as a non-negative sum of a fixed ladder of them,

    K(T, gamma(r)) ~ sum_j a_j(T) B_j(r),

and the glow as  sum_j B_j * (a_j(T(q)) L(q)):  one blur per rung of the ladder, whatever the depths, the
depth entering only the per-pixel weights a_j(T) (a table over T, ``bake_weights``).

The ladder holds the kernel's near part only, K (1 - s(gamma)), s the far window (``far_window``: a smooth step
from FAR_SPAN[0] to FAR_SPAN[1] of the far angle ``far_angle``).  Far from an emitter its shape no longer shows and
its glow is that of point sources: the compositor adds each glowing object's points' glows (the point lights' own
kernels, Sun et al. 2005 Eq. 11-12, exact to the pixel's surface) times s (``comp_emitters.far_glows``).  A sum of
Gaussians fits K's 1/gamma tail only so far (the fit weighs rings relatively, its largest Gaussian reaches 512 px),
and the kernel is taken as radial in pixels at the picture's centre, where a pixel's angle is the centre's: far
from the source both fall short (a sphere's ground 0.76-0.9 of path tracing 100-200 px away).  The ladder's sizes
double from 1 px; the fit is least squares, relative, over the kernel's core (supersampled: the kernel
diverges as 1/gamma at a source's own pixel) and its tail to the largest size (tests/test_emitter_glow.py
measures it ring by ring).

The weights depend on the camera's pixel angle (rad / px at the picture's centre; the kernel is taken as
radial there) and on g; they are baked when the fog is applied.
"""
import functools
import math

import numpy as np

from ...core import tables as tables_
from ..point import model, multiple
from .emitter_table import SIZES, T_COUNT, T_COUNT_DENSE, T_MAX, T_MIN
from .emitter_table import (FACING_COUNT, FACING_KIND_KEY, KIND_KEY, estimate_seconds, facing_spec,  # noqa: F401
                            needs, table_spec)
from ...core.ops import NumpyOps

FAR_ANGLE = 0.3      # rad: where the glow is the points' alone (``far_angle``), at most FAR_PIXELS px
FAR_PIXELS = 300     # px: ... within the fit's grid (HALF) and the ladder's reach
FAR_SPAN = (0.1, 1.0)   # the far window's smooth step, as fractions of the far angle
CORE_SUBSAMPLES = 8   # the kernel at a source's own pixel and its neighbours, averaged over 8 x 8 points
CORE = 2              # px: the core's half-width
HALF = 400            # px: the fit's grid about a source (the largest blur reaches 512)


def glow_field(g, tables, multiple_albedo=None):
    """The field a glowing pixel's kernel is made of, per unit intensity and unit albedo at extinction 1: I_1
    (``single_field``), plus I_{>=2} / W0 (``multiple.field``, Narasimhan et al.'s multiply scattered field:
    Dense Fog) when ``multiple_albedo`` W0 is given.  ``tables``: how to read the tables (a ``TableReader``)."""
    single = single_field(g, tables)
    if multiple_albedo is None:
        return single
    spec = multiple.table_spec(g, multiple_albedo)
    m = NumpyOps({spec.name: tables.array(spec, g)})
    return lambda t, c: single(t, c) + multiple.field(m, spec, t, c)


def single_field(g, tables):
    """I_1(T, cos gamma): the single-scattering field of an endless ray at extinction 1 per unit intensity (Sun et
    al. 2005 Eq. 12, the background rung of anisotropy g on numpy), T the distance to the source; ``tables``: a
    ``TableReader``."""
    g = float(g)
    m = NumpyOps(tables.per_g(g))

    def single(t, c):   # (the background table rung's kernel: ``rungs.anisotropic_rungs(g)[1]``)
        with np.errstate(all="ignore"):
            v = model.airlight_background(m, 1.0, t, t * c, t * np.sqrt(np.maximum(1.0 - c * c, 0.0)), g=g)
        return np.nan_to_num(v, nan=0.0, posinf=0.0)

    return single


def blur_weights(size):
    """The 1D weights of Blender's Gaussian Blur node of ``size`` px (sigma = size / 3, cut at |i| <= size:
    Blender's ``RE_filter_value`` Gaussian on i / size), normalised; a size below 1 is no blur."""
    n = int(round(size))
    if n < 1:
        return np.ones(1)
    i = np.arange(-n, n + 1, dtype=float)
    w = np.exp(-4.5 * (i / n) ** 2)
    return w / w.sum()


def blur_kernel_2d(size, half):
    """The 2D kernel (2 half + 1 square, centred) of the Blur node of ``size``: the outer product of
    ``blur_weights``, cut to the square."""
    w = blur_weights(size)
    n = len(w) // 2
    k = np.zeros(2 * half + 1)
    lo, hi = max(0, n - half), min(len(w), n + half + 1)
    k[half - (n - lo):half + (hi - n)] = w[lo:hi]
    return np.outer(k, k)


def _nnls(a, b, iterations=200):
    """min |a x - b| with x >= 0 (Lawson and Hanson's active set; a: (M, N), small N)."""
    m, n = a.shape
    x = np.zeros(n)
    passive = np.zeros(n, bool)
    for _ in range(iterations):
        w = a.T @ (b - a @ x)
        if passive.all() or np.max(np.where(passive, -np.inf, w)) <= 1e-12 * max(1.0, np.abs(w).max()):
            break
        passive[int(np.argmax(np.where(passive, -np.inf, w)))] = True
        while True:
            z = np.zeros(n)
            z[passive] = np.linalg.lstsq(a[:, passive], b, rcond=None)[0]
            if np.all(z[passive] > 0.0):
                x = z
                break
            bad = passive & (z <= 0.0)
            alpha = np.min(x[bad] / np.maximum(x[bad] - z[bad], 1e-300))
            x = x + alpha * (z - x)
            passive &= x > 1e-15
    return x


def far_angle(pixel_angle):
    """rad: the angle from a glowing object beyond which its glow is its points' alone: FAR_ANGLE, or FAR_PIXELS
    pixels of ``pixel_angle`` (rad/px) where that is less (a picture of many pixels: the ladder's Gaussians reach
    512 px)."""
    return min(FAR_ANGLE, FAR_PIXELS * float(pixel_angle))


def far_window(m, gamma, pixel_angle):
    """s in [0, 1]: the far part's share of the glow kernel at ``gamma`` rad from its source (module docstring), a
    smooth step over FAR_SPAN of ``far_angle``; the ladder holds 1 - s of it."""
    top = far_angle(pixel_angle)
    return m.smoothstep(FAR_SPAN[0] * top, FAR_SPAN[1] * top, gamma)


def kernel_grid(t, pixel_angle, single, albedo, half, near=True):
    """The near kernel K(T, gamma) (1 - s(gamma)) per unit source radiance on the (2 half + 1)^2 pixel grid about a
    source (module docstring; ``single(T, cos gamma)``: I_1 per unit intensity at extinction 1; s ``far_window``),
    its core supersampled; the whole kernel K with ``near`` False."""
    d = np.arange(-half, half + 1, dtype=float)
    dx, dy = np.meshgrid(d, d)
    kern = _kernel_at(t, pixel_angle, single, albedo, dx, dy, near)
    return kern.reshape(dx.shape)


def kernel_octant(t, pixel_angle, single, albedo, half, near=True):
    """``kernel_grid``'s values at ``_octant``'s points only (the kernel is radial; the fit reads no others)."""
    (rows, cols), _ = _octant(half)
    return _kernel_at(t, pixel_angle, single, albedo, (cols - half).astype(float), (rows - half).astype(float), near)


def _kernel_at(t, pixel_angle, single, albedo, dx, dy, near=True):
    """The near kernel K(T, gamma) (1 - s(gamma)) (``near``; else K) at the pixel offsets (dx, dy) from a source
    (any shape, flattened), those within CORE of it supersampled (CORE_SUBSAMPLES^2 points each)."""
    dx, dy = np.ravel(dx), np.ravel(dy)
    m = NumpyOps()

    def k_at(r_px):
        gamma = r_px * pixel_angle
        share = 1.0 - far_window(m, gamma, pixel_angle) if near else 1.0
        return albedo * single(np.full(gamma.shape, float(t)), np.cos(gamma)) * share

    kern = k_at(np.hypot(dx, dy))
    sub = (np.arange(CORE_SUBSAMPLES) + 0.5) / CORE_SUBSAMPLES - 0.5
    sx, sy = np.meshgrid(sub, sub)
    for k in np.nonzero((np.abs(dx) <= CORE) & (np.abs(dy) <= CORE))[0]:
        kern[k] = float(np.mean(k_at(np.hypot(dx[k] + sx, dy[k] + sy))))
    return kern * (pixel_angle ** 2) * float(t) ** 2


def _octant(half):
    """Indices (i, j) of the grid's octant 0 <= dx <= dy about the centre, with the count of grid pixels each
    stands for (the kernels are symmetric under the square's eight symmetries)."""
    d = np.arange(0, half + 1)
    dx, dy = np.meshgrid(d, d)
    keep = dx <= dy
    count = np.where(dx == dy, 4.0, 8.0) / np.where(dx == 0, 2.0, 1.0)
    count = np.where((dx == 0) & (dy == 0), 1.0, count)
    return (half + dy[keep], half + dx[keep]), count[keep]


def fit_weights(kern, sizes=None, scale=None):
    """(a_j) >= 0 with sum_j a_j B_j ~ ``kern`` (square, centred), least squares relative to ``scale`` (default
    ``kern``; the whole kernel K where ``kern`` is its near part, which falls to 0: each pixel weighted by 1 / K, so
    the tail counts as much as the core and the near part's error as what it adds to the whole glow), on the
    grid's octant (each point weighted by the pixels it stands for)."""
    half = kern.shape[0] // 2
    idx, _ = _octant(half)
    return fit_octant(kern[idx], half, sizes, None if scale is None else scale[idx])


def fit_octant(target, half, sizes=None, scale=None):
    """``fit_weights`` of a kernel given at ``_octant(half)``'s points (``kernel_octant``)."""
    sizes = SIZES if sizes is None else tuple(sizes)
    basis, count = _octant_basis(half, sizes)
    scale = target if scale is None else scale
    weight = np.sqrt(count) / np.maximum(scale, 1e-30 * max(float(scale.max()), 1e-300))
    return _nnls(basis * weight[:, None], target * weight)


@functools.lru_cache(maxsize=4)
def _octant_basis(half, sizes):
    """(the Blur nodes' kernels of ``sizes`` at the octant's points (points, sizes), the points' counts)."""
    idx, count = _octant(half)
    return np.stack([blur_kernel_2d(s, half)[idx] for s in sizes], axis=1), count


def rung_angle(size, pixel_angle):
    """A rung's typical angle (rad) from its source: the mean radius of the Blur node's Gaussian (sigma = size / 3;
    a 2D Gaussian's mean radius is sigma sqrt(pi / 2))."""
    return float(size) / 3.0 * math.sqrt(math.pi / 2.0) * float(pixel_angle)


def segment_share(m, t_surface, t_source, gamma):
    """The share of a source's glow along an endless ray that the ray's first stretch, to a surface at optical
    depth ``t_surface``, holds: the source at optical depth ``t_source`` seen ``gamma`` (rad, a Python float) off
    the ray.  The glow's integrand is ~ 1 / r^2 about the ray's closest point to the source (at T cos gamma, T
    sin gamma from it: Sun et al. 2005 Eq. 5 without the extinction's slow change), whose integral to the
    surface over its whole is

        [atan((T_p - T cos gamma) / (T sin gamma)) + pi/2 - gamma] / (pi - gamma):

    0 at the camera, 1/2 at the closest point, 1 far behind the source.  A glowing object's glow stops at the
    surfaces in front of it so (``comp_emitters.glows``, one share per rung of the ladder at its
    ``rung_angle``)."""
    c, s_ = math.cos(gamma), max(math.sin(gamma), 1e-6)
    x = (t_surface - t_source * c) / m.maximum(t_source * s_, 1e-12)
    return (m.atan2(x, 1.0) + (0.5 * math.pi - gamma)) * (1.0 / (math.pi - gamma))


def log_linear(t, slope):
    """ln T + slope T (numpy or a float): a coordinate in which points spread geometrically where T << 1 / slope
    and evenly where T >> 1 / slope (the weights' table's columns, ``weather``'s layers)."""
    return np.log(t) + slope * np.asarray(t, float)


def log_linear_depths(lo, hi, count, slope):
    """``count`` optical depths from ``lo`` to ``hi``, even in ``log_linear`` (inverted by Newton's method from
    T = e^s, held within [lo / 2, 2 hi]; the ends exact)."""
    s = np.linspace(float(log_linear(lo, slope)), float(log_linear(hi, slope)), count)
    t = np.exp(np.minimum(s, math.log(hi)))
    for _ in range(60):
        t = np.clip(t - (np.log(t) + slope * t - s) / (1.0 / t + slope), 0.5 * lo, 2.0 * hi)
    t[0], t[-1] = lo, hi
    return t


def optical_depths(count=T_COUNT):
    """The T of the weights' table columns: even in s = ln T + T from T_MIN to T_MAX (``table_x``)."""
    return log_linear_depths(T_MIN, T_MAX, count, 1.0)


def table_x(m, t):
    """The weights' table X of optical depth ``t``: s = ln T + T over [s(T_MIN), s(T_MAX)], clamped (a source
    nearer than T_MIN glows with T_MIN's shares and normalisation, ``source_weight``).  The columns are
    geometric in T where T << 1 and uniform where T >> 1, where the shares change with T, not ln T."""
    lo, hi = float(log_linear(T_MIN, 1.0)), float(log_linear(T_MAX, 1.0))
    tt = m.maximum(t, T_MIN)
    return m.clamp01((m.log(tt) + tt - lo) * (1.0 / (hi - lo)))


def bake_weights(single, pixel_angle, count=T_COUNT, progress=None):
    """(len(SIZES) + 1, count) float32 per unit albedo: at each ``optical_depths`` T, the fit's weights a_j(T)
    (``fit_weights``) as shares a_j / N of their sum N(T), and in the last row ln(N e^T / T).

    The table is read between its columns linearly (``source_weight``): a_j(T) itself falls as T e^{-T} (single
    scattering), which a linear read between columns overestimates where T >> 1 (the curvature of ln T - T);
    N e^T / T is nearly flat for single scattering, and the shares change slowly."""
    out = np.zeros((len(SIZES) + 1, count))
    for k, t in enumerate(optical_depths(count)):
        if progress is not None:
            progress(k, count)
        a = fit_octant(kernel_octant(t, pixel_angle, single, 1.0, HALF), HALF,
                       scale=kernel_octant(t, pixel_angle, single, 1.0, HALF, near=False))
        total = float(a.sum())
        if total > 0.0:
            out[:-1, k] = a / total
            out[-1, k] = math.log(total) + t - math.log(t)
        else:
            out[-1, k] = -80.0
    if progress is not None:
        progress(count, count)
    return out.astype(np.float32)


def bake_table(g, pixel_angle, tables, multiple_albedo=None, progress=None):
    """The weights' table (``table_spec``) of anisotropy g at ``pixel_angle``: ``bake_weights`` of its field
    (``glow_field``, its tables read through ``tables``).  ``progress(done, total)``: called at each column (it may
    raise ``table_cache.BakeCancelled``)."""
    count = T_COUNT if multiple_albedo is None else T_COUNT_DENSE
    return bake_weights(glow_field(g, tables, multiple_albedo), pixel_angle, count, progress)


def source_weight(m, spec, t):
    """e^T N(T): what the (dimmed) Emission pass of a pixel at optical depth ``t`` is multiplied by to give its
    glow's total weight (undimmed by e^T; N the sum of its rungs' weights), from the last row of ``spec``'s table:
    exp(ln(N e^T / T)) T.  No e^T is evaluated, so no depth overflows it."""
    return m.exp(m.table(spec, table_x(m, t), 1.0)) * t


def rung_share(m, spec, x, j):
    """The share a_j / N of rung j of ``spec``'s table at table X ``x`` (``table_x``)."""
    return m.table(spec, x, j / float(len(SIZES)))


# --- a flat emitter's light towards the fog: the facing factor --------------------------------------------------
#
# Each pixel q of a glowing object is a source of intensity L_q Omega_px z_q^2 (Narasimhan's 7.2: isotropic), which
# holds for a sphere but sends a flat emitter's light sideways as strongly as towards the camera.  A patch of area
# A_q = Omega_px z_q^2 / c_q (c_q = |cos| between its normal and the camera) that emits L_q from both faces (an
# Emission shader) has the intensity L_q A_q |n . omega| towards omega.  Its glow weighs the directions omega from
# it to the fog its glow rays pass by the single scattering along them; with their mean E(c) of |n . omega|, the
# source's intensity is L_q Omega_px z_q^2 E(c_q) / c_q.  For any centrally symmetric convex object (a sphere, a
# box, a cylinder) the surface the camera sees, taken two-sided, has the whole object's intensity in every
# direction (a line meets that half of the surface once on average), so its pixels' factors average to 1: only
# flat and open emitters change.

MIN_FACING = 0.02    # c below this counts as this (a sphere's limb, a sign seen edge-on: at most 20x the isotropic)
FACING_NODES = 512   # midpoint nodes over theta of ``facing_mean``


def facing_mean(c, g=0.0, nodes=FACING_NODES):
    """E(c): the mean of |n . omega| over the directions omega from a flat emitter to the fog its glow's rays pass,
    c the |cos| of its normal to the camera.  A ray passing the emitter meets the fog at the angle theta about it
    (Sun et al. 2005 Eq. 6: the airlight's 1/d^2 integrand is flat in theta, uniform over (-pi/2, pi/2) for a
    source far from the camera), omega = sin(theta) v + cos(theta) p, v the view direction and p the unit
    perpendicular from the emitter to the ray, at every azimuth phi about v; each theta weighs by the phase
    function of its scattering towards the camera, p_HG(-sin theta).  With n . v = c and n . p = s cos(phi)
    (s = sqrt(1 - c^2)), the azimuths' mean of |A + B cos(phi)| (A = c sin(theta), B = s cos(theta)) is closed
    (``_azimuth_mean``).  g = 0: (4 / pi^2) E_ell(1 - c^2), 2 / pi face-on.  The azimuths' mean is even in theta,
    so the phase function's spread matters, not its direction."""
    c = np.clip(np.asarray(c, float), 0.0, 1.0)
    theta = (np.arange(nodes) + 0.5) / nodes * np.pi - 0.5 * np.pi
    mu = -np.sin(theta)
    weight = (1.0 - g * g) / (1.0 + g * g - 2.0 * g * mu) ** 1.5
    a = c[..., None] * np.sin(theta)
    b = np.sqrt(1.0 - c * c)[..., None] * np.cos(theta)
    return (_azimuth_mean(a, b) * weight).sum(axis=-1) / weight.sum()


def _azimuth_mean(a, b):
    """(1 / 2 pi) int_0^{2 pi} |a + b cos(phi)| d phi for b >= 0: |a| where b <= |a|, else
    (2 / pi) (a asin(a / b) + sqrt(b^2 - a^2))."""
    b = np.maximum(b, 0.0)
    crossing = b > np.abs(a)
    ratio = np.where(crossing, a / np.where(crossing, b, 1.0), 0.0)
    inner = (2.0 / np.pi) * (a * np.arcsin(np.clip(ratio, -1.0, 1.0)) + np.sqrt(np.maximum(b * b - a * a, 0.0)))
    return np.where(crossing, inner, np.abs(a))


def facing_dipole(c, g=0.0, nodes=FACING_NODES, azimuths=FACING_NODES // 2):
    """D(c): the first Fourier coefficient, over the azimuth phi about the source in the image, of the same mean
    of |n . omega| (``facing_mean`` is its zeroth): a flat emitter glows more on the side its normal leans to
    (phi measured from the normal's projection on the picture, the normal taken facing the camera), as
    E(c) + D(c) cos phi.  With n . v = -c (v the view direction) and n . p = s cos phi, the mean over theta of
    |-c sin(theta) + s cos(phi) cos(theta)| (weighted by p_HG(-sin theta), as ``facing_mean``) is F(phi), and
    D = (1 / pi) int F(phi) cos(phi) d phi, by the midpoint rule in theta and phi.  0 face-on and edge-on."""
    c = np.clip(np.asarray(c, float), 0.0, 1.0)[..., None, None]
    theta = ((np.arange(nodes) + 0.5) / nodes * np.pi - 0.5 * np.pi)[None, :]
    phi = ((np.arange(azimuths) + 0.5) / azimuths * 2.0 * np.pi)[:, None]
    weight = (1.0 - g * g) / (1.0 + g * g + 2.0 * g * np.sin(theta)) ** 1.5
    s = np.sqrt(1.0 - c * c)
    f = (np.abs(-c * np.sin(theta) + s * np.cos(phi) * np.cos(theta)) * weight).sum(axis=-1) / weight.sum()
    return 2.0 * np.mean(f * np.cos(phi)[..., 0], axis=-1)


def facing_factor(m, c, mean):
    """A glowing pixel's intensity over the isotropic source's (the section above): ``mean`` (E(c), ``facing_mean``:
    read from the table of ``facing_spec``) / max(c, MIN_FACING); given D(c) (``facing_dipole``, the table's
    second row), its cos(phi) term's."""
    return mean / m.maximum(c, MIN_FACING)


def dipole_scale(size):
    """The dipole's rung factor sigma^2 / rho (px) of the Blur node of ``size``: a kernel's cos(phi) B(r) is
    written as (r . u) B(r) / rho = -(sigma^2 / rho) u . grad B(r), rho = sigma sqrt(pi / 2) the Gaussian's mean
    radius (which keeps the cos phi moment of the kernel: int (cos phi)^2 B = 1/2)."""
    sigma = float(size) / 3.0
    return sigma / math.sqrt(0.5 * math.pi)


DIPOLE_MIN_SIZE = 4   # px: rungs of this size and up carry the dipole (their gradient by +-1 px differences)


def bake_facing(g):
    """(2, FACING_COUNT) float32: ``facing_mean`` and ``facing_dipole`` at c = 0 .. 1."""
    c = np.linspace(0.0, 1.0, FACING_COUNT)
    return np.stack([facing_mean(c, g), facing_dipole(c, g)]).astype(np.float32)


def _bake_kind(spec, progress=None, tables=None):
    """``bake_table`` of the arguments ``spec`` was made from (``table_spec``)."""
    g, pixel_angle, multiple_albedo = spec.args
    return bake_table(g, pixel_angle, tables, multiple_albedo, progress)


KIND = tables_.TableKind(KIND_KEY, make=table_spec, bake=_bake_kind, estimate=estimate_seconds, needs=needs,
                         reads=True, label=lambda spec: f"the glowing objects' table ({tables_.details(spec)})")
FACING_KIND = tables_.TableKind(FACING_KIND_KEY, make=facing_spec, estimate=lambda spec: 0.1,
                                bake=lambda spec, progress=None: bake_facing(spec.args[0]))
TABLE_KINDS = (KIND, FACING_KIND)   # (``registry.KINDS``)
