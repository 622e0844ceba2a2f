"""Daylight fog: a layer with a top, the sun and the sky through it, distance haze (issue 29).

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

Two species of different scale heights (Rayleigh and Mie, ``haze_airlight``) keep the exponent's
identity (it holds for the total), so the sum of the two species' integrals is the same closed form; the
share of one species varies along the ray, and it alone is integrated by panels in that species' optical
depth, exact in the exponential's ends.

No kernel branches (select evaluates both sides): every 0/0 (horizontal rays, k -> 0, v_z -> mu_s,
H = 0) is a series switched by a select or a denominator held away from 0, and every exponent is
clamped (``EXP_CLAMP``) so no intermediate overflows in float32.
"""
import functools
import math

import numpy as np

from . import model

UNBOUNDED = model.FAR       # m; the top of a layer without one (the infinite fog): beta0 everywhere
EXP_CLAMP = 80.0            # exponents are clamped to [-80, 80] (e^-80 = 1.8e-35, a float32 normal number)
SERIES_X = 0.05             # phi1 switches to its series below this argument (series error < 1e-9)
MIN_SPAN = 1e-12            # m; a ray whose height changes less than this along a segment is horizontal
MIN_FALLOFF = 1e-6          # m; H below this is a hard top (nothing above h0)
MIN_MU = 1e-6               # the sun's elevation sine is held above this; mu_s <= 0 (sun down) gives 0
INV_4PI = 1.0 / (4.0 * math.pi)

# Distance haze: the clear-sky atmosphere of Bruneton & Neyret 2008 section 2.1 (Eq. 1-4): Rayleigh
# scattering at sea level for lambda = 680, 550, 440 nm, its scale height; aerosols of scale height
# 1.2 km whose extinction is scattering / 0.9; Cornette-Shanks g.
RAYLEIGH_RGB = (5.8e-6, 13.5e-6, 33.1e-6)   # 1/m
RAYLEIGH_HEIGHT = 8000.0                     # m (Dobashi et al. 2002 appendix A.1: 7994 m)
MIE_HEIGHT = 1200.0                          # m (Dobashi et al. 2002 appendix A.1: 1.2 km)
MIE_SCATTERING = 2.0e-5                      # 1/m, a hazy day; a parameter of the kernel
MIE_ALBEDO = 0.9                             # aerosol scattering / extinction
MIE_G = 0.76
EARTH_RADIUS = 6.371e6                       # m (only for the flat-Earth limit, ``flat_earth_error``)
HAZE_PANELS = 12                             # panels of ``haze_airlight``'s Mie integral
HAZE_DEPTH = 20.0                            # a haze ray's panels stop this camera optical depth out
HAZE_HEIGHTS = 8.0                           # ... or this many Mie scale heights above the camera
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


def haze_grading(panels):
    """The ends of ``haze_airlight``'s panels as fractions of the integrated length: (j / n)^2.5, graded
    towards the camera where the integrand is largest."""
    return tuple((j / panels) ** 2.5 for j in range(panels + 1))



def hg_phase(m, g, cos_theta):
    """Henyey-Greenstein phase function, 1/sr: (1 - g^2) / (4 pi (1 + g^2 - 2 g cos_theta)^{3/2}), |g| < 1;
    cos_theta = v . s (the light travels along -s, is scattered towards the camera along -v)."""
    den = 1.0 + g * g - 2.0 * g * cos_theta
    return ((1.0 - g * g) * INV_4PI) / (den * m.sqrt(den))


def rayleigh_phase(m, cos_theta):
    """Rayleigh phase function, 1/sr: 3 (1 + cos^2 theta) / (16 pi) (Bruneton & Neyret 2008 Eq. 2)."""
    return (3.0 / (16.0 * math.pi)) * (1.0 + cos_theta * cos_theta)


def cornette_shanks_phase(m, g, cos_theta):
    """Cornette-Shanks phase function, 1/sr (Bruneton & Neyret 2008 Eq. 4, the Mie approximation):
    3 (1 - g^2) (1 + cos^2) / (8 pi (2 + g^2) (1 + g^2 - 2 g cos)^{3/2})."""
    den = 1.0 + g * g - 2.0 * g * cos_theta
    return ((3.0 * (1.0 - g * g)) / (8.0 * math.pi * (2.0 + g * g))) * (1.0 + cos_theta * cos_theta) / (
        den * m.sqrt(den))


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


# --- distance haze: Rayleigh and Mie (Dobashi et al. 2002 Eq. 11) ----------------------------------------

def haze_extinctions(m, z, z_ground, rayleigh, mie, mie_albedo=MIE_ALBEDO, h_r=RAYLEIGH_HEIGHT,
                     h_m=MIE_HEIGHT):
    """(beta_R, beta_M) at height z (m), 1/m: each species' ground value times e^{-(z - z_ground)/H}
    (Dobashi et al. 2002 appendix A.1's rho_r, rho_m); Rayleigh does not absorb, Mie's extinction is its
    scattering ``mie`` / ``mie_albedo``."""
    y = m.maximum(z - z_ground, 0.0)
    return rayleigh * exp_neg(m, y / h_r), (mie / mie_albedo) * exp_neg(m, y / h_m)


def exponential_depth(m, pz, vz, length, beta_ground, z_ground, H):
    """Optical depth of a segment through one species of density beta_ground e^{-(z - z_ground)/H} (1/m at
    the ground; flat Earth): beta(z_lo) L phi1(|vz| L / H), z_lo the segment's lower end (heights below the
    ground count as the ground).  ``optical_depth`` with h0 = z_ground, in a third of the operations."""
    z_lo = m.minimum(pz, pz + vz * length)
    return beta_ground * exp_neg(m, m.maximum(z_lo - z_ground, 0.0) / H) * length * phi1(m, m.abs(vz) * length / H)


def haze_depth(m, pz, vz, length, z_ground, rayleigh, mie, mie_albedo=MIE_ALBEDO, h_r=RAYLEIGH_HEIGHT,
               h_m=MIE_HEIGHT):
    """Optical depth of a camera segment through both species (Dobashi et al. 2002 Eq. A.1, flat Earth)."""
    return (exponential_depth(m, pz, vz, length, rayleigh, z_ground, h_r)
            + exponential_depth(m, pz, vz, length, mie / mie_albedo, z_ground, h_m))


def haze_sun_depth(m, z, mu_s, z_ground, rayleigh, mie, mie_albedo=MIE_ALBEDO, h_r=RAYLEIGH_HEIGHT,
                   h_m=MIE_HEIGHT):
    """Optical depth from height z (m) to the sun through both species (Dobashi et al. 2002 Eq. A.4's
    exponent, flat Earth): (beta_R(z) H_R + beta_M(z) H_M) / mu_s."""
    br, bm = haze_extinctions(m, z, z_ground, rayleigh, mie, mie_albedo, h_r, h_m)
    return (br * h_r + bm * h_m) / m.maximum(mu_s, MIN_MU)


def haze_airlight(m, pz, vz, length, mu_s, cos_theta, z_ground, rayleigh, mie, mie_albedo=MIE_ALBEDO,
                  g=MIE_G, h_r=RAYLEIGH_HEIGHT, h_m=MIE_HEIGHT, panels=HAZE_PANELS, grading=haze_grading):
    """The sun's single scattering in the haze along a camera segment, per unit sun irradiance (1/sr), one
    colour channel (``rayleigh``: that channel's Rayleigh coefficient at the ground, ``mie``: the aerosols'
    scattering coefficient at the ground, both 1/m): Dobashi et al. 2002 Eq. 11's integral, flat Earth,

        L / E_sun = P_R I_R + P_M a_M I_M,  I_i = int_0^D beta_i(z(t)) e^{-Phi(t)} dt,
        Phi(t) = tau_s(z(t)) + tau_c(t)   (both species),

    P_R Rayleigh, P_M Cornette-Shanks, a_M the aerosols' albedo.  Phi = Phi(0) + k tau_c(t) with
    k = 1 - vz / mu_s holds for each species, hence for their sum, so I_R + I_M = J, the one-species closed
    form of ``sun_integral`` with the total optical depths: exact.  I_M = int e^{-Phi} dtau_M is taken in the
    Mie optical depth tau_M, where Phi is nearly linear (tau_R is a smooth function of tau_M): ``panels``
    panels whose ends are fractions ``grading`` of the integrated length (graded towards the camera), Phi
    exact at their ends and exponential between them (each panel dtau_M e^{-min(Phi_a, Phi_b)}
    phi1(|Phi_b - Phi_a|), the one-species formula).  I_R = J - I_M.  The integrated length stops where the
    camera's optical depth is certainly past HAZE_DEPTH / max(k, 1) (the rest is below e^{-HAZE_DEPTH}
    of what came before) or HAZE_HEIGHTS Mie scale heights above the camera (the aerosols' column left
    is e^{-HAZE_HEIGHTS} of it).  The error of this quadrature is measured against scipy in
    docs/measurements/2026-11-27-daylight-kernels.md."""
    mu = m.maximum(mu_s, MIN_MU)
    k = 1.0 - vz / mu
    beta_m = mie / mie_albedo
    tau_d = haze_depth(m, pz, vz, length, z_ground, rayleigh, mie, mie_albedo, h_r, h_m)
    phi0 = haze_sun_depth(m, pz, mu_s, z_ground, rayleigh, mie, mie_albedo, h_r, h_m)
    phi_d = haze_sun_depth(m, pz + vz * length, mu_s, z_ground, rayleigh, mie, mie_albedo, h_r, h_m) + tau_d
    total = sun_integral(m, tau_d, phi0, phi_d, k)
    br0, bm0 = haze_extinctions(m, pz, z_ground, rayleigh, mie, mie_albedo, h_r, h_m)
    depth = HAZE_DEPTH / m.maximum(k, 1.0)
    up = m.maximum(vz, 0.0)
    # tau_c(t) >= b0 t / (1 + up t / h_m) on a rising ray (each species' 1 - e^{-y} >= y / (1 + y) and
    # h_m <= h_r), >= b0 t on a level or falling one: past t_depth the camera's optical depth exceeds depth
    t_depth = depth / m.maximum((br0 + bm0) - depth * up / h_m, 1e-30)
    t_height = (HAZE_HEIGHTS * h_m) / m.maximum(up, 1e-30)
    t_end = m.minimum(length, m.minimum(t_depth, t_height))
    mie_part = 0.0
    tau_a = phi_a = None
    for s in grading(panels):
        t = t_end * s
        tau_b = exponential_depth(m, pz, vz, t, beta_m, z_ground, h_m)
        phi_b = (haze_sun_depth(m, pz + vz * t, mu_s, z_ground, rayleigh, mie, mie_albedo, h_r, h_m)
                 + exponential_depth(m, pz, vz, t, rayleigh, z_ground, h_r) + tau_b)
        if tau_a is not None:
            mie_part = mie_part + (tau_b - tau_a) * exp_neg(m, m.minimum(phi_a, phi_b)) * phi1(
                m, m.abs(phi_b - phi_a))
        tau_a, phi_a = tau_b, phi_b
    mie_part = m.minimum(mie_part, total)
    out = rayleigh_phase(m, cos_theta) * (total - mie_part) + (
        cornette_shanks_phase(m, g, cos_theta) * mie_albedo) * mie_part
    return m.select(m.less(0.0, mu_s), out, 0.0)


def haze_transmittance(m, pz, vz, length, z_ground, rayleigh, mie, mie_albedo=MIE_ALBEDO,
                       h_r=RAYLEIGH_HEIGHT, h_m=MIE_HEIGHT):
    """e^{-tau} of a camera segment through the haze (Dobashi et al. 2002 Eq. 11's g_v), one channel."""
    return exp_neg(m, haze_depth(m, pz, vz, length, z_ground, rayleigh, mie, mie_albedo, h_r, h_m))


def haze_sun_transmittance(m, z, mu_s, z_ground, rayleigh, mie, mie_albedo=MIE_ALBEDO, h_r=RAYLEIGH_HEIGHT,
                           h_m=MIE_HEIGHT):
    """The fraction of the sun's irradiance that reaches height z through the haze (Dobashi et al. 2002
    Eq. A.4, flat Earth), one channel; 0 for a sun on or below the horizon."""
    t = exp_neg(m, haze_sun_depth(m, z, mu_s, z_ground, rayleigh, mie, mie_albedo, h_r, h_m))
    return m.select(m.less(0.0, mu_s), t, 0.0)


def flat_earth_error(distance, scale_height, earth_radius=EARTH_RADIUS):
    """How much denser the flat-Earth medium is than the round Earth's at the end of a level ray
    ``distance`` m long (a fraction): the ground falls away by d^2 / (2 R), so the true density there is
    e^{-d^2 / (2 R H)} of the flat one's.  Python floats (a design limit, not a kernel)."""
    return math.expm1(distance * distance / (2.0 * earth_radius * scale_height))


# --- the layer in clear air: aerial perspective ----------------------------------------------------------------

AIR_PANELS = 16          # log-spaced panels of ``air_glow``, cut again where the ray crosses the layer:
AIR_CUTS = (0.0, 0.5, 1.0, 2.0, 3.0, 5.0)   # at its top and this many falloff lengths above it (the top if hard)
AIR_FIRST = 0.1          # the first log-spaced panel end: this many mean free paths at the camera


def air_column_depth(m, z, beta_air, h_air):
    """int_z^inf beta_air e^{-z'/h_air} dz' = beta_air h_air e^{-z/h_air}: the clear air's column depth above height
    z (m above the ground, heights below it count as the ground), beta_air its Rayleigh extinction at the ground
    (1/m, one colour channel), h_air its scale height (m; Dobashi et al. 2002 appendix A.1's rho_r)."""
    return beta_air * h_air * exp_neg(m, m.maximum(z, 0.0) / h_air)


def expint4(m, x):
    """E4(x) = int_0^1 mu^2 e^{-x/mu} dmu = (e^{-x} - x E3(x)) / 3 for x >= 0 (E4(0) = 1/3)."""
    return (exp_neg(m, x) - x * expint3(m, x)) * (1.0 / 3.0)


def rayleigh_sky_source(m, c, vz):
    """The uniform sky's Rayleigh single-scattering source per unit sky radiance and unit scattering coefficient
    (1, dimensionless: the radiance scattered towards -v per unit optical depth of air, over L_sky) at a point under
    a column depth c of the layer, for a view direction of z-component vz, ground black:
    int_upper p_R(v.w) e^{-c/mu} dw = 2 pi int_0^1 pbar_R(mu) e^{-c/mu} dmu, the Rayleigh phase averaged over the
    ring at mu being 3 (1 + <(v.w)^2>) / (16 pi) with <(v.w)^2> = mu^2 vz^2 + (1 - mu^2)(1 - vz^2) / 2, so
    = (3 / 8) ((1 + s / 2) E2(c) + (vz^2 - s / 2) E4(c)), s = 1 - vz^2 (``expint2``, ``expint4``)."""
    s = 1.0 - vz * vz
    return (3.0 / 8.0) * ((1.0 + 0.5 * s) * expint2(m, c) + (vz * vz - 0.5 * s) * expint4(m, c))


def _insert_sorted(m, ends, x):
    """The sorted list ``ends`` with x inserted in its place (min and max only)."""
    out = [m.minimum(ends[0], x)]
    out += [m.maximum(ends[i - 1], m.minimum(ends[i], x)) for i in range(1, len(ends))]
    return out + [m.maximum(ends[-1], x)]


def _panel(m, d_a, d_b):
    """int over a panel of e^{-Phi} per unit of a depth in which Phi is linear: e^{-min} phi1(|Phi_b - Phi_a|)."""
    return exp_neg(m, m.minimum(d_a, d_b)) * phi1(m, m.abs(d_b - d_a))


def _air_point(m, pz, vz, t, inv_mu, beta0, h0, H, h_air):
    """``air_glow``'s channel-free quantities at the panel end t: the layer's and the air's (per unit ground extinction)
    optical depths from the camera and their column depths above the point (the air's per unit ground extinction)."""
    z = pz + vz * t
    c_l = column_depth(m, z, beta0, h0, H)
    return (optical_depth(m, pz, vz, t, beta0, h0, H), exponential_depth(m, pz, vz, t, 1.0, 0.0, h_air), c_l,
            air_column_depth(m, z, 1.0, h_air))


def _air_point_hard(m, pz, vz, t, inv_mu, beta0, h0, h_air):
    return _air_point(m, pz, vz, t, inv_mu, beta0, h0, 0.0, h_air)


RATIO_NODES = 6          # Gauss-Legendre sky elevations of ``air_glow``'s layer sky source


def _scaled_source(m, c, vz, rings=None):
    """A sky source times e^{c} (smooth: the panels take e^{-c} with the exponent): the layer's,
    sum_k w_k e^{-c/mu_k} over ``rings`` ((mu_k, w_k): the sky's elevations and weights, the ring-averaged phase
    in them), else the air's Rayleigh source (``rayleigh_sky_source``)."""
    cap = m.minimum(c, EXP_CLAMP)
    if rings is None:
        source = rayleigh_sky_source(m, c, vz)
    else:
        source = 0.0
        for mu, w in rings:
            source = source + w * exp_neg(m, c * (1.0 / mu))
    return source * m.exp(cap)


def layer_sky_rings(m, vz, g, nodes=RATIO_NODES):
    """((mu_k, w_k)): the layer's sky source per unit sky radiance is sum_k w_k e^{-C / mu_k}, w_k the
    Gauss-Legendre weight times 2 pi times the Henyey-Greenstein phase averaged over the ring at mu_k
    (``hg_ring_mean``; 1/2 for isotropic scattering)."""
    xs, ws = gauss_legendre01(nodes)
    return tuple((mu, w * ((2.0 * math.pi) * hg_ring_mean(m, g, mu, vz) if g else 0.5)) for mu, w in zip(xs, ws))


def _air_channel_point(m, b, c_l, c_a, vz, *weights):
    """One channel's quantities at a panel end: the total column C = C_l + b C_a (capped at EXP_CLAMP) and the two
    sky sources over e^{-C} (the layer's, ``weights`` of ``layer_sky_rings`` at its nodes, and the air's)."""
    c = c_l + b * c_a
    rings = tuple(zip(gauss_legendre01(len(weights))[0], weights))
    return m.minimum(c, EXP_CLAMP), _scaled_source(m, c, None, rings), _scaled_source(m, c, vz)


def _air_panel(m, b, inv_mu, la, aa, ca_l, ca_a, xa, ia, ra, lb, ab, cb_l, cb_a, xb, ib, rb):
    """One panel's share of ``air_glow``'s integrals for one channel of air extinction b (1/m at the ground), from
    its ends' depths (layer la, air aa per unit b), columns (ca_l, ca_a), capped total columns (xa) and scaled sky
    sources (isotropic ia, Rayleigh ra): (sun_l, sun_a, sky_a, sky_l)."""
    cam_a, cam_b = la + b * aa, lb + b * ab
    f_sun = _panel(m, (ca_l + b * ca_a) * inv_mu + cam_a, (cb_l + b * cb_a) * inv_mu + cam_b)
    f_sky = _panel(m, xa + cam_a, xb + cam_b)
    d_air, d_layer = b * (ab - aa), lb - la
    return (d_layer * f_sun, d_air * f_sun, (d_air * (0.5 * (ra + rb))) * f_sky, (d_layer * (0.5 * (ia + ib))) * f_sky)


def _layer_sky_panel(m, la, ca, lb, cb, *weights):
    """One panel of the layer's sky glow without air (``air_glow``'s ratio's denominator), from its ends' layer
    depths and columns and the sky's ring weights (``layer_sky_rings``)."""
    rings = tuple(zip(gauss_legendre01(len(weights))[0], weights))
    ia, ib = _scaled_source(m, ca, None, rings), _scaled_source(m, cb, None, rings)
    return ((lb - la) * (0.5 * (ia + ib))) * _panel(m, m.minimum(ca, EXP_CLAMP) + la, m.minimum(cb, EXP_CLAMP) + lb)


def air_glow(m, pz, vz, length, mu_s, beta0, h0, H, air, h_air, g=0.0):
    """Aerial perspective: a camera segment's single-scattering integrals through the fog layer and the clear air,
    per colour channel of ``air`` (the air's Rayleigh extinction at the ground per channel, 1/m): Dobashi et al.
    2002 Eq. 11 with two species, the sun and the sky reaching each point through both (flat Earth),

        sun_l = int beta_l e^{-Psi},  sun_a = int beta_a e^{-Psi},  Psi(t) = (C_l + C_a)(z(t)) / mu_s + tau_l(t)
                                                                           + tau_a(t),
        sky_a = int beta_a S_R(C(z(t)), v_z) e^{-tau_l(t) - tau_a(t)} dt   (``rayleigh_sky_source``),

    and ``sky_ratio``, the air's share of the layer's sky glow: the layer's sky glow with the air (its source under
    C_l + C_a, with the Henyey-Greenstein g's ring means at RATIO_NODES elevations, ``layer_sky_rings``: a forward
    scattering haze sees the sky near the horizon, through long paths of air), dimmed along the segment by both,
    over the same without it; both by the same panels (their errors cancel: 1 at zero air), the latter's rest
    beyond them exact (``sky_airlight``); 1 where the segment meets no layer.  The caller applies it to the layer's
    exact sky glow (any g).  Returns [(sun_l, sun_a, sky_a, sky_ratio)] per channel.

    Quadrature: panels whose ends are AIR_PANELS + 1 log-spaced distances from AIR_FIRST mean free paths at the
    camera to the integrated length, with the crossings of the heights AIR_CUTS falloff lengths above the layer's
    top inserted (the top's alone for a hard top); on each panel the exponent is taken linear in each species'
    optical depth (exact where both are uniform, and for the layer alone: Psi is linear in tau_l without air) and
    a sky source as e^{-C} (with the exponent) times a linear factor.  The integrated length stops where the air
    alone has dimmed the ray by e^{-HAZE_DEPTH}, or HAZE_HEIGHTS air scale heights above the camera (of the air's
    mean channel).  Channel-free quantities are computed once per panel end (node groups: ``_air_point``), the
    channels' per end and per panel (``_air_channel_point``, ``_air_panel``).  Measured against scipy in
    docs/measurements/2026-11-27-air.md."""
    inv_mu = 1.0 / m.maximum(mu_s, MIN_MU)
    air = tuple(air)
    a0 = (air[0] + air[1] + air[2]) * (1.0 / 3.0) * exp_neg(m, m.maximum(pz, 0.0) / h_air)
    up = m.maximum(vz, 0.0)
    t_depth = HAZE_DEPTH / m.maximum(a0 - HAZE_DEPTH * up / h_air, 1e-30)
    t_height = (HAZE_HEIGHTS * h_air) / m.maximum(up, 1e-30)
    t_end = m.minimum(length, m.minimum(t_depth, t_height))
    flat = m.less(m.abs(vz), MIN_SPAN)
    inv_vz = 1.0 / m.select(flat, MIN_SPAN, vz)

    def crossing(h):   # the distance along the ray to height h, in [0, t_end] (t_end for a level ray)
        return m.select(flat, t_end, m.minimum(m.maximum((h - pz) * inv_vz, 0.0), t_end))
    hard = isinstance(H, (int, float)) and H < MIN_FALLOFF
    first = m.maximum(m.minimum(AIR_FIRST / m.maximum(extinction(m, pz, beta0, h0, H) + a0, 1e-30), t_end), 1e-6)
    ratio = 1.0 + t_end / first
    ends = [0.0 * t_end] + [first * (m.power(ratio, j / AIR_PANELS) - 1.0) for j in range(1, AIR_PANELS)] + [t_end]
    for cut in AIR_CUTS[:1] if hard else AIR_CUTS:
        ends = _insert_sorted(m, ends, crossing(h0 + cut * H))
    hard_tag = "hard" if hard else "falloff"
    points = [m.group(f"daylight air point {hard_tag}", _air_point_hard if hard else _air_point, pz, vz, t, inv_mu,
                      beta0, h0, *(() if hard else (H,)), h_air) for t in ends]
    weights = tuple(w for _, w in layer_sky_rings(m, vz, g))
    dry = 0.0
    for pa, pb in zip(points[:-1], points[1:]):
        dry = dry + m.group("daylight air layer sky panel", _layer_sky_panel, pa[0], pa[2], pb[0], pb[2], *weights)
    # beyond the panels' end (where the air has dimmed the ray by e^{-HAZE_DEPTH}) the layer's own glow goes on
    z_end = pz + vz * t_end
    rest = m.maximum(m.minimum(length, UNBOUNDED) - t_end, 0.0)
    tag = f"g {round(float(g) * 10000):+d}e-4"
    dry = dry + exp_neg(m, points[-1][0]) * m.group(
        f"daylight sky {tag}", lambda mm, *a: sky_airlight(mm, *a, albedo=1.0, g=g), z_end, vz, rest, beta0, h0, H)
    has_layer = m.less(1e-30, dry)
    out = []
    for b in air:
        chan = [m.group("daylight air channel point", _air_channel_point, b, p[2], p[3], vz, *weights) for p in points]
        sun_l = sun_a = sky_a = sky_l = 0.0
        for (pa, ca), (pb, cb) in zip(zip(points[:-1], chan[:-1]), zip(points[1:], chan[1:])):
            d = m.group("daylight air panel", _air_panel, b, inv_mu, *pa[:4], *ca, *pb[:4], *cb)
            sun_l, sun_a, sky_a, sky_l = sun_l + d[0], sun_a + d[1], sky_a + d[2], sky_l + d[3]
        out.append((sun_l, sun_a, sky_a, m.select(has_layer, sky_l / m.maximum(dry, 1e-30), 1.0)))
    return out
