"""Per-pixel fog formulas, written once for numpy, shader nodes and OSL.

Every function takes an ops namespace ``m`` first (see ``ops.py``).  Inputs are
physical: distances in m, the extinction (= scattering) coefficient ``beta``
in 1/m.  Radiances are returned per unit radiant intensity of the light, i.e.
multiply by I0 = P / (4 pi) W/sr (times the light colour) to get W/(m^2 sr).

The airlight of Sun et al. 2005 (Eq. 5, solved as Eq. 9-12 with F(u, v) of
Eq. 10) is evaluated here in the variable q = z + d, where z is the signed
distance along the ray from the point closest to the light and d the distance
to the light.  With Q = q in metres and h the distance from the light to the
ray's line, the substitution q = h tan(xi) of Sun's Appendix A turns Eq. 5 into

    L_a = beta I0 / (2 pi) * exp(-beta D_sv) * int_{Q0}^{Q1} exp(-beta (Q - Q0)) / (Q^2 + h^2) dQ

so Sun's difference F(A1, v1) - F(A1, v0) (Eq. 11) becomes a difference of
the tails K(Q0) - exp(-beta (Q1 - Q0)) K(Q1) with

    K(Q) = int_Q^inf exp(-beta (Q' - Q)) / (Q'^2 + h^2) dQ'.

The factor exp(-T_sv) is exact (Sun's e^{-T_sv cos(gamma)} e^{-A1 tan(gamma/2)}),
so nothing exponentially small is ever tabulated or subtracted.  K depends on
the polar coordinates (R, xi) of (h, Q): R^2 = Q^2 + h^2 = 2 Q d and
xi = atan2(Q, h) (xi = gamma/2 at the viewer, Sun's upper limit at the surface).
Divided by its two limits (no extinction: xi' / (R cos xi), far field 1/R^2),
K is a table N(beta R, xi) in [0.80, 1.07] that bilinear interpolation
reproduces to 2e-4 (see airlight.py).  Where the segment is short compared with
the scale of its integrand, the difference would cancel, so the integral is
taken directly by Gauss-Legendre quadrature instead.
"""
import math

from ...core import tables

# Gauss-Legendre nodes on [0, 1] for short ray segments.
_GL_X = (0.033765242898423975, 0.16939530676686776, 0.38069040695840156,
         0.6193095930415985, 0.8306046932331322, 0.966234757101576)
_GL_W = (0.08566224618958517, 0.18038078652406933, 0.23395696728634552,
         0.23395696728634552, 0.18038078652406933, 0.08566224618958517)

SHORT_SEGMENT = 0.5   # a segment is short when beta*P < SHORT_SEGMENT * min(1, beta*R0)
MIN_ANGLE = 1e-7     # rad; rays closer than this to a light are taken at this angle (gamma -> 0 and pi limits)
MIN_DISTANCE = 1e-6   # m; distances to the light are clamped here (the glow of a point light is infinite on it)
INV_4PI = 1.0 / (4.0 * math.pi)
# In-shader quadrature of the airlight (airlight_quadrature, the OSL method):
QUAD_PANELS = 72      # panels at most (enough down to beta h = 1e-16 at |g| <= 0.95, see airlight_quadrature)
QUAD_GROWTH = 1.0     # a panel is at most this times sqrt(Q^2 + h^2) long (its distance to the poles Q = +-ih)
QUAD_DEPTH = 4.0      # ... and at most this optical depth thick
QUAD_END = 30.0       # the integral stops at optical depth 30 from Q0 (e^-30 = 1e-13)
FAR = 1e15            # m; the length of a ray that meets no surface (its square still fits a float32)
EQUIANGULAR_POINTS = 2   # points of ``airlight_equiangular`` a sample, one in each stratum of angle
EQUIANGULAR_DEPTH = 8.0  # its segment's end: optical depths past the light's closest point (or the camera)
INV_2PI = 1.0 / (2.0 * math.pi)


def xi_over_cos(m, xi):
    """(pi/2 - xi) / cos(xi) for xi in [0, pi/2], with its limit 1 at pi/2."""
    c = tables.HALF_PI - xi
    return (c + 1e-7) / (m.sin(c) + 1e-7)


def hg_weight(m, g, q, h):
    """4 pi p_HG(cos theta): the Henyey-Greenstein phase function's weight on the airlight integrand at
    the ray point Q = q (dimensionless; 1 for g = 0, Sun's isotropic 1/(4 pi)).

    With v = Q/h the scattering angle there has cos theta = (1 - v^2) / (1 + v^2) (Pegoraro et al.,
    Eq. 8 with Eq. 9: theta = 2 xi, forward scattering towards the viewer at Q -> 0), so
    4 pi p = (1 - g^2) ((Q^2 + h^2) / ((1 - g)^2 h^2 + (1 + g)^2 Q^2))^{3/2}, finite for |g| < 1.
    """
    if not g:
        return 1.0
    a, b = (1.0 - g) * h, (1.0 + g) * q
    ratio = (q * q + h * h) / m.maximum(a * a + b * b, 1e-300)
    return (1.0 - g * g) * ratio * m.sqrt(ratio)


def phase_scale(m, g, q, h):
    """Distance (m) from Q = q to the nearest singularity of the airlight integrand in the complex
    plane: sqrt(q^2 + h^2), or with a forward phase peak (g > 0) sqrt(q^2 + (h / s)^2)
    (``tables.hg_stretch``): the length over which the integrand changes."""
    h_eff = h * (1.0 / tables.hg_stretch(g)) if g > 0.0 else h
    return m.sqrt(q * q + h_eff * h_eff)


def airlight_tail(m, beta, q, h, d, g=0.0):
    """K(Q) in 1/m at Q = q on a ray at distance h from the light, the point d from the light (module
    docstring): the table of anisotropy g (``airlight.normalised_tail``) divided by its limits."""
    r = m.maximum(m.sqrt(2.0 * q * d), MIN_DISTANCE)   # = sqrt(q^2 + h^2), without squaring q
    xi = m.atan2(q, h)
    n = m.table(tables.anisotropic(tables.AIRLIGHT, g), tables.airlight_x(m, beta * r, g),
                tables.airlight_y(m, q, h, g, xi))
    far = beta * r * r
    if g:
        far = far / hg_weight(m, g, q, h)
    return n / (r / xi_over_cos(m, xi) + far)


def closest_point_q(m, d, along, h):
    """Q = z + d, stably: h^2 / (d - z) where z < 0.  along = z is signed, d >= |z|."""
    return m.select(m.less(0.0, along), along + d, h * h / m.maximum(d + m.abs(along), 1e-30))


def segment_ends(m, d_sv, along, h, d_vp, h_min):
    """(h, d_sp, q0, q1, seg) of the camera ray's segment from the viewer to a surface at d_vp (m), in Sun
    et al. 2005's closest-point coordinate Q (Eq. 5): h raised to ``h_min`` (a ray through the light keeps
    a finite integrand), the light-surface distance D_sp = sqrt((d_vp - along)^2 + h^2), the segment's ends
    Q0 and Q1 (``closest_point_q``) and its length Q1 - Q0 = d_vp + d_sp - d_sv, taken as
    d_vp (q0 + q1) / (d_sv + d_sp) without cancellation.  Shared by ``airlight_segment`` and
    ``airlight_quadrature``."""
    h = m.maximum(h, h_min)
    z1 = d_vp - along
    d_sp = m.sqrt(z1 * z1 + h * h)
    q0 = closest_point_q(m, d_sv, -along, h)
    q1 = closest_point_q(m, d_sp, z1, h)
    return h, d_sp, q0, q1, d_vp * ((q0 + q1) / m.maximum(d_sp + d_sv, 1e-30))


def airlight_segment(m, beta, d_sv, along, h, d_vp, g=0.0):
    """Airlight per unit intensity, 1/m^2: Sun et al. 2005 Eq. 5 / Eq. 11, ray from the viewer to a surface.

    d_sv: viewer-light distance; along: D_sv cos(gamma); h: D_sv sin(gamma);
    d_vp: viewer-surface distance (all m).  The light-surface distance is
    D_sp = sqrt((d_vp - along)^2 + h^2).  g: Henyey-Greenstein anisotropy (a Python
    float: the integrand times ``hg_weight``, Pegoraro et al. Eq. 8; tables per g, Biri 2006).
    """
    neg_beta = -beta   # once, not per use: every material inlines this per light
    h, d_sp, q0, q1, seg = segment_ends(m, d_sv, along, h, d_vp, MIN_ANGLE * d_sv)
    long_ = airlight_tail(m, beta, q0, h, d_sv, g) - m.exp(neg_beta * seg) * airlight_tail(m, beta, q1, h, d_sp, g)
    if g < 0.0:
        # back-scatter: both tails are dominated by the peak far beyond the light, and on rays within a few
        # MIN_DISTANCE of it their difference cancels below zero (tests/test_stability.py): no negative glow
        long_ = m.maximum(long_, 0.0)
    short = 0.0
    h2 = h * h
    a2 = h2 * ((1.0 - g) ** 2) if g else None   # hg_weight's (1 - g)^2 h^2, once per segment
    for x, w in zip(_GL_X, _GL_W):
        p = seg * x
        q = q0 + p
        q2 = q * q
        r2 = m.maximum(q2 + h2, 1e-30)
        if g:   # hg_weight / r2 = (1 - g^2) sqrt(r2 / den) / den, den = (1 - g)^2 h^2 + (1 + g)^2 q^2
            den = m.maximum(a2 + ((1.0 + g) ** 2) * q2, 1e-300)
            short = short + (w * (1.0 - g * g)) * m.exp(neg_beta * p) * m.sqrt(r2 / den) / den
        else:
            short = short + w * m.exp(neg_beta * p) / r2
    short = short * seg
    is_short = m.less(beta * seg, SHORT_SEGMENT * m.minimum(1.0, beta * phase_scale(m, g, q0, h)))
    return (beta * INV_2PI) * m.exp(neg_beta * d_sv) * m.select(is_short, short, long_)


def airlight_background(m, beta, d_sv, along, h, g=0.0):
    """Airlight per unit intensity, 1/m^2, of a ray that meets no surface: Sun et al. 2005 Eq. 12
    (g: as in ``airlight_segment``)."""
    h = m.maximum(h, MIN_ANGLE * d_sv)
    q0 = closest_point_q(m, d_sv, -along, h)
    return (beta * INV_2PI) * m.exp(-beta * d_sv) * airlight_tail(m, beta, q0, h, d_sv, g)


def airlight_quadrature(m, beta, d_sv, along, h, d_vp, g=0.0):
    """Airlight per unit intensity, 1/m^2, by quadrature of Sun et al. 2005 Eq. 5 in the shader: no tables.

    Same integral as ``airlight_segment`` (module docstring), in P = Q - Q0,
    (beta / 2 pi) e^{-beta D_sv} int_0^{Q1 - Q0} e^{-beta P} / ((Q0 + P)^2 + h^2) dP,
    taken by 6-point Gauss-Legendre on consecutive panels, each at most
    QUAD_GROWTH sqrt(Q^2 + h^2) long (so the integrand's poles at Q = +-ih stay
    outside the panel's convergence ellipse) and QUAD_DEPTH optical depths
    thick, up to Q1 or optical depth QUAD_END.  Panels grow geometrically
    (x2) until Q ~ 4/beta, so 1 + log2(4 / (beta h)) + QUAD_END / QUAD_DEPTH
    panels suffice (4 more with a forward peak of g = 0.95): QUAD_PANELS = 72 covers beta h >= 1e-16.  Against scipy
    quadrature of Eq. 5 (tests/test_airlight.py): max relative error 1.1e-6.
    A ray that meets no surface (Eq. 12) has d_vp = FAR.  ``g``: Henyey-Greenstein
    anisotropy, the integrand times ``hg_weight`` (Pegoraro et al. Eq. 8); panels are then
    at most QUAD_GROWTH ``phase_scale`` long (the weight's poles at Q = +-ih/s).
    """
    h, _, q0, _, seg = segment_ends(m, d_sv, along, h, d_vp, MIN_ANGLE * m.maximum(d_sv, MIN_DISTANCE))
    end = m.minimum(seg, QUAD_END / beta)

    def panel(pa, total):
        qa = q0 + pa
        pb = m.minimum(pa + m.minimum(QUAD_GROWTH * phase_scale(m, g, qa, h), QUAD_DEPTH / beta), end)
        width = pb - pa
        s = 0.0
        for x, w in zip(_GL_X, _GL_W):
            p = pa + width * x
            q = q0 + p
            s = s + w * hg_weight(m, g, q, h) * m.exp(-beta * p) / (q * q + h * h)
        return pb, total + s * width

    _, total = m.fori(QUAD_PANELS, panel, (0.0, 0.0), done=lambda pa, total: 1.0 - m.less(pa, end))
    return (beta * INV_2PI) * m.exp(-beta * d_sv) * total


def airlight_quadrature_background(m, beta, d_sv, along, h, g=0.0):
    """:func:`airlight_quadrature` of a ray that meets no surface (Sun et al. 2005 Eq. 12), 1/m^2."""
    return airlight_quadrature(m, beta, d_sv, along, h, FAR, g)



def airlight_equiangular(m, beta, d_sv, along, h, d_vp, u, g=0.0):
    """One sample's estimate of the airlight per unit intensity, 1/m^2 (Sun et al. 2005 Eq. 5), for the uniform
    number ``u`` in [0, 1): its mean over u is ``airlight_segment``'s value, without a table or a sum.

    Equiangular sampling (Kulla and Fajardo 2012, Eq. 8-10): a point of the ray at the angle theta, seen from the
    light, from the ray's closest point, taken uniformly between the segment's ends theta_a = atan2(-along, h)
    and theta_b = atan2(d_vp - along, h), lies at t = along + h tan(theta) from the camera and r = h / cos(theta)
    from the light.  Its density over t, h / ((theta_b - theta_a) r^2), cancels Eq. 5's 1/r^2, so the estimate
    beta / (4 pi) 4 pi p_HG (theta_b - theta_a) / h e^{-beta (t + r)} varies only by the extinction and the
    phase function over the segment.  The scattering angle there has cosine -sin(theta) (toward the camera from
    the light; ``hg_weight``).  EQUIANGULAR_POINTS points, one in each equal stratum of theta ((u + k) / K),
    are averaged.  The segment ends EQUIANGULAR_DEPTH optical depths past the light's closest point (or the
    camera), where what is left is below e^-8 of the glow: a ray to the sky keeps its points where it glows.
    The viewport preview's sampled lights (``nodes/preview_sampled.py``) take it, one light a render sample.
    """
    h = m.maximum(h, MIN_ANGLE * m.maximum(d_sv, MIN_DISTANCE))
    theta_a = m.atan2(-1.0 * along, h)
    end = m.minimum(d_vp, m.maximum(along, 0.0) + EQUIANGULAR_DEPTH / m.maximum(beta, 1e-30))
    span = m.atan2(end - along, h) - theta_a
    step = span * (1.0 / EQUIANGULAR_POINTS)
    scale = (beta * (0.25 / math.pi)) * step / h   # (the strata's mean: span / K)
    start = m.mul_add(u, step, theta_a)
    total = 0.0
    for k in range(EQUIANGULAR_POINTS):
        theta = start + step * float(k) if k else start
        cos_t = m.maximum(m.cos(theta), 1e-30)
        point = m.exp(-beta * (m.mul_add(h, m.tan(theta), along) + h / cos_t))
        if g:   # 4 pi p_HG at cos = -sin(theta): (1 - g^2) (1 + g^2 + 2 g sin(theta))^{-3/2}
            point = point * ((1.0 - g * g) * m.power(m.maximum(m.mul_add(m.sin(theta), 2.0 * g, 1.0 + g * g),
                                                               1e-30), -1.5))
        total = total + point
    return scale * total


def airlight_equiangular_background(m, beta, d_sv, along, h, u, g=0.0):
    """:func:`airlight_equiangular` of a ray that meets no surface (Sun et al. 2005 Eq. 12), 1/m^2."""
    return airlight_equiangular(m, beta, d_sv, along, h, FAR, u, g)

def ray_light_geometry(m, origin, direction, light):
    """(d_sv, along, h) of a ray (unit ``direction``) and a light position, all vectors."""
    to_light = light - origin
    d_sv = m.length(to_light)
    along = m.dot(to_light, direction)
    h = m.length(m.cross(to_light, direction))
    return d_sv, along, h


def transmittance(m, beta, d):
    """exp(-beta d): Beer-Lambert extinction over d metres (Sun et al. 2005 Eq. 2, 14, 19)."""
    return m.exp(-beta * d)
