"""Daylight fog: a layer with a top, the sun and the sky through it (issue 29; the clear air: ``aerial.py``).

The medium is a function of height only (z up, metres).  The fog layer of extinction

    beta(z) = beta0                          z <= h0   (the layer's top)
    beta(z) = beta0 exp(-(z - h0) / H)       z >  h0   (H = 0: a hard top, nothing above h0)

(``UNBOUNDED``, a top at model.FAR, is the infinite fog of the night scenes), single-scattering albedo
a (scattering a beta).  Below the ground the medium never matters: a camera segment ends at a surface,
the sun and the sky shine from above.  Every kernel takes scalars (``ops.py``): a camera point of
height ``pz`` (m), the z-component ``vz`` of a unit view direction, a segment length (m), the sun's
elevation sine ``mu_s`` (the z-component of the unit vector towards the sun) and the cosine of the
scattering angle ``cos_theta`` = v . s (1 looking straight at the sun).

Two facts carry everything here (derivations in docs/measurements/2026-11-27-daylight-kernels.md):

* The column depth C(z) = int_z^inf beta dz' (``column_depth``) is closed form, and the optical depth
  along any straight ray is the column depth's change divided by |v_z| (``optical_depth`` writes it
  without that division, so horizontal rays are exact).
* Along a camera ray z(t) = p_z + v_z t, the optical depth to the sun from z(t) is
  tau_s(t) = tau_s(0) - (v_z / mu_s) tau_c(t), tau_c(t) the camera's optical depth to t, for EVERY
  vertical profile: both are the same column depth read along two directions.  So the sun's single
  scattering (Dobashi et al. 2002 Eq. 11 with one species) is int_0^{tau_D} e^{-tau_s(0) - k tau} dtau,
  k = 1 - v_z / mu_s: one closed form for the slab, the exponential and both chained across the top
  (``sun_airlight``).  The sky is the same integral summed over the sun's directions
  (``sky_airlight``).

No kernel branches (select evaluates both sides): every 0/0 (horizontal rays, k -> 0, v_z -> mu_s,
H = 0) is a series switched by a select or a denominator held away from 0, and every exponent is
clamped (``EXP_CLAMP``) so no intermediate overflows in float32.
"""
import functools
import math

import numpy as np

from ..point import model

UNBOUNDED = model.FAR       # m; the top of a layer without one (the infinite fog): beta0 everywhere
EXP_CLAMP = 80.0            # exponents are clamped to [-80, 80] (e^-80 = 1.8e-35, a float32 normal number)
SERIES_X = 0.05             # phi1 switches to its series below this argument (series error < 1e-9)
MIN_SPAN = 1e-12            # m; a ray whose height changes less than this along a segment is horizontal
MIN_FALLOFF = 1e-6          # m; H below this is a hard top (nothing above h0)
MIN_MU = 1e-6               # the sun's elevation sine is held above this; mu_s <= 0 (sun down) gives 0
INV_4PI = 1.0 / (4.0 * math.pi)
SKY_NODES = 10                               # Gauss-Legendre directions of ``sky_airlight``


@functools.lru_cache(maxsize=None)
def gauss_legendre01(n):
    """(nodes, weights) of n-point Gauss-Legendre on [0, 1], as Python floats (unrolled in the kernels)."""
    x, w = np.polynomial.legendre.leggauss(n)
    return tuple(float(v) for v in 0.5 * (x + 1.0)), tuple(float(v) for v in 0.5 * w)


def exp_neg(m, x):
    """e^{-x} with x clamped to [-EXP_CLAMP, EXP_CLAMP]: no float32 overflow in either direction."""
    return m.exp(-m.minimum(m.maximum(x, -EXP_CLAMP), EXP_CLAMP))


def phi1(m, x):
    """(1 - e^{-x}) / x for x >= 0 (int_0^1 e^{-x s} ds), 1 at x = 0: the series 1 - x/2 + x^2/6 - x^3/24
    + x^4/120 below SERIES_X (error < x^5/720 < 5e-10), the quotient above it."""
    xs = m.minimum(x, SERIES_X)     # the series is evaluated everywhere (select): kept finite for large x
    series = 1.0 + xs * (-0.5 + xs * (1.0 / 6.0 + xs * (-1.0 / 24.0 + xs * (1.0 / 120.0))))
    quotient = (1.0 - exp_neg(m, x)) / m.maximum(x, SERIES_X)
    return m.select(m.less(x, SERIES_X), series, quotient)


def hg_phase(m, g, cos_theta):
    """Henyey-Greenstein phase function, 1/sr: (1 - g^2) / (4 pi (1 + g^2 - 2 g cos_theta)^{3/2}), |g| < 1;
    cos_theta = v . s (the light travels along -s, is scattered towards the camera along -v)."""
    den = 1.0 + g * g - 2.0 * g * cos_theta
    return ((1.0 - g * g) * INV_4PI) / (den * m.sqrt(den))


# --- the layer ------------------------------------------------------------------------------------------

def extinction(m, z, beta0, h0, H):
    """beta(z), 1/m: beta0 up to the top h0 (m), beta0 e^{-(z - h0)/H} above it, 0 above a hard top (H = 0)."""
    above = m.maximum(z - h0, 0.0)
    fall = exp_neg(m, above / m.maximum(H, MIN_FALLOFF))
    hard = m.less(H, MIN_FALLOFF) * m.less(0.0, above)
    return beta0 * m.select(hard, 0.0, fall)


def column_depth(m, z, beta0, h0, H):
    """C(z) = int_z^inf beta(z') dz', the vertical optical depth from height z (m) to the top of the medium:
    beta0 (max(h0 - z, 0) + H e^{-max(z - h0, 0)/H}) (H = 0: beta0 max(h0 - z, 0))."""
    above = m.maximum(z - h0, 0.0)
    return beta0 * (m.maximum(h0 - z, 0.0) + H * exp_neg(m, above / m.maximum(H, MIN_FALLOFF)))


def optical_depth(m, pz, vz, length, beta0, h0, H):
    """Optical depth of the segment from height pz (m) along a unit direction of z-component vz, ``length``
    m long, through the layer (beta0 1/m, top h0 m, falloff H m): the length below the top times beta0,
    plus the part above it,

        tau_above = beta0 e^{-x_lo} L_above phi1(dx),  x_lo = (z_lo - h0)/H,  dx = |vz| L_above / H,

    z_lo the lower end of the part above the top, dx its rise in falloff lengths (the exponential integrated exactly:
    int e^{-(z - h0)/H} dt = e^{-x_lo} L phi1(dx)).  No division by vz: horizontal rays (vz = 0) and
    rays along the top are exact; H = 0 (a hard top) makes the part above 0."""
    if isinstance(H, (int, float)) and H < MIN_FALLOFF:   # a hard top known when the kernel is built: no part
        return _hard_depth(m, pz, vz, length, beta0, h0)      # above it (the same value, a third of the nodes)
    z1 = pz + vz * length
    z_lo, z_hi = m.minimum(pz, z1), m.maximum(pz, z1)
    span = z_hi - z_lo
    flat = m.less(span, MIN_SPAN)
    below_frac = m.select(flat, 1.0 - m.less(h0, z_lo),
                          m.clamp01((h0 - z_lo) / m.maximum(span, MIN_SPAN)))
    l_below = length * below_frac
    l_above = length - l_below
    hs = m.maximum(H, MIN_FALLOFF)
    tau_above = exp_neg(m, (m.maximum(z_lo, h0) - h0) / hs) * l_above * phi1(m, m.abs(vz) * l_above / hs)
    tau_above = m.select(m.less(H, MIN_FALLOFF), 0.0, tau_above)
    return beta0 * (l_below + tau_above)


def _hard_depth(m, pz, vz, length, beta0, h0):
    """``optical_depth`` of a hard top (H = 0): beta0 times the length below h0."""
    z1 = pz + vz * length
    z_lo, z_hi = m.minimum(pz, z1), m.maximum(pz, z1)
    span = z_hi - z_lo
    below_frac = m.select(m.less(span, MIN_SPAN), 1.0 - m.less(h0, z_lo),
                          m.clamp01((h0 - z_lo) / m.maximum(span, MIN_SPAN)))
    return beta0 * (length * below_frac)


def transmittance(m, pz, vz, length, beta0, h0, H):
    """e^{-tau} of a camera segment (``optical_depth``): what is left of a surface's radiance."""
    return exp_neg(m, optical_depth(m, pz, vz, length, beta0, h0, H))


def sun_depth(m, z, mu_s, beta0, h0, H):
    """Optical depth from height z (m) to the sun, elevation sine mu_s > 0: C(z) / mu_s (flat Earth;
    mu_s held above MIN_MU, so a sun on the horizon gives C / MIN_MU, not a division by 0)."""
    return column_depth(m, z, beta0, h0, H) / m.maximum(mu_s, MIN_MU)


def sun_transmittance(m, z, mu_s, beta0, h0, H):
    """The fraction of the sun's irradiance that reaches height z (m) through the layer: e^{-C(z)/mu_s}
    (Dobashi et al. 2002 Eq. 11's g_l, flat Earth), 0 for a sun on or below the horizon (mu_s <= 0: the
    ground plane hides it)."""
    up = m.less(0.0, mu_s)
    return m.select(up, exp_neg(m, sun_depth(m, z, mu_s, beta0, h0, H)), 0.0)


def sun_integral(m, tau_d, phi_0, phi_d, k):
    """int_0^{tau_d} e^{-Phi(tau)} dtau for Phi linear in tau, Phi(0) = phi_0, Phi(tau_d) = phi_d =
    phi_0 + k tau_d: tau_d e^{-min(phi_0, phi_d)} phi1(|k tau_d|), from the end where Phi is smallest
    (nothing grows for k < 0); 0 for tau_d = 0, tau_d e^{-phi_0} for k = 0."""
    return tau_d * exp_neg(m, m.minimum(phi_0, phi_d)) * phi1(m, m.abs(tau_d * k))


def sun_airlight(m, pz, vz, length, mu_s, cos_theta, beta0, h0, H, albedo=1.0, g=0.0):
    """The sun's single scattering along a camera segment per unit sun irradiance (1/sr; times the sun's
    irradiance E_sun in W/m^2 gives W/(m^2 sr)): Dobashi et al. 2002 Eq. 11, one species,

        L / E_sun = a p(cos_theta) int_0^D beta(z(t)) e^{-tau_c(t) - tau_s(z(t))} dt
                  = a p tau_D e^{-min(tau_s0, tau_s1 + tau_D)} phi1(|tau_D (1 - vz/mu_s)|),

    tau_D the segment's optical depth, tau_s0, tau_s1 the sun's optical depths at its two ends: the
    integrand is e^{-tau_s0 - k tau} in the camera's optical depth tau for every vertical profile
    (k = 1 - vz / mu_s), integrated from the end where the exponent is smallest so nothing grows (k < 0:
    looking up more steeply than the sun).  Limits: k -> 0 (vz -> mu_s) and tau_D -> 0 through phi1;
    vz = 0 exact; rays that never meet the layer (tau_D = 0) give 0; a sun on or below the horizon
    gives 0.  p: Henyey-Greenstein of anisotropy g (``hg_phase``)."""
    tau_d = optical_depth(m, pz, vz, length, beta0, h0, H)
    tau_s0 = sun_depth(m, pz, mu_s, beta0, h0, H)
    tau_s1 = sun_depth(m, pz + vz * length, mu_s, beta0, h0, H)
    integral = sun_integral(m, tau_d, tau_s0, tau_s1 + tau_d, 1.0 - vz / m.maximum(mu_s, MIN_MU))
    return m.select(m.less(0.0, mu_s), (albedo * hg_phase(m, g, cos_theta)) * integral, 0.0)


# --- the sky -------------------------------------------------------------------------------------------

# E1(x) + ln x for 0 < x <= 1 (Abramowitz & Stegun 5.1.53, |error| < 2e-7)
_E1_SERIES = (-0.57721566, 0.99999193, -0.24991055, 0.05519968, -0.00976004, 0.00107857)
# x e^x E2(x) for x >= 1 as (1 + u (a1 + u (a2 + u a3))) / (1 + u (b1 + u (b2 + u b3))), u = 1/x: fitted to
# scipy.special.expn (tests/test_daylight.py measures its relative error: < 2e-6 on [1, 1e7])
_E2_NUM = (6.259766763730008, 6.4949820829417195, 0.13640901135554848)
_E2_DEN = (8.259410344627094, 17.036276590455433, 8.117898612302426)
_LN_ROOT = 1024.0      # ``log`` takes ln of the 1024th root (|ln| <= 0.07 for x in [1e-30, 1e30])


def log(m, x):
    """ln x for x in [1e-30, 1e30] from power and a series (the ops have no logarithm): with
    y = x^(1/1024) and s = (y - 1)/(y + 1), ln x = 2048 (s + s^3/3 + s^5/5 + s^7/7) (|s| < 0.035, series
    error < 1e-11; in float32 the root's rounding makes it ~6e-5 absolute)."""
    y = m.power(m.minimum(m.maximum(x, 1e-30), 1e30), 1.0 / _LN_ROOT)
    s = (y - 1.0) / (y + 1.0)
    s2 = s * s
    return (2.0 * _LN_ROOT) * s * (1.0 + s2 * (1.0 / 3.0 + s2 * (1.0 / 5.0 + s2 * (1.0 / 7.0))))


def expint2(m, x):
    """The exponential integral E2(x) = int_0^1 e^{-x/mu} dmu for x >= 0 (E2(0) = 1): e^{-x} - x E1(x) with
    A&S 5.1.53 for x <= 1 (x ln x is exact in the limit x -> 0), e^{-x} R(1/x) / x with a rational R
    for x > 1 (``_E2_NUM``, ``_E2_DEN``).  Relative error < 3e-7 below 1, < 2e-6 above (float64)."""
    xs = m.minimum(x, 1.0)
    a = _E1_SERIES
    poly = a[0] + xs * (a[1] + xs * (a[2] + xs * (a[3] + xs * (a[4] + xs * a[5]))))
    small = exp_neg(m, xs) + xs * (log(m, xs) - poly)
    xl = m.maximum(x, 1.0)
    u = 1.0 / xl
    n, d = _E2_NUM, _E2_DEN
    r = (1.0 + u * (n[0] + u * (n[1] + u * n[2]))) / (1.0 + u * (d[0] + u * (d[1] + u * d[2])))
    large = exp_neg(m, xl) * r * u
    return m.select(m.less(x, 1.0), small, large)


def expint3(m, x):
    """E3(x) = int_0^1 mu e^{-x/mu} dmu = (e^{-x} - x E2(x)) / 2 for x >= 0 (E3(0) = 1/2); above x = 1 with
    1 - R(u) written without cancellation (same rational as ``expint2``)."""
    xs = m.minimum(x, 1.0)
    small = 0.5 * (exp_neg(m, xs) - xs * expint2(m, xs))
    xl = m.maximum(x, 1.0)
    u = 1.0 / xl
    n, d = _E2_NUM, _E2_DEN
    den = 1.0 + u * (d[0] + u * (d[1] + u * d[2]))
    one_minus_r = u * ((d[0] - n[0]) + u * ((d[1] - n[1]) + u * (d[2] - n[2]))) / den
    large = 0.5 * exp_neg(m, xl) * one_minus_r
    return m.select(m.less(x, 1.0), small, large)


def sky_source(m, z, beta0, h0, H, albedo=1.0):
    """The sky's single-scattering source at height z per unit sky radiance (dimensionless: radiance
    scattered per unit optical depth over L_sky): a uniform sky of radiance L_sky over the upper
    hemisphere, the ground black (it sends nothing up), isotropic scattering,

        S(z) / L_sky = a / (4 pi) int_{upper} e^{-C(z) / mu} dw = (a / 2) E2(C(z)),

    C the column depth above z (``column_depth``): any vertical profile; for the slab beta0 (h0 - z) +
    beta0 H.  Dobashi et al. 2002's ambient term made a function of depth."""
    return (0.5 * albedo) * expint2(m, column_depth(m, z, beta0, h0, H))


def sky_irradiance(m, z, beta0, h0, H):
    """The sky's irradiance on an upward-facing horizontal surface at height z, over its value without fog
    (pi L_sky): 2 pi L int_0^1 mu e^{-C/mu} dmu / (pi L) = 2 E3(C(z)) (direct sky light only; the fog's
    own glow on the surface is not in it)."""
    return 2.0 * expint3(m, column_depth(m, z, beta0, h0, H))


# E(m) = (1 + m1 (a1 + ...)) + m1 (b1 + ...) ln(1/m1), m1 = 1 - m (Abramowitz & Stegun 17.3.36, |error| < 2e-8)
_ELLIPTIC_A = (0.44325141463, 0.06260601220, 0.04757383546, 0.01736506451)
_ELLIPTIC_B = (0.24998368310, 0.09200180037, 0.04069697526, 0.00526449639)


def elliptic_e(m, m1):
    """The complete elliptic integral of the second kind E(m) of parameter m = 1 - m1, 0 < m1 <= 1 (A&S 17.3.36)."""
    a, b = _ELLIPTIC_A, _ELLIPTIC_B
    pa = 1.0 + m1 * (a[0] + m1 * (a[1] + m1 * (a[2] + m1 * a[3])))
    pb = m1 * (b[0] + m1 * (b[1] + m1 * (b[2] + m1 * b[3])))
    return pa - pb * m.log(m1)


def hg_ring_mean(m, g, mu, vz):
    """The Henyey-Greenstein phase function averaged over the ring of directions of z-component mu (1/sr):
    (1 / 2 pi) int p(v . w) dphi, v of z-component vz.  With v . w = a + b cos phi (a = mu vz,
    b = sqrt((1 - mu^2)(1 - vz^2))), A = 1 + g^2 - 2 g a, B = 2 |g| b:
    int_0^{2 pi} (A - B cos phi)^{-3/2} dphi = 4 E(k^2) / ((A - B) sqrt(A + B)), k^2 = 2 B / (A + B)
    (Gradshteyn & Ryzhik 2.571), so the mean is (1 - g^2) E / (2 pi^2 (A - B) sqrt(A + B)); 1 / (4 pi) at g = 0.
    A - B >= (1 - |g|)^2 > 0: no singularity for |g| < 1."""
    b = m.sqrt(m.maximum((1.0 - mu * mu) * (1.0 - vz * vz), 0.0))
    big_a = (1.0 + g * g) - (2.0 * g) * (mu * vz)
    big_b = (2.0 * abs(g)) * b
    diff, total = big_a - big_b, big_a + big_b
    return ((1.0 - g * g) / (2.0 * math.pi * math.pi)) * elliptic_e(m, diff / total) / (diff * m.sqrt(total))


WALL_NODES = 6                               # Gauss-Legendre nodes of ``sky_wall_irradiance``


def sky_wall_irradiance(m, z, beta0, h0, H, nodes=WALL_NODES):
    """The sky's irradiance on a vertical surface at height z over its value without fog (pi L_sky / 2): a wall
    sees the sky's upper half through the column depth C(z) / mu, (4 / pi) int_0^1 sqrt(1 - mu^2) e^{-C / mu} dmu
    (the clipped cosine integrated over azimuth is 2 sqrt(1 - mu^2)), by ``nodes``-point Gauss-Legendre (1e-3 at
    C = 0, where the integrand's root at mu = 1 is steepest; 2e-3 of the ratio at C = 0.1 to 2)."""
    return wall_irradiance_of_column(m, column_depth(m, z, beta0, h0, H), nodes)


def wall_irradiance_of_column(m, c, nodes=WALL_NODES):
    """``sky_wall_irradiance`` under a column depth c above the point (any vertical profile, any species)."""
    xs, ws = gauss_legendre01(nodes)
    total = 0.0
    for mu, w in zip(xs, ws):
        total = total + (w * (4.0 / math.pi) * math.sqrt(1.0 - mu * mu)) * exp_neg(m, c * (1.0 / mu))
    return total


def sky_tilted_irradiance(m, z, nz, beta0, h0, H):
    """The sky's direct irradiance through the layer on a surface of normal z-component nz at height z, per unit sky
    radiance (W/m^2 per W/(m^2 sr)): the quadratic in nz through its exact values facing down (0), sideways
    (pi/2 ``sky_wall_irradiance``) and up (pi ``sky_irradiance``), clamped at 0.  Within 2 % of the fog-free value
    pi (1 + nz) / 2 for nz >= 0 and 3 % at nz = -0.5 (tests/test_sunlight.py); below, where the sky's weight is
    small, more."""
    return tilted_irradiance_of_column(m, column_depth(m, z, beta0, h0, H), nz)


def tilted_irradiance_of_column(m, c, nz):
    """``sky_tilted_irradiance`` under a column depth c above the point (the direct sky light depends on the
    column alone: any vertical profile, the layer and the air together)."""
    a = (0.5 * math.pi) * wall_irradiance_of_column(m, c)
    half_up = math.pi * expint3(m, c)
    return m.maximum(a + nz * (half_up + nz * (half_up - a)), 0.0)


def sky_airlight(m, pz, vz, length, beta0, h0, H, albedo=1.0, nodes=SKY_NODES, g=0.0):
    """The uniform sky's single scattering along a camera segment per unit sky radiance (dimensionless),
    ground black:

        L / L_sky = int_0^D beta S(z(t)) e^{-tau_c(t)} dt = a int_0^1 I(mu) 2 pi pbar(mu) dmu,

    I(mu) the one-species integral of ``sun_airlight`` for a sun of elevation sine mu (the sky is a sum of
    suns; each is closed form along the ray, for every vertical profile) and pbar the phase function averaged over
    the sky's ring at mu (``hg_ring_mean``; 1 / (4 pi) for isotropic scattering, g = 0, where the factor is 1/2):
    ``nodes``-point Gauss-Legendre in mu.  Its error against scipy (docs/measurements/2026-11-27-daylight-kernels.md)
    comes from the grazing directions (mu -> 0) near the top of a hard layer."""
    tau_d = optical_depth(m, pz, vz, length, beta0, h0, H)
    c0 = column_depth(m, pz, beta0, h0, H)
    c1 = column_depth(m, pz + vz * length, beta0, h0, H)
    xs, ws = gauss_legendre01(nodes)
    total = 0.0
    for mu, w in zip(xs, ws):
        term = w * sun_integral(m, tau_d, c0 * (1.0 / mu), c1 * (1.0 / mu) + tau_d, 1.0 - vz * (1.0 / mu))
        if g:
            term = term * ((2.0 * math.pi) * hg_ring_mean(m, g, mu, vz))
        else:
            term = 0.5 * term
        total = total + term
    return albedo * total


def sky_transmittance(m, pz, vz, beta0, h0, H):
    """The sky seen through the layer along a ray that meets no surface (Koschmieder's law with a
    height-dependent medium): L = L_sky e^{-tau(ray to infinity)} + ``sky_airlight`` (+ ``sun_airlight``).
    A ray that points down ends on the ground (give its length to ``transmittance``); here its depth is that
    of model.FAR metres, and the result 0."""
    return transmittance(m, pz, vz, UNBOUNDED, beta0, h0, H)
