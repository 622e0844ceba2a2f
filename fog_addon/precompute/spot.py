"""Spot lights in fog: Blender's cone and blend, the ray clipped to the cone, the rim integrated (issue 9).

Not yet wired into the node groups or OSL: the numpy physics and its measured accuracy.

Blender's spot (Cycles and EEVEE, measured per pixel: ../shared/notes/blender-facts.md section 1):
the intensity towards a point is the point light's times

    f = smoothstep((c - c_h) / ((1 - c_h) b)),   c_h = cos(size / 2),  b = blend,

c the cosine between the light-to-point direction in the light's own space (non-uniform scale
deforms the cone) and its local -Z axis; a hard cut (f = 1 inside) when b = 0; no other cos factor.

Along a camera ray the airlight (Sun et al. 2005 Eq. 5, per unit intensity) becomes
int f(c(x)) w(x) beta e^{-beta (d + x)} / (4 pi d^2) dx.  The cone of half-angle <= 90 degrees is
convex, so a ray meets the set where c >= k in one interval (``cone_interval``):

* inside the inner cone (c >= c_in = c_h + (1 - c_h) b) f = 1 and the point light's integral applies
  unchanged on that sub-segment (Pegoraro et al.: the segment's bounds are free; here the viewer moved
  to the segment's start, ``model.airlight_segment``, times the extinction to it);
* on the blend rim (c_h < c < c_in, at most two intervals) f varies smoothly and the integral is taken
  by Gauss-Legendre quadrature (``RIM_NODES`` points per interval).
"""
import numpy as np

from . import model

RIM_NODES = 12    # Gauss-Legendre points per rim interval (tests/test_spot.py measures the error)
_GL = tuple((float(x), float(w)) for x, w in zip(*np.polynomial.legendre.leggauss(RIM_NODES)))


def spot_falloff(m, c, cos_half, blend):
    """Blender's spot factor f in [0, 1] for the cosine c to the axis (module docstring).

    ``cos_half`` = cos(size / 2), ``blend`` in [0, 1]; blend = 0 is a hard cut at c = cos_half.
    """
    width = (1.0 - cos_half) * blend
    x = m.clamp01((c - cos_half) / m.maximum(width, 1e-30))
    soft = x * x * (3.0 - 2.0 * x)
    hard = 1.0 - m.less(c, cos_half)
    return m.select(m.less(width, 1e-12), hard, soft)


def _local(m, rows, v):
    """The light-space vector of ``v``: rows = the three rows of the light's inverse 3x3 matrix."""
    return m.dot(rows[0], v), m.dot(rows[1], v), m.dot(rows[2], v)


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


def _segment(m, beta, origin, direction, light, t0, t1, g):
    """Airlight per unit intensity (1/m^2) of the ray's piece [t0, t1] (t0 < t1; t1 may be FAR):
    the viewer moved to t0, times e^{-beta t0}."""
    start = origin + m.scale(direction, t0)
    d_sv, along, h = model.ray_light_geometry(m, start, direction, light)
    seg = model.airlight_segment(m, beta, d_sv, along, h, t1 - t0, g)
    return m.select(m.less(t0, t1), m.exp(-beta * t0) * seg, 0.0)


RIM_DEPTH = 12.0   # the rim's quadrature stops this optical depth past its start (e^-12 = 6e-6)


def _rim(m, beta, origin, direction, light, rows, t0, t1, cos_half, blend, g):
    """f(c) times the point light's airlight over [t0, t1] (1/m^2), by Gauss-Legendre quadrature in
    Sun's angle xi = atan(Q / h) (Eq. 9: the integrand beta/(2 pi h) e^{-beta (D_sv + Q - Q_0)} w is
    smooth and bounded there however close the ray passes the light), up to optical depth RIM_DEPTH."""
    d_sv, along, h = model.ray_light_geometry(m, origin, direction, light)
    h = m.maximum(h, model.MIN_ANGLE * d_sv)
    q0 = model.closest_point_q(m, d_sv, -along, h)

    def q_at(t):   # Q = z + d at the ray's point t, without cancellation (model.closest_point_q)
        z = t - along
        return model.closest_point_q(m, m.sqrt(z * z + h * h), z, h)

    qa = q_at(t0)
    qb = m.minimum(q_at(t1), qa + RIM_DEPTH / beta)
    xa, xb = m.atan2(qa, h), m.atan2(qb, h)
    half, centre = 0.5 * (xb - xa), 0.5 * (xb + xa)
    total = 0.0
    for x, w in _GL:
        xi = centre + half * x
        q = h * m.sin(xi) / m.maximum(m.cos(xi), 1e-30)
        t = along + (q * q - h * h) / m.maximum(2.0 * q, 1e-300)   # z = (Q^2 - h^2) / 2Q
        lx, ly, lz = _local(m, rows, origin + m.scale(direction, t) - light)
        c = -lz / m.maximum(m.sqrt(lx * lx + ly * ly + lz * lz), 1e-300)
        total = total + w * spot_falloff(m, c, cos_half, blend) * model.hg_weight(m, g, q, h) * m.exp(
            -beta * (q - q0))
    value = (beta * model.INV_2PI) * m.exp(-beta * d_sv) / h * half * total
    return m.select(m.less(t0, t1), value, 0.0)


def airlight_spot(m, beta, origin, direction, light, rows, cos_half, blend, d_vp, g=0.0):
    """Airlight of a spot light per unit intensity, 1/m^2, along a camera ray (module docstring).

    origin, direction (unit), light: world vectors (m); rows: the light's inverse 3x3 matrix as three
    row vectors (its axis is local -Z); cos_half = cos(spot size / 2) >= 0; blend in [0, 1]; d_vp: the
    distance to the surface (model.FAR for the sky); g: Henyey-Greenstein anisotropy (Python float).
    """
    p0 = _local(m, rows, origin - light)
    d = _local(m, rows, direction)
    cos_in = cos_half + (1.0 - cos_half) * blend
    lo_out, hi_out = cone_interval(m, p0, d, cos_half, d_vp)
    lo_in, hi_in = cone_interval(m, p0, d, m.minimum(cos_in, 1.0 - 1e-7), d_vp)
    empty_in = 1.0 - m.less(lo_in, hi_in)
    inner = _segment(m, beta, origin, direction, light, lo_in, hi_in, g)
    # the rim: [lo_out, lo_in] and [hi_in, hi_out], or the whole outer interval when the inner is empty
    first_end = m.select(empty_in, hi_out, lo_in)
    rim = (_rim(m, beta, origin, direction, light, rows, lo_out, first_end, cos_half, blend, g)
           + (1.0 - empty_in) * _rim(m, beta, origin, direction, light, rows, hi_in, hi_out, cos_half, blend, g))
    return inner + rim
