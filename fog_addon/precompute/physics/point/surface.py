"""Surface radiance due to single-scattered airlight: Sun, Ramamoorthi, Narasimhan, Nayar 2005, section 4.

Sun et al. split the light a surface point p reflects into the direct term
(Eq. 14) and the reflected airlight L_{p,a} (Eq. 15): the airlight of Eq. 12
(ray from p to infinity, D_vp = inf, light at distance D_sp) integrated against
the BRDF over the incident directions.  In our polar formulation (model.py)
that airlight is, per unit intensity, with T = beta D_sp and gamma' the angle
between the incident ray and the direction to the light,

    L_a(gamma') = beta^2 / (2 pi) * exp(-T) * K_inf(T sin gamma', T (1 - cos gamma'))

(``airlight.k_inf``).  With the energy-normalised Phong lobe
f_r cos(theta_i) = rho (n + 1) / (2 pi) max(0, cos theta_i)^n (n = 1: Lambert,
rho / pi cos theta_i), Eq. 15 becomes

    L_{p,a} = rho * beta exp(-T) / (2 pi D_sp) * M_n(T, theta)                        [1/m^2 per W/sr]
    M_n(T, theta) = T (n + 1) / (2 pi) int_{S^2} K_inf(T sin gamma', T (1 - cos gamma')) max(0, cos theta_i)^n d omega_i

theta is the angle between the lobe axis and the direction to the light: the
normal for the diffuse term (Sun's theta_s), the mirror direction of the view
vector for the glossy one (Sun's theta'_s, Ramamoorthi-Hanrahan
reparameterisation).  It covers [0, pi]: a surface facing away from the light
still receives fog light.  Sun's G_n (Eq. 16) is G_n = 2 pi / (n + 1) e^{-T} M_n,
which turns the above into Eq. 17-18 (k_d = rho / pi for n = 1).  M_n is
dimensionless and O(1): finite as T -> 0 (K_inf -> atan2(u, a) / u, so
T K_inf -> (pi - gamma') / (2 sin gamma') and

    M_n(0, theta) = (n + 1) / (2 pi) int_0^pi (pi - gamma') / 2 * Phi_n(theta, gamma') d gamma',

e.g. M_1(0, 0) = pi/2 + 1, M_1(0, pi) = pi/2 - 1), ~ ln T / T for T >> 1, and
~ sqrt(n) near theta = 0 for large n (the 1/gamma' glow around the light seen
through a narrow lobe).

Quadrature (``surface_m``), in coordinates centred on the light direction
(gamma' polar, phi azimuth), d omega = sin gamma' d gamma' d phi:

    M_n = (n + 1) / (2 pi) int_0^pi [T K_inf sin gamma'] Phi_n(theta, gamma') d gamma'
    Phi_n(theta, gamma') = int_0^{2 pi} max(0, cos theta cos gamma' + sin theta sin gamma' cos phi)^n d phi.

The bracket is finite at gamma' = 0 (-> pi/2, the 1/gamma' singularity of the
airlight cancels against sin gamma') but has gamma' ln gamma' terms there and a
feature at gamma' ~ 1/T, so gamma' uses geometrically graded Gauss-Legendre
panels up to 0.1 and uniform ones (width 1.5/sqrt(n_max)) beyond; the bracket
is computed once per T and reused for every theta and n.  Phi_n is taken by
Gauss-Legendre on [0, phi_max] (where the base is positive; the base is analytic
there), cut at 8 lobe widths for large n.  Against a 4x finer quadrature the
relative error is below 2e-5 (n = 1, where Phi_1 has (gamma' - c)^{3/2} kinks)
and 1e-7 (n >= 2); against scipy quadrature of Eq. 15 / Eq. 5 (tests) below 7e-6.

The table (``bake_surface_table``, layout ``tables.SURFACE``) stores ln M_n for
n = 2^(k/4), k = 0..40, on the grid of ``tables.surface_x`` / ``tables.surface_y``;
bilinear interpolation of the logarithm keeps the error relative over the 4
decades M_n spans.  Shaders interpolate ln M linearly in the level 4 log2 n
between two levels (``surface_factor``).  Measured against a finer quadrature at
random off-grid points, T in [0, 20], theta in [0, pi]: max 0.37 % on the levels,
0.43 % halfway between levels (p99 0.33 %; T <= 10: max 0.37 %); T in [20, 60]:
0.55 %.  Beyond T = 60 the lookup clamps (M too large by ~T/60, times exp(-T) < 1e-26).
"""
import math

import numpy as np

from ...core import table_cache, tables
from .airlight import k_inf
from ...core.ops import NumpyOps

MIN_DISTANCE = 1e-6   # m; light-surface distances are clamped here (the scattered light grows as 1/D_sp)
INV_2PI = 1.0 / (2.0 * math.pi)

# Quadrature settings of the bake (see module docstring; measured in tests/test_surface.py).
_GAMMA_H = 1.5 / math.sqrt(1024.0)   # uniform gamma' panel width (rad) for gamma' > _GAMMA_G1
_GAMMA_G0 = 1e-6                     # first graded gamma' panel edge (rad)
_GAMMA_G1 = 0.1                      # end of the graded panels (rad)
_GAMMA_GRADED = 10                   # number of graded panels
_GAMMA_ORDER = 8                     # Gauss-Legendre points per gamma' panel
_K_PANELS = 16                       # k_inf panels (rel. error 1e-5, see airlight.k_inf)
_PHI_NODES = 16                      # Gauss-Legendre points for Phi_n
_PHI_CUT = 8.0                       # Phi_n integrand cut at this many lobe widths
_LOBE_FLOOR = 1e-12                  # (A + B)^n below this: the (theta, gamma') pair contributes nothing


# --------------------------------------------------------------------------------------------
# Quadrature of M_n (bake and references)
# --------------------------------------------------------------------------------------------

def gamma_nodes(h=_GAMMA_H, g0=_GAMMA_G0, g1=_GAMMA_G1, graded=_GAMMA_GRADED, order=_GAMMA_ORDER):
    """Composite Gauss-Legendre nodes and weights for gamma' in [0, pi] (rad).

    Panels [0, g0], ``graded`` geometric panels g0 -> g1, uniform panels of width <= h to pi.
    """
    geo = g0 * (g1 / g0) ** np.linspace(0.0, 1.0, graded + 1)
    nu = max(1, int(math.ceil((math.pi - g1) / h)))
    edges = np.concatenate([[0.0], geo, np.linspace(g1, math.pi, nu + 1)[1:]])
    x, w = np.polynomial.legendre.leggauss(order)
    lo, hi = edges[:-1, None], edges[1:, None]
    return (0.5 * (hi - lo) * x + 0.5 * (hi + lo)).ravel(), (0.5 * (hi - lo) * w).ravel()


def radiance_profile(t, gamma, panels=_K_PANELS, g=0.0):
    """T K_inf(T sin gamma', T (1 - cos gamma')) sin gamma', shape (len t, len gamma) (dimensionless).

    The airlight reaching p from direction gamma' is beta/(2 pi D_sp) exp(-T) times
    this / sin gamma'.  T = 0 gives the exact limit (pi - gamma') / 2; with Henyey-Greenstein
    anisotropy g (K_inf weighted by the phase function, ``airlight.k_inf``) T = 0 is taken at T = 1e-9.
    """
    t = np.asarray(t, float).reshape(-1, 1)
    s = np.sin(gamma)
    c1 = 2.0 * np.sin(0.5 * gamma) ** 2          # 1 - cos gamma' without cancellation
    ts = np.where(t > 0.0, t, 1.0 if not g else 1e-9)
    # a few T at a time: k_inf's (T, gamma', panel, node) temporaries then stay in cache
    out = np.concatenate([k_inf(ts[i:i + 4] * s, ts[i:i + 4] * c1, panels, g) for i in range(0, len(ts), 4)])
    out *= ts * s
    return np.where((t > 0.0) | bool(g), out, 0.5 * (math.pi - gamma))


def phi_integral(theta, gamma, n, nodes=_PHI_NODES, cut=_PHI_CUT):
    """Phi_n(theta, gamma') = int_0^{2 pi} max(0, cos th cos g + sin th sin g cos phi)^n d phi (rad).

    Shape (len theta, len gamma).  Pairs whose largest base cos(theta - gamma')
    has n-th power below 1e-12 are 0.
    """
    theta = np.asarray(theta, float).reshape(-1, 1)
    a = np.cos(theta) * np.cos(gamma)
    b = np.sin(theta) * np.sin(gamma)
    top = a + b                                   # cos(theta - gamma'), the base at phi = 0
    out = np.zeros(np.broadcast(a, b).shape)
    live = top > _LOBE_FLOOR ** (1.0 / n)
    a, b, top = a[live], b[live], top[live]
    bs = np.maximum(b, 1e-300)
    phimax = np.arccos(np.clip(-a / bs, -1.0, 1.0))   # pi where the whole ring is lit
    width = np.sqrt(top / (n * bs))                  # (A + B cos phi)^n ~ top^n exp(-phi^2 / (2 width^2))
    phic = np.minimum(phimax, cut * width)
    x, w = np.polynomial.legendre.leggauss(nodes)
    base = np.cos(phic[:, None] * (0.5 * (x + 1.0)))
    base *= b[:, None]
    base += a[:, None]
    np.maximum(base, 0.0, out=base)
    if n != 1.0:
        np.power(base, n, out=base)
    out[live] = phic * (base @ w)   # 2 (symmetry) * 0.5 (GL on [0, 1]) = 1
    return out


def surface_m(t, theta, n, h=None, profile=None, gamma=None):
    """M_n(T, theta) by quadrature, shape (len t, len theta): the outer product of the two grids.

    t: optical light-surface distances T = beta D_sp (>= 0); theta: lobe-axis to
    light angles (rad, [0, pi]); n: Phong exponent (>= 1).  ``h`` overrides the
    gamma' panel width (default: the bake's).  ``profile``/``gamma``: a
    precomputed (radiance_profile * weights, nodes) pair to reuse across calls.
    """
    if profile is None:
        g, wg = gamma_nodes(_GAMMA_H if h is None else h)
        profile = radiance_profile(t, g) * wg
    else:
        g = gamma
    phi = phi_integral(theta, g, n)
    return (n + 1.0) * INV_2PI * (profile @ phi.T)


def surface_m_t0(theta, n, h=None):
    """M_n(0, theta): the T -> 0 limit (no extinction), shape (len theta,)."""
    return surface_m([0.0], theta, n, h=h)[0]


def bake_surface_table(spec=tables.SURFACE):
    """ln M_n(T, theta) for every exponent of tables.PHONG_EXPONENTS, float32, layout of tables.SURFACE,
    for the anisotropy ``spec.g`` (``tables.anisotropic``).

    Level k occupies rows [k R, (k + 1) R), R = tables.SURFACE_THETA; entry
    [k R + j, i] holds ln M at T = surface_t(i / (W - 1)), theta = surface_theta(j / (R - 1), k).
    """
    rows = tables.SURFACE_THETA
    assert spec.height == rows * len(tables.PHONG_EXPONENTS)
    t = tables.surface_t(np.linspace(0.0, 1.0, spec.width))
    g, wg = gamma_nodes()
    profile = radiance_profile(t, g, g=spec.g) * wg
    y = np.linspace(0.0, 1.0, rows)
    out = np.empty((spec.height, spec.width), np.float32)
    for k, n in enumerate(tables.PHONG_EXPONENTS):
        theta = tables.surface_theta(y, k)
        m = surface_m(t, theta, n, profile=profile, gamma=g)
        out[k * rows:(k + 1) * rows] = np.log(m).T
    return out


# --------------------------------------------------------------------------------------------
# Per-pixel formulas (written against an ops namespace m, see ops.py)
# --------------------------------------------------------------------------------------------

_LEVELS = len(tables.PHONG_EXPONENTS)
_ROW_EDGE = 0.01 / (tables.SURFACE_THETA - 1)   # keeps bilinear taps inside a level's band (float32 safe)
_LOG_EPS = 1.0 / 1024.0


def exponent_level(n):
    """Table level coordinate of the Phong exponent n (Python float): 4 log2 n, clamped to the table."""
    x = tables.PHONG_LEVELS_PER_OCTAVE * math.log2(max(float(n), 1e-30))
    return min(max(x, 0.0), _LEVELS - 1.0)


def log2_approx(m, x):
    """log2 x for x in [1, 2^10] from two powers (no log among the ops): sinh(e ln x) / (e ln 2), e = 2^-10.

    Truncation e^2 (ln x)^3 / 6 < 6e-5, float32 rounding ~6e-5 (absolute, in ln x).
    """
    return (m.power(x, _LOG_EPS) - m.power(x, -_LOG_EPS)) * (0.5 / (_LOG_EPS * math.log(2.0)))


def surface_log_m(m, t, theta, level, g=0.0):
    """ln M of one table level at optical distance t and lobe angle theta (rad): one bilinear lookup.

    ``level``: Python int or an ``m`` value holding an integer in [0, len(PHONG_EXPONENTS) - 1].
    The band of the level is addressed through Y of the whole image; Y within the band is kept
    0.01 rows away from its edges so that the second tap never reads the next level.
    """
    rows = tables.SURFACE_THETA
    y = m.minimum(m.maximum(tables.surface_y(m, theta, level), _ROW_EDGE), 1.0 - _ROW_EDGE)
    y_image = (level * float(rows) + y * float(rows - 1)) * (1.0 / (tables.SURFACE.height - 1))
    return m.table(tables.anisotropic(tables.SURFACE, g), tables.surface_x(m, t), y_image)


def surface_factor(m, t, theta, level, g=0.0):
    """M_n(T, theta) (dimensionless) from the table, ln M interpolated linearly in the level (= 4 log2 n).

    ``level``: a Python float (per-material constant: 1 lookup on a level, else 2)
    or an ``m`` value (always 2 lookups).  Clamped to the table's range.  One exp.
    """
    if not hasattr(level, "__array__") and isinstance(level, (int, float)):
        level = min(max(float(level), 0.0), _LEVELS - 1.0)
        k0 = min(int(math.floor(level)), _LEVELS - 2)
        f = level - k0
        if f < 1e-6:
            return m.exp(surface_log_m(m, t, theta, k0, g))
        if f > 1.0 - 1e-6:
            return m.exp(surface_log_m(m, t, theta, k0 + 1, g))
        return m.exp((1.0 - f) * surface_log_m(m, t, theta, k0, g) + f * surface_log_m(m, t, theta, k0 + 1, g))
    level = m.minimum(m.maximum(level, 0.0), _LEVELS - 1.0)
    k0 = m.minimum(m.floor(level), _LEVELS - 2.0)
    f = level - k0
    a = surface_log_m(m, t, theta, k0, g)
    b = surface_log_m(m, t, theta, k0 + 1.0, g)
    return m.exp(a + f * (b - a))


def surface_scatter(m, beta, d_sp, cos_theta, level, g=0.0):
    """Reflected airlight per unit intensity and unit albedo, 1/m^2: Sun et al. 2005 Eq. 15 (Eq. 17-18).

    L_{p,a} / (I0 rho) = beta exp(-beta D_sp) / (2 pi D_sp) * M_n(beta D_sp, theta).

    beta: extinction (= scattering) coefficient, 1/m; d_sp: light-surface
    distance, m (clamped to MIN_DISTANCE); cos_theta: cosine of the angle between
    the lobe axis and the direction to the light (normal for the diffuse term;
    mirrored view direction for the glossy one, Sun's theta'_s); level: table
    level of the Phong exponent, 4 log2 n (0.0 = Lambert, see ``exponent_level``
    / ``principled_to_phong``), Python float or ``m`` value.  Multiply by I0 (W/sr)
    and the albedo (rho_d or rho_s) for W/(m^2 sr) leaving the surface, then by
    exp(-beta D_vp) towards the viewer (Eq. 19).  beta = 0 gives exactly 0.  g: Henyey-Greenstein
    anisotropy (a Python float): the airlight inside Eq. 15 weighted by the phase function, from the
    table baked for g.
    """
    return surface_scatter_angle(m, beta, d_sp, angle_from_cos(m, cos_theta), level, g)


def surface_scatter_angle(m, beta, d_sp, theta, level, g=0.0):
    """:func:`surface_scatter` with the angle theta (rad, [0, pi]) instead of its cosine."""
    d = m.maximum(d_sp, MIN_DISTANCE)
    t = beta * d
    return (beta * INV_2PI) * m.exp(-t) / d * surface_factor(m, t, theta, level, g)


def lobe_angle(m, axis, to_light):
    """Angle (rad, [0, pi]) between two vectors (any lengths): atan2(|a x b|, a . b), accurate near 0 and pi."""
    return m.atan2(m.length(m.cross(axis, to_light)), m.dot(axis, to_light))


def angle_from_cos(m, c):
    """acos(c) via atan2 (no acos among the ops), c outside [-1, 1] clamped; ~3e-4 rad resolution in float32."""
    return m.atan2(m.sqrt(1.0 - c * c), c)


def phong_level(m, roughness):
    """Table level (4 log2 n) of the Phong exponent of ``phong_exponent_from_roughness``, against ``m``."""
    alpha = m.maximum(roughness * roughness, 1e-6)                # GGX alpha = roughness^2
    n = 0.5 * (1.0 / (alpha * alpha) - 1.0)
    n = m.minimum(m.maximum(n, tables.PHONG_EXPONENTS[0]), tables.PHONG_EXPONENTS[-1])
    return tables.PHONG_LEVELS_PER_OCTAVE * log2_approx(m, n)


def bake_specular_albedo(spec=tables.SPECULAR_ALBEDO):
    """A(mu, r) and B(mu, r) of the split sum E = F0 A + F90 B (Karis 2013): the directional albedo of a
    GGX lobe (alpha = r^2, Walter et al. 2007) with Smith's height-correlated masking-shadowing (Heitz 2014)
    and Schlick's Fresnel F0 + (F90 - F0) (1 - v.h)^5, seen at mu = cos(view angle); and E with the
    Fresnel equations of a dielectric of IOR tables.SPECULAR_IOR.  Layout of tables.SPECULAR_ALBEDO (A, B
    and E in three slices of rows), float32.

    Quadrature over the half vector h drawn from D cos(theta_h): u -> cos^2 theta_h = (1 - u) / (1 + (a^2 - 1) u)
    by 96-point Gauss-Legendre in u, 64 midpoints in azimuth (the integrand depends on its cosine only:
    the 32 in [0, pi] give the same mean); the integrand f cos(theta_l) / pdf is then G (v.h) /
    (mu cos theta_h), smooth however narrow the lobe."""
    mu = np.maximum(np.linspace(0.0, 1.0, spec.width), 1e-3)[None, :, None, None]
    r = np.linspace(0.0, 1.0, tables.SPECULAR_ROUGHNESS)[:, None, None, None]
    a2 = np.maximum(r * r, 1e-3) ** 2
    x, w = np.polynomial.legendre.leggauss(96)
    u, wu = (0.5 * (x + 1.0))[None, None, :, None], (0.5 * w)[None, None, :, None]
    phi = ((np.arange(32) + 0.5) * (math.pi / 32))[None, None, None, :]
    cos_h = np.sqrt((1.0 - u) / (1.0 + (a2 - 1.0) * u))
    sin_h = np.sqrt(np.maximum(1.0 - cos_h * cos_h, 0.0))
    sin_v = np.sqrt(1.0 - mu * mu)
    v_h = sin_v * sin_h * np.cos(phi) + mu * cos_h
    cos_l = 2.0 * v_h * cos_h - mu

    def smith_lambda(c):
        c2 = np.maximum(c * c, 1e-12)
        return 0.5 * (np.sqrt(1.0 + a2 * (1.0 - c2) / c2) - 1.0)

    ok = (cos_l > 0.0) & (v_h > 0.0)
    weight = np.where(ok, v_h / (mu * cos_h * (1.0 + smith_lambda(mu) + smith_lambda(np.maximum(cos_l, 1e-6)))), 0.0)
    fresnel = (1.0 - np.clip(v_h, 0.0, 1.0)) ** 5
    mean = lambda f: np.sum(np.mean(f, axis=-1) * wu[..., 0], axis=-1)   # noqa: E731  (u by GL, phi uniform)
    return np.concatenate([mean(weight * (1.0 - fresnel)), mean(weight * fresnel),
                           mean(weight * dielectric_fresnel(v_h, tables.SPECULAR_IOR))]).astype(np.float32)


def dielectric_fresnel(c, ior):
    """Unpolarised reflectance of a dielectric of relative index ``ior`` at the cosine c of incidence (the
    Fresnel equations, numpy)."""
    c = np.clip(c, 0.0, 1.0)
    g = np.sqrt(np.maximum(ior * ior - 1.0 + c * c, 0.0))
    a, b = (g - c) / (g + c), (c * (g + c) - 1.0) / (c * (g - c) + 1.0)
    return 0.5 * a * a * (1.0 + b * b)


def _specular_coords(m, roughness, cos_view):
    spec, rows = tables.SPECULAR_ALBEDO, tables.SPECULAR_ROUGHNESS
    return m.clamp01(cos_view), m.clamp01(roughness) * ((rows - 1.0) / (spec.height - 1.0)), rows / (spec.height - 1.0)


def metal_albedo(m, f0, roughness, cos_view):
    """Directional albedo of a metal's specular layer: F0 A + B from ``bake_specular_albedo`` (f0: RGB)."""
    x, y, step = _specular_coords(m, roughness, cos_view)
    bias = m.table(tables.SPECULAR_ALBEDO, x, y + step)
    return m.scale(f0, m.table(tables.SPECULAR_ALBEDO, x, y)) + m.combine(bias, bias, bias)


def dielectric_albedo(m, f0, roughness, cos_view):
    """Directional albedo of a dielectric specular layer of normal reflectance f0 (scalar): the table's
    Fresnel-equation albedo of IOR tables.SPECULAR_IOR scaled by f0 over its F0 (Blender's IOR Level
    scales F0 the same way), 0 for f0 = 0."""
    x, y, step = _specular_coords(m, roughness, cos_view)
    f0_table = ((tables.SPECULAR_IOR - 1.0) / (tables.SPECULAR_IOR + 1.0)) ** 2
    return m.minimum(m.table(tables.SPECULAR_ALBEDO, x, y + 2.0 * step) * (f0 * (1.0 / f0_table)), 1.0)


SINGULAR_ROUGHNESS = 1e-7 ** 0.25   # ~0.0178: Cycles reflects a GGX lobe of alpha_x alpha_y = roughness^4 <= 1e-7
#                                    as a mirror (its label singular: bsdf.h), so its reflected ray is a segment


def sharp_share(m, roughness):
    """1 where Cycles reflects a Principled BSDF's specular layer of ``roughness`` as a mirror (SINGULAR_ROUGHNESS),
    else 0.  There the fog it reflects is the glow along its mirrored ray, exact (``nodes/glass_tails.py``'s tails),
    not the sharpest Phong lobe's blur of it (n = 1024: about 2 degrees)."""
    return 1.0 - m.less(SINGULAR_ROUGHNESS, roughness)


def principled_to_phong(m, base_color, metallic, roughness, specular_ior_level, cos_view, ior=1.5, transmission=0.0):
    """(rho_d, rho_s, level) of a Principled BSDF for the reflected airlight, against ``m``.

    base_color: vector (RGB); metallic, roughness, specular_ior_level: scalars; cos_view: the cosine
    between the shading normal and the direction to the viewer; ior: Python float (Blender's default
    1.5).  rho_d, rho_s: RGB albedos of the diffuse (n = 1 about the normal) and glossy (about the
    mirrored view vector) lobes; level: table level of the glossy exponent (``phong_level``).

    The glossy lobe of Eq. 17-18 is normalised to 1, so its albedo is the specular layer's directional
    albedo seen from the viewer (``dielectric_albedo``, ``metal_albedo``: the Phong lobe carries the
    prefiltered fog light, E(mu) the reflectance: Karis 2013).  It rises from F0 at normal incidence
    to several times that at grazing angles (roughness 0.45: 0.04 to 0.2 at mu = 0.1), where wet roads
    and floors are seen.

    * dielectric F0 = ((ior - 1) / (ior + 1))^2 * 2 * specular_ior_level
      (Blender 4+: IOR Level 0.5 keeps the IOR's F0, 0.04 at IOR 1.5);
      metal F0 = base colour; F0 = mix(F0_dielectric, base_color, metallic).
    * rho_d = base_color (1 - metallic) (1 - transmission) (1 - E_dielectric(mu)): the diffuse base receives
      what the dielectric specular layer does not reflect, where the surface does not let it through (Blender's
      Principled BSDF mixes its transmission lobe in for the diffuse one by Transmission Weight).
    * level from roughness r: GGX alpha = r^2 ~ Blinn-Phong exponent 2/alpha^2 - 2 about the half vector
      (Walter et al. 2007); the reflected-direction lobe is twice as wide in angle, so
      n = (1/alpha^2 - 1) / 2 (see ``phong_exponent_from_roughness``).

    Ignored: coat, sheen, subsurface, diffuse roughness, anisotropy; what is transmitted is the segments' past the
    surface (``nodes/glass_tails.py``).
    """
    f0_d = m.minimum(specular_ior_level * (2.0 * ((ior - 1.0) / (ior + 1.0)) ** 2), 1.0)
    e_d = dielectric_albedo(m, f0_d, roughness, cos_view)
    through = 1.0 if isinstance(transmission, (int, float)) and transmission == 0.0 else 1.0 - transmission
    rho_d = m.scale(base_color, (1.0 - metallic) * (1.0 - e_d) * through)
    grey = (1.0 - metallic) * e_d
    rho_s = m.scale(metal_albedo(m, base_color, roughness, cos_view), metallic) + m.combine(grey, grey, grey)
    return rho_d, rho_s, phong_level(m, roughness)


# --------------------------------------------------------------------------------------------
# numpy convenience and material mapping
# --------------------------------------------------------------------------------------------

_TABLE_CACHE = {}


def surface_table(g=0.0):
    """The baked table for anisotropy g (cached per process, and on disk: ``table_cache.cached_bake``)."""
    spec = tables.anisotropic(tables.SURFACE, g)
    if spec.name not in _TABLE_CACHE:
        _TABLE_CACHE[spec.name] = table_cache.cached_bake(spec, lambda: bake_surface_table(spec))
    return _TABLE_CACHE[spec.name]


def surface_radiance_scattered(beta, d_sp, theta, n, rho=1.0, table=None):
    """Reflected airlight L_{p,a} per unit intensity, 1/m^2, exactly as the shaders compute it (NumpyOps).

    beta (1/m), d_sp (m), theta (rad, the shaders get cos theta), rho (albedo) broadcast as
    arrays; n: Phong exponent, a Python float (per-material level) or an array (per-pixel level).
    """
    table = surface_table() if table is None else table
    m = NumpyOps({tables.SURFACE.name: table})
    beta, d_sp, theta = np.broadcast_arrays(*(np.asarray(v, float) for v in (beta, d_sp, theta)))
    if isinstance(n, (int, float)):
        level = exponent_level(n)
    else:
        n = np.clip(np.asarray(n, float), tables.PHONG_EXPONENTS[0], tables.PHONG_EXPONENTS[-1])
        level = tables.PHONG_LEVELS_PER_OCTAVE * log2_approx(m, n)
    return np.asarray(rho, float) * surface_scatter(m, beta, d_sp, np.cos(theta), level)


def phong_exponent_from_roughness(roughness):
    """Phong exponent n (about the mirror direction) matching a GGX lobe of Blender roughness r.

    GGX alpha = r^2 (Blender's convention).  For small alpha GGX ~ Beckmann ~
    Blinn-Phong with exponent n_h = 2 / alpha^2 - 2 about the half vector
    (Walter et al. 2007).  The reflected-direction lobe is twice as wide in
    angle (theta_r ~ 2 theta_h, so cos^{n_h} theta_h ~ cos^{n_h / 4} theta_r),
    giving n = (1 / alpha^2 - 1) / 2, clamped to the tabulated range [1, 1024]
    (r >= 0.76 gives n = 1; r <= 0.15 gives 1024, a ~2 degree lobe).
    Python float in, Python float out; ``phong_level`` is the same against ``m``.
    """
    alpha = max(float(roughness), 1e-3) ** 2
    n = 0.5 * (1.0 / (alpha * alpha) - 1.0)
    lo, hi = tables.PHONG_EXPONENTS[0], tables.PHONG_EXPONENTS[-1]
    return min(max(n, lo), hi)


def principled_albedos(base_color, metallic=0.0, roughness=0.5, specular_ior_level=0.5, ior=1.5, cos_view=1.0):
    """numpy version of :func:`principled_to_phong`: (rho_d RGB, rho_s RGB, n); arrays broadcast (cos_view
    one per view)."""
    m = NumpyOps({tables.SPECULAR_ALBEDO.name: specular_table()})
    rho_d, rho_s, _ = principled_to_phong(m, np.asarray(base_color, float), np.asarray(metallic, float),
                                          np.asarray(roughness, float), np.asarray(specular_ior_level, float),
                                          np.asarray(cos_view, float), ior)
    n = np.vectorize(phong_exponent_from_roughness, otypes=[float])(roughness)
    return rho_d, rho_s, float(n) if np.ndim(n) == 0 else n


def specular_table():
    """The specular albedo table (cached per process, and on disk: ``table_cache.cached_bake``)."""
    if tables.SPECULAR_ALBEDO.name not in _TABLE_CACHE:
        _TABLE_CACHE[tables.SPECULAR_ALBEDO.name] = table_cache.cached_bake(tables.SPECULAR_ALBEDO,
                                                                            bake_specular_albedo)
    return _TABLE_CACHE[tables.SPECULAR_ALBEDO.name]
