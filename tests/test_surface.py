"""Reflected airlight of Sun et al. 2005 section 4 (Eq. 15-18, Appendix B): quadrature, table, per-pixel formula.

References are independent of ``surface.py``: scipy adaptive quadrature of
Eq. 15 whose airlight is itself scipy quadrature of Sun's Eq. 5 (D_vp = inf),
once in coordinates centred on the light and once in the lobe frame of Sun's
Appendix B; and Sun's Eq. 16-17 with F of Eq. 10 for the Lambertian case.

M_n (dimensionless) is defined in surface.py: L_{p,a} = rho beta exp(-T) / (2 pi D_sp) * M_n(T, theta).
"""
import math
import warnings

import numpy as np
import pytest
from scipy.integrate import quad

from fog_addon.precompute.core import tables
from fog_addon.precompute.model import rungs
from fog_addon.precompute.physics.point import surface
from fog_addon.precompute.core.ops import NumpyOps

# Measured (see surface.py / the report): table + level interpolation <= 0.43 % for T <= 20,
# quadrature of the bake vs scipy <= 2e-6.
TABLE_TOL = 5e-3
QUAD_TOL = 1e-5


@pytest.fixture(scope="module")
def table():
    return surface.surface_table()


@pytest.fixture(scope="module")
def ops(table):
    return NumpyOps({tables.SURFACE.name: table, tables.SPECULAR_ALBEDO.name: surface.specular_table()})


def table_m(ops, t, theta, n):
    """M_n from the table as the shaders read it (per-material level: a Python float)."""
    return float(surface.surface_factor(ops, np.asarray(float(t)), np.asarray(float(theta)),
                                        surface.exponent_level(n)))


# --- independent references --------------------------------------------------------------

def airlight_eq5(cos_g, t_sp, eps=1e-9, g=0.0):
    """exp(T) L_a / (beta^2 I0) of Sun Eq. 5 with D_vp = inf, optical units, by scipy quad (1, dimensionless).

    (1 / 4 pi) int_0^inf exp(-d(t) - t) / d(t)^2 dt, d^2 = T^2 + t^2 - 2 t T cos(gamma'); ``g``: the
    integrand times 4 pi p_HG(theta), theta the scattering angle at t (light -> t -> the surface point).
    """
    tc = max(t_sp * cos_g, 0.0)
    h2 = t_sp * t_sp * max(1.0 - cos_g * cos_g, 0.0)

    def f(t):
        d2 = (t - t_sp * cos_g) ** 2 + h2
        d = math.sqrt(d2)
        w = (1.0 - g * g) / (1.0 + g * g + 2.0 * g * (t - t_sp * cos_g) / d) ** 1.5 if g else 1.0
        return w * math.exp(t_sp - d - t) / d2

    # the integrand is a Lorentzian of half-width h = T sin(gamma') at t = T cos(gamma'):
    # break the range at tc +- h 10^k so that quad resolves it however narrow it is
    h = math.sqrt(h2)
    edges = {0.0, tc, tc + 60.0}
    for k in range(12):
        for e in (tc - h * 10.0 ** k, tc + h * 10.0 ** k):
            if 0.0 < e < tc + 60.0:
                edges.add(e)
    edges = sorted(edges)
    total = sum(quad(f, lo, hi, epsabs=0, epsrel=eps, limit=200)[0] for lo, hi in zip(edges[:-1], edges[1:]))
    return total / (4.0 * math.pi)


def m_ref_light_frame(t_sp, theta, n, eps=1e-8, g=0.0):
    """M_n by Eq. 15 in coordinates centred on the light (gamma', phi): scipy quad, airlight from Eq. 5
    (with the Henyey-Greenstein phase function of anisotropy ``g``)."""
    ct, st = math.cos(theta), math.sin(theta)

    def ring(g):
        a, b = ct * math.cos(g), st * math.sin(g)
        if a + b <= 0.0:
            return 0.0
        phimax = math.pi if a >= b else math.acos(-a / b)
        return 2.0 * quad(lambda p: max(a + b * math.cos(p), 0.0) ** n, 0.0, phimax,
                          epsabs=0, epsrel=1e-10, limit=200)[0]

    def f(g):
        r = ring(g)
        return 0.0 if r == 0.0 else airlight_eq5(math.cos(g), t_sp, g=hg) * math.sin(g) * r

    hg = g
    pts = sorted({x for x in (abs(math.pi / 2 - theta), math.pi / 2 + theta, theta, min(1.0 / t_sp, 1.0))
                  if 0.0 < x < math.pi})
    val = quad(f, 0.0, math.pi, epsabs=0, epsrel=eps, limit=400, points=pts)[0]
    return t_sp * (n + 1.0) * val            # 2 pi T * (n + 1) / (2 pi) * integral


def m_ref_lobe_frame(t_sp, theta, n, eps=1e-7):
    """M_n by Eq. 15 over the hemisphere in the lobe frame (theta_i, phi_i) of Sun's Appendix B (slow)."""
    ct, st = math.cos(theta), math.sin(theta)

    def inner(ti):
        c, s = math.cos(ti), math.sin(ti)
        g = lambda ph: airlight_eq5(c * ct + s * st * math.cos(ph), t_sp, eps=1e-9)
        return 2.0 * c ** n * s * quad(g, 0.0, math.pi, epsabs=0, epsrel=eps, limit=200)[0]

    pts = [theta] if theta < math.pi / 2 else None
    val = quad(inner, 0.0, math.pi / 2, epsabs=0, epsrel=eps, limit=200, points=pts)[0]
    return t_sp * (n + 1.0) * val


# (T, theta, n) -> M_n from m_ref_lobe_frame (2-30 s each where the light is inside the
# hemisphere, so cached here); recomputed with --regen-references, the cheap ones (theta > pi/2) always.
# They agree with m_ref_light_frame and with surface_m to <= 1.2e-6.
LOBE_FRAME = {
    (0.02, 0.0, 1.0): 2.4846714812173225,
    (0.05, 2.5, 1.0): 0.5073241657589753,
    (0.3, 1.2, 1.0): 1.0639709182621693,
    (1.0, 0.5, 1.0): 1.3745394030555729,
    (3.0, 2.0, 1.0): 0.12224960775738103,
    (15.0, math.pi, 2.0): 0.01813574316568166,
    (20.0, 1.0, 4.0): 0.12186556466724473,
    (1.5, 0.7, 6.0): 1.1888049988191949,        # between table levels
    (10.0, 2.8, 8.0): 0.024825706306362074,
    (5.0, 0.2, 16.0): 2.9875868197192514,
    (2.0, 1.2, 64.0): 0.26410474164029807,
    (8.0, 0.3, 100.0): 1.3968631577802804,      # between table levels
}


# --- tests ---------------------------------------------------------------------------------

LIGHT_FRAME_POINTS = [
    (0.01, 0.0, 1.0), (0.5, 0.8, 1.0), (1.0, 1.5, 1.0), (20.0, 1.0, 1.0), (2.0, math.pi, 1.0),
    (0.2, 2.2, 2.0), (3.0, 0.3, 8.0), (12.0, 2.0, 4.0), (1.0, 0.02, 64.0), (6.0, 0.15, 256.0),
    (0.7, 0.6, 11.0), (4.0, 0.05, 1024.0),
]


@pytest.mark.parametrize("t_sp, theta, n", LIGHT_FRAME_POINTS)
def test_m_vs_scipy_eq5_light_frame(t_sp, theta, n, ops):
    """Bake quadrature and table vs scipy quadrature of Eq. 15 / Eq. 5 (light-centred frame)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ref = m_ref_light_frame(t_sp, theta, n)
    quad_m = surface.surface_m([t_sp], [theta], n)[0, 0]
    assert abs(quad_m / ref - 1.0) < QUAD_TOL
    assert abs(table_m(ops, t_sp, theta, n) / ref - 1.0) < TABLE_TOL


@pytest.mark.parametrize("key", sorted(LOBE_FRAME))
def test_m_vs_scipy_lobe_frame(key, ops, regen):
    """Sun's Appendix B frame: the cached values (recomputed if cheap or on --regen-references)."""
    t_sp, theta, n = key
    ref = LOBE_FRAME[key]
    if regen or theta > math.pi / 2:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            fresh = m_ref_lobe_frame(t_sp, theta, n)
        assert abs(fresh / ref - 1.0) < 1e-6, (key, fresh)
    assert abs(surface.surface_m([t_sp], [theta], n)[0, 0] / ref - 1.0) < QUAD_TOL
    assert abs(table_m(ops, t_sp, theta, n) / ref - 1.0) < TABLE_TOL


@pytest.mark.parametrize("beta, d_sp, theta", [(0.05, 20.0, 0.4), (0.3, 4.0, 1.9), (0.02, 3.0, 0.0)])
def test_lambert_equals_sun_eq17(beta, d_sp, theta, table):
    """n = 1 is Lambert: beta^2 I0 k_d G_0 / (2 pi T) of Eq. 17 with G_0 of Eq. 16 (Sun's F, Eq. 10), k_d = rho / pi."""
    rho = 0.7
    t_sp = beta * d_sp
    ct, st = math.cos(theta), math.sin(theta)

    def sun_bracket(g):   # exp(-T cos g) / sin g * [F(A1, pi/2) - F(A1, g/2)], A1 = T sin g
        a1 = t_sp * math.sin(g)
        f = quad(lambda xi: math.exp(-a1 * math.tan(xi)), g / 2, math.pi / 2, epsabs=0, epsrel=1e-10)[0]
        return math.exp(-t_sp * math.cos(g)) * f   # / sin g cancels d omega's sin g

    def ring(g):          # int over phi of max(0, cos theta_i)
        a, b = ct * math.cos(g), st * math.sin(g)
        if a + b <= 0.0:
            return 0.0
        phimax = math.pi if a >= b else math.acos(-a / b)
        return 2.0 * (a * phimax + b * math.sin(phimax))

    pts = sorted({x for x in (abs(math.pi / 2 - theta), math.pi / 2 + theta) if 0.0 < x < math.pi})
    g0 = quad(lambda g: sun_bracket(g) * ring(g), 0.0, math.pi, epsabs=0, epsrel=1e-9, limit=400, points=pts)[0]
    k_d = rho / math.pi
    expected = beta * beta * k_d * g0 / (2.0 * math.pi * t_sp)          # per unit I0, 1/m^2
    got = float(surface.surface_radiance_scattered(beta, d_sp, theta, 1.0, rho=rho, table=table))
    assert abs(got / expected - 1.0) < TABLE_TOL


def test_t0_limit_closed_form(table):
    """T -> 0: T K_inf -> (pi - gamma') / (2 sin gamma'), so M_n(0, 0) = (n+1)/2 int_0^{pi/2} (pi - g) cos^n g dg."""
    closed = {  # (n, theta): value
        (1.0, 0.0): math.pi / 2 + 1.0,
        (1.0, math.pi): math.pi / 2 - 1.0,
        (2.0, 0.0): 1.5 * (3.0 * math.pi ** 2 / 16.0 + 0.25),
        (2.0, math.pi): 1.5 * (math.pi ** 2 / 16.0 - 0.25),
    }
    m = NumpyOps({tables.SURFACE.name: table})
    for (n, theta), value in closed.items():
        assert surface.surface_m_t0([theta], n)[0] == pytest.approx(value, rel=QUAD_TOL)
        assert surface.surface_m([1e-7], [theta], n)[0, 0] == pytest.approx(value, rel=1e-5)   # continuity
        # T = 0, theta in {0, pi}: table nodes, up to the quadrature (5e-6) and the 0.01-row clamp of surface_log_m
        # (<= 1e-4)
        assert table_m(m, 0.0, theta, n) == pytest.approx(value, rel=2e-4)
    # all levels at theta = 0 and pi vs the 1-D closed-form integrals
    for k, n in enumerate(tables.PHONG_EXPONENTS[::8]):
        top = (n + 1) / 2 * quad(lambda g: (math.pi - g) * math.cos(g) ** n, 0, math.pi / 2, epsrel=1e-12)[0]
        bottom = (n + 1) / 2 * quad(lambda g: g * math.cos(g) ** n, 0, math.pi / 2, epsrel=1e-12)[0]
        assert table_m(m, 0.0, 0.0, n) == pytest.approx(top, rel=2e-4)
        assert table_m(m, 0.0, math.pi, n) == pytest.approx(bottom, rel=2e-4)


def test_linear_in_beta(table):
    """beta -> 0: L_{p,a} -> beta M_n(0, theta) / (2 pi D) (linear; beta = 0 gives exactly 0)."""
    d, theta = 7.0, 0.9
    betas = np.array([0.0, 1e-9, 2e-9, 4e-9])
    for n in (1.0, 30.0):
        v = surface.surface_radiance_scattered(betas, d, theta, n, table=table)
        assert v[0] == 0.0
        assert v[2] / v[1] == pytest.approx(2.0, rel=1e-4)
        assert v[3] / v[1] == pytest.approx(4.0, rel=1e-4)
        m0 = surface.surface_m_t0([theta], n)[0]
        assert v[1] / (1e-9 / (2 * math.pi * d)) == pytest.approx(m0, rel=TABLE_TOL)


def test_no_nan_inf(table):
    beta = np.array([0.0, 0.0, 1e-3, 0.1, 1.0, 100.0, 0.05, 0.05])[:, None]
    d = np.array([0.0, 1e-9, 1.0, 10.0, 1e3, 1e6, 0.0, 5.0])[None, :]
    for theta in (0.0, 1e-8, math.pi / 2, math.pi - 1e-8, math.pi):
        for n in (1.0, 1.3, 7.0, 1024.0, 0.5, 5000.0):
            v = surface.surface_radiance_scattered(beta, d, theta, n, table=table)
            assert np.all(np.isfinite(v)) and np.all(v >= 0.0)
            assert np.all(v[0] == 0.0) and np.all(v[1] == 0.0)     # no fog, no fog light
    m = NumpyOps({tables.SURFACE.name: table})
    c = np.array([-1.0, -1.0 - 1e-7, 0.0, 1.0, 1.0 + 1e-7])
    th = surface.angle_from_cos(m, c)
    assert np.all(np.isfinite(th)) and np.allclose(th, [math.pi, math.pi, math.pi / 2, 0.0, 0.0])
    v = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 2.0]])
    assert np.all(np.isfinite(surface.lobe_angle(m, v, v[::-1])))


def test_table_offgrid_relative_error(ops):
    """Random off-grid (T, theta) incl. intermediate exponents vs a finer quadrature: relative error <= TABLE_TOL."""
    rng = np.random.default_rng(11)
    t = np.concatenate([10 ** rng.uniform(-4, math.log10(20.0), 40), rng.uniform(0, 20, 20)])
    th = np.concatenate([rng.uniform(0, math.pi, 40), rng.uniform(0, 0.2, 20)])
    g, w = surface.gamma_nodes(h=0.5 / 32)
    prof = surface.radiance_profile(t, g, panels=24) * w
    for n in (1.0, 1.0905, 2.0, 5.19, 45.25, 181.02, 939.0, 1024.0):
        ref = surface.surface_m(t, th, n, profile=prof, gamma=g)
        got = surface.surface_factor(ops, t[:, None], th[None, :], surface.exponent_level(n))
        err = np.abs(got / ref - 1.0)
        assert err.max() < TABLE_TOL, (n, err.max())


def test_table_layout():
    tab = surface.surface_table()
    assert tab.dtype == np.float32 and tab.shape == (tables.SURFACE.height, tables.SURFACE.width)
    assert np.all(np.isfinite(tab))
    x = np.linspace(0, 1, 7)
    m = NumpyOps()
    assert np.allclose(tables.surface_x(m, tables.surface_t(x)), x, atol=1e-9)
    for k in range(len(tables.PHONG_EXPONENTS)):
        assert np.allclose(tables.surface_y(m, tables.surface_theta(x, k), k), x, atol=1e-9)
    assert tables.surface_theta(1.0, 0) == pytest.approx(math.pi)


def test_levels_static_and_per_pixel_agree(ops):
    """A Python-float level (1-2 lookups chosen at build time) and a per-pixel level (always 2) agree."""
    t = np.array([0.0, 0.01, 0.5, 3.0, 15.0])[:, None]
    th = np.array([0.0, 0.1, 1.0, 2.0, math.pi])[None, :]
    for n in (1.0, 1.19, 3.0, 64.0, 700.0, 1024.0):
        static = surface.surface_factor(ops, t, th, surface.exponent_level(n))
        level = tables.PHONG_LEVELS_PER_OCTAVE * surface.log2_approx(ops, np.full(t.shape, n))
        dynamic = surface.surface_factor(ops, t, th, level)
        assert np.allclose(dynamic, static, rtol=1e-4, atol=0)
    assert surface.exponent_level(1.0) == 0.0 and surface.exponent_level(1024.0) == len(tables.PHONG_EXPONENTS) - 1
    assert surface.exponent_level(0.3) == 0.0 and surface.exponent_level(1e5) == len(tables.PHONG_EXPONENTS) - 1
    x = np.geomspace(1.0, 1024.0, 50)
    assert np.allclose(surface.log2_approx(ops, x), np.log2(x), atol=1e-4)


def test_material_mapping(ops):
    r = np.array([0.0, 0.1, 0.2, 0.3, 0.5, 0.8, 1.0])
    n = [surface.phong_exponent_from_roughness(v) for v in r]
    assert n == sorted(n, reverse=True)
    assert n[0] == tables.PHONG_EXPONENTS[-1] and n[-1] == 1.0
    assert surface.phong_exponent_from_roughness(0.5) == pytest.approx(7.5)   # alpha = 0.25
    levels = surface.phong_level(ops, r)
    assert np.allclose(levels, [surface.exponent_level(v) for v in n], atol=1e-3)
    rho_d, rho_s, n = surface.principled_albedos([0.8, 0.5, 0.2], metallic=0.0, roughness=0.4, cos_view=0.7)
    e = surface.principled_albedos([0.0, 0.0, 0.0], roughness=0.4, cos_view=0.7)[1]
    assert np.allclose(rho_s, e) and np.allclose(rho_d, np.array([0.8, 0.5, 0.2]) * (1 - e))
    assert n == pytest.approx(0.5 * (0.4 ** -4 - 1))
    rho_d, rho_s, _ = surface.principled_albedos([0.9, 0.6, 0.3], metallic=1.0, cos_view=0.7)
    assert np.all(rho_d == 0.0) and np.all(np.diff(rho_s) < 0)
    assert surface.principled_albedos([0.5] * 3, specular_ior_level=0.0, cos_view=0.3)[1] == pytest.approx(0.0)
    # per-pixel inputs (vectors (..., 3), scalars (...))
    base = np.array([[0.8, 0.5, 0.2], [0.9, 0.6, 0.3]])
    rd, rs, lv = surface.principled_to_phong(ops, base, np.array([0.0, 1.0]), np.array([0.4, 0.2]),
                                             np.array([0.5, 0.5]), np.array([0.7, 0.7]))
    assert rd.shape == rs.shape == (2, 3) and lv.shape == (2,)
    assert np.allclose(rd[1], 0.0)


def _fresnel(cos_i, ior):
    """Unpolarised Fresnel reflectance of a dielectric (s and p written out: Born & Wolf)."""
    sin_t = np.sqrt(1.0 - cos_i * cos_i) / ior
    cos_t = np.sqrt(1.0 - sin_t * sin_t)
    r_s = (cos_i - ior * cos_t) / (cos_i + ior * cos_t)
    r_p = (ior * cos_i - cos_t) / (ior * cos_i + cos_t)
    return 0.5 * (r_s * r_s + r_p * r_p)


def test_specular_albedo_limits():
    """The specular layer's directional albedo (``surface.bake_specular_albedo``, the glossy lobe's rho_s):
    a smooth surface (roughness 0) reflects the Fresnel equations' reflectance (dielectric, IOR 1.5) and
    Schlick's (metal), within the bilinear lookup; rougher lobes lose energy to masking (below 1 for
    F = 1) and never exceed it; a dielectric's albedo rises towards grazing angles.  (Against Cycles'
    own Principled BSDF: tests/test_material_kinds.py.)"""
    m = NumpyOps({tables.SPECULAR_ALBEDO.name: surface.specular_table()})
    mu = np.linspace(0.05, 1.0, 20)
    smooth = surface.dielectric_albedo(m, 0.04, np.zeros_like(mu), mu)
    np.testing.assert_allclose(smooth, _fresnel(mu, 1.5), rtol=0.03, atol=2e-3)
    metal = surface.metal_albedo(m, np.array([0.9, 0.6, 0.3]), np.zeros_like(mu), mu)
    want = np.array([0.9, 0.6, 0.3]) + (1 - np.array([0.9, 0.6, 0.3])) * ((1 - mu) ** 5)[:, None]
    np.testing.assert_allclose(metal, want, rtol=0.03, atol=2e-3)
    for r, least in ((0.2, 0.85), (0.5, 0.7), (0.9, 0.35)):   # GGX single scattering loses up to ~60 %
        white = surface.metal_albedo(m, np.ones(3), np.full_like(mu, r), mu)[:, 0]
        assert np.all(white <= 1.0 + 1e-6) and white.min() > least, (r, white.min())
        rising = surface.dielectric_albedo(m, 0.04, np.full_like(mu, r), mu)
        assert np.all(np.diff(rising) < 0), r   # mu grows: the albedo falls from grazing to normal


# --- anisotropic fog (issue 9): the table baked for Henyey-Greenstein g --------------------------------

# Measured over LIGHT_FRAME_POINTS (the worst: T = 1, theta = 1.5, Lambert: forward-scattered light
# grazing the surface): g = -0.5 0.31 %, 0.5 0.19 %, 0.85 0.91 %, 0.95 2.8 % (rungs.hg_scatter_error).
@pytest.mark.parametrize("g", (-0.5, 0.5, 0.85, 0.95))
def test_anisotropic_m_vs_scipy(g):
    spec = tables.anisotropic(tables.SURFACE, g)
    ops = NumpyOps({spec.name: surface.surface_table(g)})
    worst = 0.0
    for t_sp, theta, n in LIGHT_FRAME_POINTS:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            ref = m_ref_light_frame(t_sp, theta, n, g=g)
        got = float(surface.surface_factor(ops, np.asarray(float(t_sp)), np.asarray(float(theta)),
                                           surface.exponent_level(n), g))
        worst = max(worst, abs(got / ref - 1.0))
    assert worst < rungs.hg_scatter_error(g), worst
    assert rungs.choose("nodes", 0, g).scatter.max_error == rungs.hg_scatter_error(g)
