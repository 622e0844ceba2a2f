"""Spot lights in fog: Blender's cone and blend, the ray clipped to the cone, the rim integrated (issue 9).

Blender's spot (Cycles and EEVEE, measured per pixel: ../shared/notes/blender-facts.md section 1):
the intensity towards a point is the point light's times

    f = smoothstep((c - c_h) / ((1 - c_h) b)),   c_h = cos(size / 2),  b = blend,

c the cosine between the light-to-point direction in the light's own space (non-uniform scale
deforms the cone) and its local -Z axis; a hard cut (f = 1 inside) when b = 0; no other cos factor.
The spot's radius (soft shadows) and "show cone" (a viewport drawing) change nothing in the fog.

Along a camera ray the airlight (Sun et al. 2005 Eq. 5, per unit intensity) becomes
int f(c(t)) w(t) beta e^{-beta (d + t)} / (4 pi d^2) dt.  The cone of half-angle <= 90 degrees is
convex, so a ray meets the set where c >= k in one interval (``cone_interval``):

* inside the inner cone (c >= c_in = c_h + (1 - c_h) b) f = 1 and the point light's integral applies
  unchanged on that sub-segment (Pegoraro et al.: the segment's bounds are free; here the viewer moved
  to the segment's start, any point-light airlight rung of ``rungs.py``, times the extinction to it);
* on the blend rim (c_h < c < c_in, at most two intervals) f varies smoothly and the integral is taken
  by Gauss-Legendre quadrature in u = tan(xi / 2), xi Sun's angle (``_rim``: ``RIM_NODES`` points per
  interval, or fewer, ``RIM_LADDER``, where the Quality allows).

The kernels take scalars only (so OSL runs them as they are): the point light's ray geometry
(d_sv, along, h) and the ray in the light's space, p = M^-1 (origin - light) and d = M^-1 direction
(``light_space_ray``), M the light's 3x3 world matrix.
"""
import functools
import math
from typing import Any, NamedTuple

import numpy as np

from ...core import tables
from ..point import model

RIM_NODES = 10    # Gauss-Legendre points per rim interval (tests/test_spot.py, 200 random spots per case: max
                  # 2.0e-3 of the whole glow with non-uniform scale and g = -0.5)
RIM_LADDER = (RIM_NODES, 6, 4)   # the rim's point counts a spot's glow can take, exact first: fewer where the
#                                  view's samples show they move no pixel beyond the Quality's target (predict.py);
#                                  over random spots (tests/test_spot.py) 6 points are within 1.4e-2, 4 within 4.6e-2
RIM_DEPTH = 12.0   # the rim's quadrature stops this optical depth past its start (e^-12 = 6e-6)
INNER_DEPTH = 60.0   # the inner segment stops this optical depth past its start (e^-60 = 1e-26)


@functools.lru_cache(maxsize=None)
def _gauss_legendre(n):
    return tuple((float(x), float(w)) for x, w in zip(*np.polynomial.legendre.leggauss(n)))


def ramp_end(m, cos_half, blend):
    """The cosine where Blender's blend ramp reaches 1: c_h + (1 - c_h) b, at least 1e-7 above c_h (blend = 0:
    Blender's hard cut as a ramp 1e-7 wide in cosine, under 2e-4 degrees for any cone: no pixel shows it)."""
    return cos_half + m.maximum((1.0 - cos_half) * blend, 1e-7)


def ramp(m, c, cos_half, cos_end):
    """Blender's spot factor f in [0, 1] at the cosine c to the axis: smoothstep((c - c_h) / ((1 - c_h) b))
    (module docstring), given ``ramp_end``: one Map Range node in shader nodes."""
    return m.smoothstep(cos_half, cos_end, c)


def spot_falloff(m, c, cos_half, blend):
    """Blender's spot factor f in [0, 1] for the cosine c to the axis, ``cos_half`` = cos(size / 2),
    ``blend`` in [0, 1] (blend = 0: a hard cut at c = cos_half, ``ramp_end``)."""
    return ramp(m, c, cos_half, ramp_end(m, cos_half, blend))


def light_space(m, rows, v):
    """(x, y, z) of the world vector ``v`` in the light's space: rows = the three rows of the inverse of
    the light's 3x3 world matrix (any positive multiple of them: only directions matter)."""
    return m.dot(rows[0], v), m.dot(rows[1], v), m.dot(rows[2], v)


def light_space_ray(m, rows, origin, direction, light):
    """(px, py, pz, dx, dy, dz): a camera ray's origin relative to the light and its direction, in the
    light's space (the spot kernels' arguments)."""
    return (*light_space(m, rows, origin - light), *light_space(m, rows, direction))


def axis_cosine(m, rows, point, light):
    """The cosine c between the light's axis and the direction from the light to a world ``point``, in the
    light's space (where Blender measures its cone)."""
    x, y, z = light_space(m, rows, point - light)
    return -z / m.maximum(m.sqrt(x * x + y * y + z * z), 1e-30)


def falloff_at(m, rows, point, light, cos_half, blend):
    """Blender's spot factor f at a world ``point`` (its direct light there is f times the point light's)."""
    return spot_falloff(m, axis_cosine(m, rows, point, light), cos_half, blend)


# --- the fog light a spot scatters onto surfaces ---------------------------------------------------------
#
# Sun et al. 2005 Eq. 15 sums the fog light reaching a surface point p over the fog points x.  Grouping x by
# the direction u in which the light shines towards it (x = L + r u), the point light's fog light at p is
# int_{S^2} G(u) du, with G(u) the light scattered towards p along the light's ray u: the airlight integral
# of Eq. 5 with the light and the viewer swapped (e^{-beta (r + d)} w / d^2 along the ray, d = |x - p|),
# a function of T = beta D_sp and the angle alpha between u and the direction from the light to p only.  A
# spot lights only the rays u in its cone, so the total fog light it sends to p (before the surface's
# cosine) is the point light's times
#
#     F = int_cone G du / int_{S^2} G du,
#
# a function of T, the angle psi of p from the axis and the cone's half-angle theta_c.  The surface's
# cosine (or Phong lobe) inside Eq. 15 depends on the direction the fog light arrives from, which for a
# spot is not the point light's: seen from beside a beam the light comes from the beam.  The bake also
# stores the first moment of the arrival directions, E1 = int_cone int (x - p) / d ... , in the frame of the
# direction e_l from p to the light and e_a, the unit vector normal to e_l towards the axis (by symmetry E1
# lies in their plane).  The shader turns it into the mean direction mu and the mean resultant length R of
# the spot's fog light and of the point light's, and
#
#     spot = F * point(mu) * resp(n . mu, R_spot) / resp(n . mu, R_point)
#
# for the diffuse lobe: the point light's exact response (its table) evaluated at the direction the spot's
# light comes from, corrected by the ratio of the Lambertian responses of two von Mises-Fisher
# distributions of those concentrations (``lobe_response``).  The glossy lobe takes the point light's at mu
# (the correction, a diffuse one, does not carry over to narrow lobes).  The cone is taken hard at the
# middle of Blender's blend ramp.  Measured against hemisphere quadrature of the spot's airlight in
# tests/test_spot_scatter.py.

def _arc_inside(alpha, psi, theta_c):
    """(measure, first moment) of the circle at angle ``alpha`` around a direction that lies ``psi`` from the
    axis, inside the cone of half-angle ``theta_c`` about the axis (numpy): the azimuthal measure (rad, 0 to
    2 pi) and int cos(phi) dphi over it, phi from the azimuth towards the axis."""
    sa, sp = np.sin(alpha), np.sin(psi)
    with np.errstate(divide="ignore", invalid="ignore"):
        k = np.clip((np.cos(theta_c) - np.cos(alpha) * np.cos(psi)) / (sa * sp), -1.0, 1.0)
    inside = np.cos(alpha) * np.cos(psi) >= np.cos(theta_c)   # where sa sp = 0: all or nothing
    partial = sa * sp > 1e-12
    return (np.where(partial, 2.0 * np.arccos(k), np.where(inside, 2.0 * np.pi, 0.0)),
            np.where(partial, 2.0 * np.sqrt(1.0 - k * k), 0.0))


def _arc_lambert(alpha, psi):
    """(measure, first moment) as ``_arc_inside``'s, each direction weighted by Lambert's max(0, cos) to the
    axis: cos = A + B cos(phi), A = cos alpha cos psi, B = sin alpha sin psi, integrated in closed form over the
    azimuths where it is positive (|phi| < phi_m = arccos(-A / B))."""
    a = np.cos(alpha) * np.cos(psi)
    b = np.sin(alpha) * np.sin(psi)
    with np.errstate(divide="ignore", invalid="ignore"):
        phim = np.arccos(np.clip(-a / b, -1.0, 1.0))
    partial = (b > 1e-12) & (np.abs(a) < b)
    s = np.sin(phim)
    measure = np.where(partial, 2.0 * (a * phim + b * s), np.where(a > 0.0, 2.0 * np.pi * a, 0.0))
    moment = np.where(partial, 2.0 * a * s + b * (phim + s * np.cos(phim)), np.where(a > 0.0, np.pi * b, 0.0))
    return measure, moment


# alpha quadrature of the bake: Gauss-Legendre panels graded towards alpha = 0 (G narrows as T grows)
_ALPHA_EDGES = (0.0, 0.005, 0.02, 0.06, 0.15, 0.35, 0.7, 1.3, 2.2, math.pi)
_ALPHA_POINTS = 24
_XI_PANELS = 32   # per light ray, in Sun's angle xi seen from p, graded towards p (tests: F within 1e-4)
_XI_ORDER = 8
_PSI_EDGE = 1e-4  # rad: the rows psi = 0 and pi are baked this close to them (the axis moment's limit there)


def _ray_terms(t, alpha, g):
    """(G, G_l, G_a) along the light's rays at angles ``alpha`` (A,) from the direction to p, for optical
    distances ``t`` (W,), D_sp = 1: G the fog light they send to p (the airlight of Eq. 5 with light and
    viewer swapped, up to a factor per T) and its first moment's components along e_l and towards the ray.

    In Sun's angle xi of the ray point seen from p (z = h tan xi about the ray's closest point, h = sin
    alpha, d = h / cos xi) the integrand t e^{-t (r + d)} w / d^2 dr is t e^{-t (r + d)} w dxi / h, smooth
    and bounded; the scattering angle is pi/2 + xi (cos = -sin xi), so the Henyey-Greenstein weight is
    (1 - g^2) / (1 + g^2 + 2 g sin xi)^{3/2}.  Composite Gauss-Legendre on xi in [alpha - pi/2, pi/2]
    graded towards max(0, alpha - pi/2), the point nearest p."""
    x, w = np.polynomial.legendre.leggauss(_XI_ORDER)
    edges = np.linspace(-1.0, 1.0, _XI_PANELS + 1)
    edges = np.sign(edges) * edges * edges
    lo, hi = edges[:-1, None], edges[1:, None]
    s = (0.5 * (hi - lo) * x + 0.5 * (hi + lo)).ravel()
    ws = (0.5 * (hi - lo) * w).ravel()
    a = np.asarray(alpha, float)[None, :, None]
    xi0 = a - 0.5 * math.pi
    c = np.maximum(xi0, 0.0)
    before = s < 0.0
    xi = np.where(before, c + s * (c - xi0), c + s * (0.5 * math.pi - c))
    jac = np.where(before, c - xi0, 0.5 * math.pi - c) * ws
    h, r0 = np.sin(a), np.cos(a)
    d = h / np.cos(xi)
    r = r0 + h * np.tan(xi)
    tt = np.asarray(t, float)[:, None, None]
    phase = (1.0 - g * g) / (1.0 + g * g + 2.0 * g * np.sin(xi)) ** 1.5 if g else 1.0
    f = tt * np.exp(-tt * (r + d)) * phase * jac / h
    return f.sum(-1), (f * (1.0 - r * r0) / d).sum(-1), (f * r * h / d).sum(-1)


def bake_scatter_tables(g=0.0):
    """The float32 (height, width, 4) table ``tables.SPOT_MOMENTS`` for anisotropy g: F, the first
    moment along e_l and the one towards the axis divided by sin psi, both over the point light's total
    (module section above), and the point light's first moment.  The last slice is the whole sphere (the
    point light: F = 1)."""
    x, w = np.polynomial.legendre.leggauss(_ALPHA_POINTS)
    alpha, weight = [], []
    for a, b in zip(_ALPHA_EDGES[:-1], _ALPHA_EDGES[1:]):
        alpha.append(0.5 * (b - a) * x + 0.5 * (b + a))
        weight.append(0.5 * (b - a) * w)
    alpha, weight = np.concatenate(alpha), np.concatenate(weight)
    spec = tables.SPOT_MOMENTS
    t = np.maximum(tables.surface_t(np.linspace(0.0, 1.0, spec.width)), 1e-6)   # (W,)
    g_all, g_l, g_a = (v * (weight * np.sin(alpha))[None, :] for v in _ray_terms(t, alpha, g))   # (W, A)
    total = 2.0 * np.pi * g_all.sum(axis=1)[None, :]
    psi = np.clip(np.linspace(0.0, np.pi, tables.SPOT_PSI), _PSI_EDGE, np.pi - _PSI_EDGE)
    out = np.empty((spec.height, spec.width, spec.channels))
    for k in range(tables.SPOT_SLICES):
        rows = slice(k * tables.SPOT_PSI, (k + 1) * tables.SPOT_PSI)
        if k < tables.SPOT_CONES:
            arcs, moments = _arc_inside(alpha[None, :], psi[:, None], k * tables.HALF_PI / (tables.SPOT_CONES - 1))
        elif k == tables.SPOT_LAMBERT_SLICE:
            arcs, moments = _arc_lambert(alpha[None, :], psi[:, None])
        else:
            arcs, moments = np.full((tables.SPOT_PSI, alpha.size), 2.0 * np.pi), np.zeros((tables.SPOT_PSI, alpha.size))
        out[rows, :, tables.SPOT_SHARE] = (arcs @ g_all.T) / total
        out[rows, :, tables.SPOT_MOMENT_LIGHT] = (arcs @ g_l.T) / total
        out[rows, :, tables.SPOT_MOMENT_AXIS] = (moments @ g_a.T) / (total * np.sin(psi)[:, None])
    out[..., tables.SPOT_SHARE] = np.clip(out[..., tables.SPOT_SHARE], 0.0, 1.0)
    out[..., tables.SPOT_MOMENT_POINT] = out[tables.SPOT_SPHERE_SLICE * tables.SPOT_PSI, :, tables.SPOT_MOMENT_LIGHT]
    return out.astype(np.float32)


def _vmf_kappa(r):
    """The concentration kappa of the von Mises-Fisher distribution of mean resultant length r in (0, 1):
    coth kappa - 1/kappa = r, by bisection in log kappa (numpy)."""
    lo, hi = np.full(np.shape(r), -12.0), np.full(np.shape(r), 16.0)
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        k = np.exp(mid)
        mean = np.where(k < 1e-3, k / 3.0, 1.0 / np.tanh(np.minimum(k, 700.0)) - 1.0 / k)
        low = mean < r
        lo, hi = np.where(low, mid, lo), np.where(low, hi, mid)
    return np.exp(0.5 * (lo + hi))


def bake_lobe_response(spec=tables.LOBE_RESPONSE):
    """resp(c, R) = int f(w) max(0, n . w) dw / pi, f the von Mises-Fisher density of mean resultant length
    R about mu, c = n . mu (layout of tables.LOBE_RESPONSE; float32): 1 / (4 pi) for R = 0, max(0, c) / pi
    for R = 1.  In t = mu . w the azimuthal integral of the clamped cosine is closed form (2 pi c t, 0, or
    2 (A phi_m + B sin phi_m) where the ring crosses the horizon); t by Gauss-Legendre panels graded
    towards t = 1, where the density e^{kappa (t - 1)} concentrates."""
    c = np.linspace(-1.0, 1.0, spec.width)[None, :, None]
    r = np.linspace(0.0, 1.0, spec.height)
    x, w = np.polynomial.legendre.leggauss(16)
    edges = np.concatenate([[0.0], 2.0 * 1e-7 ** np.linspace(1.0, 0.0, 48)])   # u = 1 - t in [0, 2]
    lo, hi = edges[:-1, None], edges[1:, None]
    u = (0.5 * (hi - lo) * x + 0.5 * (hi + lo)).ravel()
    wu = (0.5 * (hi - lo) * w).ravel()
    tt = 1.0 - u
    a = c * tt
    b = np.sqrt(np.maximum(1.0 - c * c, 0.0)) * np.sqrt(np.maximum(1.0 - tt * tt, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        phim = np.arccos(np.clip(-a / b, -1.0, 1.0))
    ring = np.where(a >= b, 2.0 * np.pi * a, np.where(a <= -b, 0.0, 2.0 * (a * phim + b * np.sin(phim))))
    kappa = _vmf_kappa(np.clip(r, 1e-9, 1.0 - 1e-9))[:, None, None]
    density = kappa / (2.0 * np.pi * -np.expm1(-2.0 * kappa)) * np.exp(-kappa * u)   # per steradian, (R, 1, U)
    out = np.sum(density * ring * wu, axis=-1) / np.pi
    out[0] = 0.25 / np.pi
    out[-1] = np.maximum(c[0, :, 0], 0.0) / np.pi
    return out.astype(np.float32)


def _lookup(m, spec, x, y0, step, frac, channel):
    """Bilinear in (X, psi) of ``spec``'s ``channel`` at two slices ``step`` apart in Y, linear between them by
    ``frac`` (the four channels of a texel come with one lookup)."""
    f0 = m.table(spec, x, y0, channel=channel)
    return f0 + frac * (m.table(spec, x, y0 + step, channel=channel) - f0)


def world_axis(m, rows):
    """Unit world direction of the cone's axis (the light's local -Z) from the rows of its inverse matrix:
    -(row_x x row_y), normalised (the matrix's third column, up to a positive factor)."""
    axis = m.cross(rows[1], rows[0])
    return m.scale(axis, 1.0 / m.maximum(m.length(axis), 1e-30))


def lobe_response(m, c, r):
    """resp(c, R) of ``bake_lobe_response`` from its table."""
    return m.table(tables.LOBE_RESPONSE, m.mul_add(c, 0.5, 0.5), r)


def _moments(m, beta, d_sp, c_axis, cos_half, blend, g):
    """(F, E1 . e_l, E1 . e_a / sin psi, the point light's R) from the tables of g (module section above):
    the cone's share and first moment over the point light's total, once per light and surface point."""
    spec, slice_rows = tables.anisotropic(tables.SPOT_MOMENTS, g), tables.SPOT_PSI
    cos_mid = cos_half + (1.0 - cos_half) * (0.5 * blend)   # the cone taken hard mid-ramp
    psi = m.atan2(m.sqrt(1.0 - c_axis * c_axis), c_axis)
    theta = m.atan2(m.sqrt(1.0 - cos_mid * cos_mid), cos_mid)
    s = m.clamp01(theta * (1.0 / tables.HALF_PI)) * (tables.SPOT_CONES - 1.0)
    k0 = m.minimum(m.floor(s), tables.SPOT_CONES - 2.0)
    step = slice_rows / (spec.height - 1.0)
    y0 = m.mul_add(k0, step, psi * ((slice_rows - 1.0) / (math.pi * (spec.height - 1.0))))
    x = tables.surface_x(m, beta * d_sp)
    frac = s - k0
    return (*(_lookup(m, spec, x, y0, step, frac, k)
              for k in (tables.SPOT_SHARE, tables.SPOT_MOMENT_LIGHT, tables.SPOT_MOMENT_AXIS)),
            m.table(spec, x, y0, channel=tables.SPOT_MOMENT_POINT))


def lambert_moments(m, beta, d_sp, c_axis, g):
    """``_moments`` of a Lambertian emitter about the axis (the tables' last slice, ``_arc_lambert``): the
    share of the point light's fog light its cosine lights, its first moment, and the point light's R."""
    spec, slice_rows = tables.anisotropic(tables.SPOT_MOMENTS, g), tables.SPOT_PSI
    psi = m.atan2(m.sqrt(1.0 - c_axis * c_axis), c_axis)
    y0 = m.mul_add(psi, (slice_rows - 1.0) / (math.pi * (spec.height - 1.0)),
                   tables.SPOT_LAMBERT_SLICE * slice_rows / (spec.height - 1.0))
    x = tables.surface_x(m, beta * d_sp)
    return tuple(m.table(spec, x, y0, channel=k) for k in (tables.SPOT_SHARE, tables.SPOT_MOMENT_LIGHT,
                                                            tables.SPOT_MOMENT_AXIS, tables.SPOT_MOMENT_POINT))


def lambert_scatter(m, beta, d_sp, cos_n, cos_r, level, c_axis, cos_n_axis, cos_r_axis, *, point, g=0.0):
    """(diffuse, glossy) of ``scatter`` for a Lambertian emitter about the axis (an area light far from the
    point: ``area.scatter``), per unit normal intensity: the same mean-direction model with the moments of
    ``lambert_moments``."""
    moments = lambert_moments(m, beta, d_sp, c_axis, float(g))
    return (_lobe(m, beta, d_sp, cos_n, 0.0, cos_n_axis, c_axis, moments, point, diffuse=True),
            _lobe(m, beta, d_sp, cos_r, level, cos_r_axis, c_axis, moments, point, diffuse=False))


def _lobe(m, beta, d_sp, cos_theta, level, cos_lobe_axis, c_axis, moments, point, diffuse):
    """One lobe of ``scatter``: the point light's at the mean direction, times F (and, ``diffuse``, the
    concentration's correction), at most the point light's."""
    share, e_l, e_a, r_point = moments
    sin_psi = m.sqrt(1.0 - c_axis * c_axis)
    # E1 . lobe = e_l cos_theta + e_a sin_psi (lobe . e_a), lobe . e_a = (lobe . axis + c_axis cos_theta) / sin_psi
    along = m.mul_add(e_l, cos_theta, e_a * m.mul_add(c_axis, cos_theta, cos_lobe_axis))
    size = m.maximum(m.sqrt(m.mul_add(e_l, e_l, (e_a * sin_psi) * (e_a * sin_psi))), 1e-30)
    cos_mu = m.minimum(m.maximum(along / size, -1.0), 1.0)
    spot = point(m, beta, d_sp, cos_mu, level) * share
    if diffuse:
        r_spot = m.minimum(size / m.maximum(share, 1e-30), 1.0)
        spot = spot * lobe_response(m, cos_mu, r_spot) / m.maximum(lobe_response(m, cos_mu, r_point), 1e-6)
    # the spot lights a part of the point light's fog: never more than the point light's fog light
    return m.minimum(spot, point(m, beta, d_sp, cos_theta, level))


def scatter(m, beta, d_sp, cos_n, cos_r, level, c_axis, cos_half, blend, cos_n_axis, cos_r_axis, *, point, g=0.0):
    """(diffuse, glossy): the fog light a spot scatters onto a surface per unit albedo (1/m^2) through its
    Lambertian lobe and its Phong lobe of table level ``level``: the point light's (``point``, a scatter
    rung's kernel: Sun et al. 2005 Eq. 17-18) at the mean direction of the spot's fog light, times the
    cone's share F, and for the diffuse lobe the correction for its concentration (module section above).
    The tables are read once for both lobes.

    cos_n, cos_r: the normal and the mirrored view vector against the direction to the light; c_axis: the
    point's ``axis_cosine``; cos_n_axis, cos_r_axis: the normal and the mirrored view vector against the
    cone's ``world_axis``."""
    moments = _moments(m, beta, d_sp, c_axis, cos_half, blend, float(g))
    return (_lobe(m, beta, d_sp, cos_n, 0.0, cos_n_axis, c_axis, moments, point, diffuse=True),
            _lobe(m, beta, d_sp, cos_r, level, cos_r_axis, c_axis, moments, point, diffuse=False))


def cone_interval(m, p0, d, kappa, t_end):
    """[lo, hi] (lo >= hi: empty) of t in [0, t_end] where the light-space point p0 + t d (tuples of
    x, y, z) is inside the cone c >= kappa about -Z, kappa in [0, 1) (half-angle <= 90 degrees).

    c >= kappa is -p_z >= kappa |p|: the quadratic Q(t) = (1 - k^2) p_z^2 - k^2 (p_x^2 + p_y^2) >= 0 on
    the nappe -p_z >= 0.  The nappe is convex, so the set is one interval: between the roots of Q when
    Q opens downwards (A < 0), beyond the root on the ray's far side when it opens upwards (A > 0) and
    the ray heads into the nappe (-d_z > 0), before the near root when it heads out of it.
    """
    k2 = kappa * kappa
    px, py, pz = p0
    dx, dy, dz = d
    a = (1.0 - k2) * dz * dz - k2 * (dx * dx + dy * dy)
    b = (1.0 - k2) * pz * dz - k2 * (px * dx + py * dy)
    c = (1.0 - k2) * pz * pz - k2 * (px * px + py * py)
    disc = b * b - a * c
    root = m.sqrt(disc)
    # the two roots without cancellation: q = -(b + sign(b) sqrt(disc)), roots q / a and c / q
    q = -(b + m.select(m.less(b, 0.0), -root, root))
    safe_q = m.select(m.less(m.abs(q), 1e-300), 1e-300, q)
    safe_a = m.select(m.less(m.abs(a), 1e-300), 1e-300, a)
    r1, r2 = q / safe_a, c / safe_q
    r_min, r_max = m.minimum(r1, r2), m.maximum(r1, r2)
    no_root = m.less(disc, 0.0)
    big = model.FAR * 4.0
    # a < 0: [r_min, r_max] if it lies on the nappe (-p_z >= 0 at its middle) and the roots exist
    mid = 0.5 * (r_min + r_max)
    on_nappe = 1.0 - m.less(-(pz + mid * dz), 0.0)
    closed_ok = (1.0 - no_root) * on_nappe
    lo_closed = m.select(closed_ok, r_min, big)
    hi_closed = m.select(closed_ok, r_max, -big)
    # a >= 0: heading into the nappe (-d_z > 0) [r_max, inf), else (-inf, r_min]; with no root the line
    # never meets the cone's surface: all of it is inside (if its start is on the nappe) or none
    into = m.less(dz, 0.0)
    whole = 1.0 - m.less(-pz, 0.0)
    lo_open = m.select(no_root, m.select(whole, -big, big), m.select(into, r_max, -big))
    hi_open = m.select(no_root, m.select(whole, big, -big), m.select(into, big, r_min))
    opens_up = 1.0 - m.less(a, 0.0)
    lo = m.maximum(m.select(opens_up, lo_open, lo_closed), 0.0)
    hi = m.minimum(m.select(opens_up, hi_open, hi_closed), t_end)
    return lo, m.maximum(hi, lo)


def _cone(m, px, py, pz, dx, dy, dz, kappa, t_end):
    return cone_interval(m, (px, py, pz), (dx, dy, dz), kappa, t_end)


def cone_hit(m, px, py, pz, dx, dy, dz, cos_half, t_end):
    """1 if the ray (in the light's space, ``light_space_ray``) meets the spot's cone before ``t_end``, else 0:
    outside it the spot's glow is 0 (the shader builders skip computing it there, ``shading.Gated``)."""
    lo, hi = m.group("Spot Cone Interval", _cone, px, py, pz, dx, dy, dz, cos_half, t_end)
    return m.less(lo, hi)


def _kernel_name(fn):
    """A name for the kernel ``fn`` (a function or a functools.partial of one), its bound values included."""
    base = getattr(fn, "func", fn)
    bound = ", ".join(f"{k} {_kernel_name(v) if callable(v) else v if isinstance(v, int) else f'{v:+.3f}'}"
                      for k, v in sorted(getattr(fn, "keywords", {}).items()))
    return base.__name__ + (f" ({bound})" if bound else "")


def _inner(m, beta, along, h, t0, t1, *, inner):
    """The point light's airlight (1/m^2) over the ray's piece [t0, t1] (empty if t0 >= t1; t1 may be
    FAR): ``inner`` (a point-light airlight kernel) with the viewer moved to t0, times e^{-beta t0}."""
    a0 = along - t0
    d0 = m.maximum(m.sqrt(a0 * a0 + h * h), model.MIN_DISTANCE)
    seg = m.maximum(m.minimum(t1 - t0, INNER_DEPTH / m.maximum(beta, 1e-30)), 0.0)   # beta = 0: no fog
    return m.select(m.less(t0, t1), m.exp(-beta * t0) * inner(m, beta, d0, a0, h, seg), 0.0)


def ray_quadrature(m, beta, d_sv, along, h, t0, t1, profile, g=0.0, nodes=RIM_NODES):
    """int f(t) times the point light's airlight integrand over the camera ray's piece [t0, t1] (1/m^2, per unit
    intensity), ``profile(t)`` = f the light's relative intensity towards the ray's point t (an ops value), by
    Gauss-Legendre quadrature in u = tan(xi / 2), xi = atan(Q / h) Sun's angle (Eq. 9: in xi the integrand
    beta/(2 pi h) e^{-beta (D_sv + Q - Q_0)} w is smooth and bounded however close the ray passes the light;
    dxi = 2 du / (1 + u^2), and Q = 2 h u / (1 - u^2) needs no tangent), up to optical depth RIM_DEPTH.  In xi
    the Henyey-Greenstein weight is (1 - g^2) / (1 + g^2 - 2 g cos 2 xi)^{3/2} (scattering angle 2 xi, Pegoraro
    et al. Eq. 8-9; ``model.hg_weight`` in Q), cos xi = (1 - u^2) / (1 + u^2).  A spot's blend rim
    (``_rim``) and an area light's whole glow (``area.py``) are this with their own f."""
    h = m.maximum(h, model.MIN_ANGLE * d_sv)
    q0 = model.closest_point_q(m, d_sv, -along, h)

    def q_at(t):   # Q = z + d at the ray's point t, without cancellation (model.closest_point_q)
        z = t - along
        return model.closest_point_q(m, m.sqrt(z * z + h * h), z, h)

    h2 = h * h

    def u_at(q):   # tan(xi / 2) = Q / (h + sqrt(h^2 + Q^2)), in [0, 1)
        return q / (h + m.sqrt(m.mul_add(q, q, h2)))

    qa = q_at(t0)
    qb = m.minimum(q_at(t1), qa + RIM_DEPTH / m.maximum(beta, 1e-30))
    ua, ub = u_at(qa), u_at(qb)
    half, centre = 0.5 * (ub - ua), 0.5 * (ub + ua)
    two_h, beta_q0 = 2.0 * h, beta * q0
    total = 0.0
    for x, w in _gauss_legendre(nodes):
        u = m.mul_add(half, x, centre)
        cos_part = m.mul_add(u, -u, 1.0)   # 1 - u^2 (0 where a float32 u rounds to 1: Q clamps to qb)
        q = m.minimum(m.maximum(two_h * u / cos_part, qa), qb)
        t = m.mul_add(q - h2 / q, 0.5, along)   # the ray's t there: z = (Q^2 - h^2) / 2Q
        f = profile(t)
        jacobian = 1.0 / (2.0 - cos_part)   # dxi / du / 2 = 1 / (1 + u^2)
        if g:
            cos_xi = cos_part * jacobian
            f = f * m.power(m.mul_add(cos_xi * cos_xi, -4.0 * g, (1.0 + g) * (1.0 + g)), -1.5)
        total = m.mul_add(f * m.exp(m.mul_add(q, -beta, beta_q0)) * jacobian, w, total)
    value = (beta * (2.0 * model.INV_2PI) * (1.0 - g * g)) * m.exp(-beta * d_sv) / h * half * total
    return m.select(m.less(t0, t1), value, 0.0)


def _rim(m, beta, d_sv, along, h, neg_pz, neg_dz, a, t_l, h_l2, t0, t1, cos_half, cos_end, g=0.0,
         rim_nodes=RIM_NODES):
    """f(c) times the point light's airlight over [t0, t1] (1/m^2): ``ray_quadrature`` with Blender's spot
    factor (``ramp``) as f.  (neg_pz, ..., h_l2): ``_ray_quadratic``."""
    def profile(t):
        s = t - t_l
        dist = m.maximum(m.sqrt(m.mul_add(a, s * s, h_l2)), 1e-30)   # |p + t d|; 0 where a ray meets the apex
        return ramp(m, m.mul_add(t, neg_dz, neg_pz) / dist, cos_half, cos_end)

    return ray_quadrature(m, beta, d_sv, along, h, t0, t1, profile, g, rim_nodes)


def _ray_quadratic(m, px, py, pz, dx, dy, dz):
    """(-p_z, -d_z, a, t_l, h_l2) of the ray p + t d in the light's space for ``_rim``: |p + t d|^2 = a (t -
    t_l)^2 + h_l2 with a = |d|^2, t_l = -p.d / a and h_l2 = |p x d|^2 / a (no cancellation near the apex)."""
    p, d = m.combine(px, py, pz), m.combine(dx, dy, dz)
    a = m.maximum(m.dot(d, d), 1e-30)
    cross = m.cross(p, d)
    return -pz, -dz, a, -m.dot(p, d) / a, m.dot(cross, cross) / a


def airlight(m, beta, d_sv, along, h, d_vp, px, py, pz, dx, dy, dz, cos_half, blend, *,
             inner=model.airlight_segment, g=0.0, rim_nodes=RIM_NODES):
    """Airlight of a spot light per unit intensity, 1/m^2, along a camera ray (module docstring).

    (d_sv, along, h): the ray's geometry about the light (``model.ray_light_geometry``); d_vp: the
    distance to the surface, m (model.FAR for the sky); (px, py, pz, dx, dy, dz): the ray in the light's
    space (``light_space_ray``); cos_half = cos(spot size / 2) >= 0; blend in [0, 1].  ``inner``: the
    point-light airlight kernel of the inner cone (a table or quadrature rung, its g bound); g:
    Henyey-Greenstein anisotropy of the rim's integrand (Python float).  Shader nodes share it, and its
    parts, as node groups (``m.group``).
    """
    fn = functools.partial(_airlight, inner=inner, g=float(g), **_rim_keyword(rim_nodes))
    return m.group(f"Spot Airlight [{_kernel_name(fn)}]", fn, beta, d_sv, along, h, d_vp, px, py, pz, dx, dy, dz,
                   cos_half, blend)


class _Clip(NamedTuple):
    """A ray's pieces in a spot's cone (``_clip``): ``lo_in``-``hi_in`` in the inner cone, the rims
    ``lo_out``-``first_end`` and (unless ``empty_in``) ``hi_in``-``hi_out``."""
    lo_out: Any
    hi_out: Any
    lo_in: Any
    hi_in: Any
    empty_in: Any      # 1 if the ray misses the inner cone: then its one rim is the whole outer interval
    first_end: Any
    cos_end: Any       # ``ramp_end``


def _clip(m, ray, cos_half, blend, t_end):
    """The pieces of the ray (light space) up to ``t_end`` in the spot's outer and inner cones."""
    cos_in = cos_half + (1.0 - cos_half) * blend
    lo_out, hi_out = m.group("Spot Cone Interval", _cone, *ray, cos_half, t_end)
    lo_in, hi_in = m.group("Spot Cone Interval", _cone, *ray, m.minimum(cos_in, 1.0 - 1e-7), t_end)
    empty_in = 1.0 - m.less(lo_in, hi_in)
    return _Clip(lo_out, hi_out, lo_in, hi_in, empty_in, m.select(empty_in, hi_out, lo_in),
                 ramp_end(m, cos_half, blend))


def _rim_keyword(rim_nodes):
    """The rim's point count as a kernel's keyword, none for RIM_NODES (the groups' names stay as they were)."""
    return {} if int(rim_nodes) == RIM_NODES else {"rim_nodes": int(rim_nodes)}


def _parts(inner, g, rim_nodes):
    """(the inner piece's kernel group, the rim's kernel group) as ``m.group`` names and functions."""
    rim = functools.partial(_rim, g=float(g), **_rim_keyword(rim_nodes))
    return ((f"Spot Inner [{_kernel_name(inner)}]", functools.partial(_inner, inner=inner)),
            (f"Spot Rim [{_kernel_name(rim)}]", rim))


def _airlight(m, beta, d_sv, along, h, d_vp, px, py, pz, dx, dy, dz, cos_half, blend, *, inner, g,
              rim_nodes=RIM_NODES):
    ray = (px, py, pz, dx, dy, dz)
    c = _clip(m, ray, cos_half, blend, d_vp)
    (inner_name, inner_fn), (rim_name, rim) = _parts(inner, g, rim_nodes)
    value = m.group(inner_name, inner_fn, beta, along, h, c.lo_in, c.hi_in)
    # the rim: [lo_out, lo_in] and [hi_in, hi_out], or the whole outer interval when the inner is empty
    rim_args = (beta, d_sv, along, h, *_ray_quadratic(m, *ray))
    value = value + m.group(rim_name, rim, *rim_args, c.lo_out, c.first_end, cos_half, c.cos_end)
    return value + (1.0 - c.empty_in) * m.group(rim_name, rim, *rim_args, c.hi_in, c.hi_out, cos_half, c.cos_end)


def airlight_pair(m, beta, d_sv, along, h, d_vp, px, py, pz, dx, dy, dz, cos_half, blend, *,
                  inner=model.airlight_segment, g=0.0, rim_nodes=RIM_NODES):
    """(:func:`airlight` to the surface at ``d_vp``, :func:`airlight_background`) of one ray, 1/m^2, for a
    backend that needs both per pixel (the compositor: a pixel partly covered mixes the two).  The same
    formulas, sharing what they have in common: the cone intervals (the ray's to infinity, clipped at
    d_vp) and every rim d_vp does not cut, so three rims are integrated instead of four."""
    fn = functools.partial(_airlight_pair, inner=inner, g=float(g), **_rim_keyword(rim_nodes))
    return m.group(f"Spot Airlight Pair [{_kernel_name(fn)}]", fn, beta, d_sv, along, h, d_vp, px, py, pz, dx, dy,
                   dz, cos_half, blend)


def _airlight_pair(m, beta, d_sv, along, h, d_vp, px, py, pz, dx, dy, dz, cos_half, blend, *, inner, g,
                   rim_nodes=RIM_NODES):
    ray = (px, py, pz, dx, dy, dz)
    c = _clip(m, ray, cos_half, blend, model.FAR)
    # the pieces inline, not as kernel groups: operations on the same inputs are then built once (the two
    # inner pieces' common start, what the rims share), which node groups would hide from each other
    (_, inner_fn), (_, rim) = _parts(inner, g, rim_nodes)
    rim_args = (beta, d_sv, along, h, *_ray_quadratic(m, *ray))
    first = rim(m, *rim_args, c.lo_out, c.first_end, cos_half, c.cos_end)
    second = (1.0 - c.empty_in) * rim(m, *rim_args, c.hi_in, c.hi_out, cos_half, c.cos_end)
    background = inner_fn(m, beta, along, h, c.lo_in, c.hi_in) + first + second
    # to the surface: d_vp cuts at most one rim, the first (before first_end) or else the second, whose
    # piece [hi_in, d_vp] is empty unless d_vp lies in it
    before_first_end = m.less(d_vp, c.first_end)
    cut = rim(m, *rim_args, m.select(before_first_end, c.lo_out, c.hi_in), d_vp, cos_half, c.cos_end)
    second_cut = (1.0 - c.empty_in) * m.select(m.less(d_vp, c.hi_out), cut, second)
    rims = m.select(before_first_end, cut, first + second_cut)
    surface = inner_fn(m, beta, along, h, c.lo_in, m.maximum(m.minimum(c.hi_in, d_vp), c.lo_in))
    return surface + rims, background


def airlight_background(m, beta, d_sv, along, h, px, py, pz, dx, dy, dz, cos_half, blend, *,
                        inner=model.airlight_segment, g=0.0, rim_nodes=RIM_NODES):
    """:func:`airlight` of a ray that meets no surface (Sun et al. 2005 Eq. 12), 1/m^2."""
    return airlight(m, beta, d_sv, along, h, model.FAR, px, py, pz, dx, dy, dz, cos_half, blend,
                    inner=inner, g=g, rim_nodes=rim_nodes)


def airlight_spot(m, beta, origin, direction, light, rows, cos_half, blend, d_vp, g=0.0, rim_nodes=RIM_NODES):
    """:func:`airlight` from world vectors (origin, unit direction, light position: m; rows: the light's
    inverse 3x3 matrix as three row vectors), with the table's point-light segment for anisotropy g."""
    d_sv, along, h = model.ray_light_geometry(m, origin, direction, light)
    return airlight(m, beta, d_sv, along, h, d_vp, *light_space_ray(m, rows, origin, direction, light),
                    cos_half, blend, inner=functools.partial(model.airlight_segment, g=g), g=g, rim_nodes=rim_nodes)
