"""Stability of the shipped airlight formulations over the extended domain (issue 8 §4).

Shipped: the node groups' N-table model (``airlight.airlight``) and the OSL
method's quadrature (``quadrature=True``), each in float64 and in float32 as
the shaders evaluate it (tools/shader_float32.py).  Domain: optical depths
T_sv, T_vp in [1e-4, 1e3] and T_vp = inf (the background), gamma in
[1e-7, pi - 1e-7], beta in [1e-4, 1e2] per metre, distances D = T / beta.

* No formulation gives NaN, Inf or a negative value anywhere on a dense grid
  of that domain, extreme corners included (and gamma = 0 and pi exactly).
* Accuracy against the cached quadrature of Sun Eq. 5 on the grid of
  tools/stability_map.py (tests/data/stability_reference.npz, 44 200 samples;
  ``--regen-references`` or ``tools/stability_map.py --regen`` recomputes it):
  the documented bounds (1.6e-4 table, 1.1e-6 quadrature) hold in the
  documented domain in float64; over the extended domain each formulation
  has a measured bound outside named regions where it is known to fail, and
  those regions are pinned by tests of their own (numbers in README.md,
  "Stability map").  ``test_documented_bound_everywhere`` is an expected
  failure (strict) for each formulation that breaks its documented bound
  somewhere: it passes, and so fails the suite, once a fix removes the failure.

Error of a sample: |L_m - L| / max(L, tiny), tiny the smallest normal number
of the format (tools/stability_map.py).
"""
import math

import numpy as np
import pytest

from fog_addon.precompute.physics.point import airlight as al
from fog_addon.precompute.physics.point import model
from fog_addon.precompute.core.ops import NumpyOps
from tools import airlight_reference as ref
from tools import shader_float32 as f32
from tools import stability_map as sm

SHIPPED = ("table_f64", "table_f32", "quad_f64", "quad_f32")
DOCUMENTED = {"table_f64": 1.6e-4, "table_f32": 1.6e-4, "quad_f64": 1.1e-6, "quad_f32": 1.1e-6}
# Measured over the extended domain outside the known regions below (max on the grid, rounded up).
EXTENDED = {"table_f64": 1.9e-4,     # 1.86e-4 at T_sv = 68, gamma >= pi - 0.1: interpolation of N at rho ~ 136
            "table_f32": 1.9e-4,     # the same, plus float32 rounding
            "quad_f64": 1.1e-6,      # 4.9e-7
            "quad_f32": 4e-5}        # 3.4e-5: the rounding of the float32 inputs (along = D_sv cos gamma)
BLEND_SLOPE = 0.0                    # float32 table, short segments: the select multiplies the long branch by exactly 0
BLEND_REGION = 1e8                   # ... where T_sv / (T_vp gamma) exceeds this
DOCUMENTED_DOMAIN = dict(t_sv=ref.T_SV, t_vp=ref.T_VP, beta=ref.BETA, gamma=(1e-6, math.pi - 1e-6))


@pytest.fixture(scope="module")
def table():
    return al.bake_airlight_table()


@pytest.fixture(scope="module")
def cache(regen):
    return sm.load_reference(regen=regen, log=print)


@pytest.fixture(scope="module")
def grid(cache, table):
    """The map's samples, their true ln L, regions, and every shipped formulation's values and errors."""
    params = sm.samples()
    beta, d_sv, d_vp, gamma = params
    t_sv, t_vp = beta * d_sv, beta * d_vp
    ln_l = sm.log_truth(cache)
    g = dict(params=params, ln_l=ln_l, t_sv=t_sv, t_vp=t_vp, gamma=gamma, beta=beta)
    g["near_light"] = sm.near_light(params)                 # the table reads N at R >= 1 um
    # float32: the prefactor (beta / 2 pi) e^{-T_sv} is below the smallest normal number, the value is not
    g["denormal_prefactor"] = ((np.log(beta / (2 * math.pi)) - t_sv < math.log(sm.TINY["float32"]))
                               & (ln_l >= math.log(sm.TINY["float32"])))
    with np.errstate(divide="ignore", invalid="ignore"):
        g["blend_x"] = np.where(np.isfinite(t_vp), t_sv / (t_vp * gamma), 0.0)
    g["blend"] = g["blend_x"] > BLEND_REGION
    for name in SHIPPED:
        g[name] = sm.evaluate(name, params, table)
        g["err_" + name] = sm.rel_error(g[name], ln_l, sm.TINY[sm.FORMULATIONS[name][1]])
    return g


def known_regions(g, name):
    """Samples where ``name`` is known to miss its extended-domain bound (see the module docstring)."""
    m = np.zeros(g["ln_l"].shape, bool)
    if name.startswith("table"):
        m |= g["near_light"]
    if name.endswith("f32"):
        m |= g["denormal_prefactor"]
    if name == "table_f32":
        m |= g["blend"]
    return m


def _worst(g, err, mask, label):
    e = np.where(mask, err, -1.0)
    i = np.unravel_index(int(np.argmax(e)), e.shape)
    msg = (f"{label}: max {e[i]:.3g} over {int(mask.sum())} samples at beta={g['beta'][i]:.3g} "
           f"T_sv={g['t_sv'][i]:.4g} T_vp={g['t_vp'][i]:.4g} gamma={g['gamma'][i]:.3g}")
    print("\n" + msg)
    return e[i], msg


# --- the reference ---------------------------------------------------------------

def test_reference_cache_is_sound(cache):
    assert cache["scaled"].shape == (len(sm.BETAS), len(sm.T_GRID), len(sm.T_VP_GRID), len(sm.GAMMAS))
    assert np.all(np.isfinite(cache["scaled"])) and np.all(cache["scaled"] > 0)
    assert cache["est_rel"].max() < 1e-10           # QUADPACK's own error estimate
    assert cache["check_rel"].max() < 1e-8          # against the independent Eq. 9 quadrature (5.2e-10)


def test_reference_cache_is_current(cache):
    """A few cached values recomputed live, so the cache cannot go stale."""
    rng = np.random.default_rng(8)
    t_sv, t_vp = sm.true_depths()
    for _ in range(16):
        b, i, j, k = (int(rng.integers(n)) for n in cache["scaled"].shape)
        live = ref.eq5_quad(1.0, t_sv[b, i], t_vp[b, j], sm.GAMMAS[k], scaled=True)[0]
        assert abs(live / cache["scaled"][b, i, j, k] - 1.0) < 1e-12, (b, i, j, k)


# --- NaN / Inf anywhere in the domain ---------------------------------------------------

def _dense(n_t=48, n_gamma=14, n_beta=7):
    """(beta, d_sv, d_vp, gamma) on a grid over the map's domain: T_sv, T_vp log-spaced (and T_vp = inf),
    gamma at 0, pi/2, pi and log-spaced towards 0 and pi, beta from 1e-4 to 1e2 /m."""
    t = np.geomspace(*sm.T_RANGE, n_t)
    gamma = np.concatenate([[0.0], np.geomspace(1e-7, 1.0, n_gamma), [0.5 * math.pi],
                            math.pi - np.geomspace(1e-7, 1.0, n_gamma)[::-1], [math.pi]])
    beta = np.geomspace(1e-4, 1e2, n_beta)
    b, ts, tv, g = np.meshgrid(beta, t, np.concatenate([t, [np.inf]]), gamma, indexing="ij")
    return b, ts / b, tv / b, g


@pytest.mark.parametrize("name", SHIPPED)
def test_never_nan_or_inf(name, table):
    """Dense grid: 48 x 49 depths (T_vp = inf included) x 31 angles (0, 1e-7 ... pi - 1e-7, pi) x 7 beta."""
    p = _dense()
    v = sm.evaluate(name, p, table)
    bad = ~np.isfinite(v) | (v < 0.0)
    if bad.any():
        i = tuple(np.argwhere(bad)[0])
        pytest.fail(f"{name}: {int(bad.sum())} of {v.size} NaN/Inf/negative, e.g. beta={p[0][i]:.3g} "
                    f"D_sv={p[1][i]:.4g} D_vp={p[2][i]:.4g} gamma={p[3][i]:.3g} -> {v[i]}")


# --- accuracy ------------------------------------------------------------------------

@pytest.mark.parametrize("name", ("table_f64", "quad_f64"))
def test_documented_bound_in_documented_domain(grid, name):
    """T_sv in [0.01, 20], T_vp in [0.01, 50] or inf, beta in [1e-3, 1], gamma in [1e-6, pi - 1e-6]
    (tools/airlight_reference.py, the 44 000 samples behind the documented figures), except, for
    the table, rays within 1 um of the light: they are in that domain too (D_sv < 1 m with
    gamma = 1e-6) but no random sample found them (test_table_near_light_underestimates)."""
    inside = lambda key, lo_hi: (grid[key] >= lo_hi[0]) & (grid[key] <= lo_hi[1] * (1 + 1e-6))
    m = (inside("t_sv", DOCUMENTED_DOMAIN["t_sv"]) & inside("beta", DOCUMENTED_DOMAIN["beta"])
         & inside("gamma", DOCUMENTED_DOMAIN["gamma"])
         & (inside("t_vp", DOCUMENTED_DOMAIN["t_vp"]) | np.isinf(grid["t_vp"])))
    if name.startswith("table"):
        print(f"\n{int((m & grid['near_light']).sum())} of {int(m.sum())} samples within 1 um of the light left out")
        m &= ~grid["near_light"]
    worst, msg = _worst(grid, grid["err_" + name], m, f"{name} in the documented domain")
    assert worst < DOCUMENTED[name], msg


@pytest.mark.parametrize("name", SHIPPED)
def test_extended_domain_outside_known_regions(grid, name):
    err = grid["err_" + name]
    assert not np.isnan(err).any()
    worst, msg = _worst(grid, err, ~known_regions(grid, name), f"{name} outside its known regions")
    assert worst < EXTENDED[name], msg


def test_quad_float32_error_is_its_inputs(grid):
    """The float32 quadrature's 3.4e-5 is the rounding of its inputs: float64 arithmetic on the same
    float32 (beta, D_sv, along, h, D_vp) misses by as much (along = D_sv cos gamma in float32 cannot
    place a surface near the closest point to the light: T_vp ~ T_sv, gamma small)."""
    b, s, a, h, v, finite = f32.shader_inputs(*(np.ravel(x) for x in grid["params"]))
    d = lambda x: x.astype(float)
    with np.errstate(all="ignore"):
        val = model.airlight_quadrature(NumpyOps(), d(b), d(s), d(a), d(h), np.where(finite, d(v), model.FAR))
    e_in = sm.rel_error(val.reshape(grid["ln_l"].shape), grid["ln_l"], sm.TINY["float32"])
    e32 = grid["err_quad_f32"]
    print(f"\nquad: float64 at the float32 inputs max {e_in.max():.3g}, float32 max {e32.max():.3g}, "
          f"max difference {np.max(np.abs(e32 - e_in)):.3g}")
    assert np.max(np.abs(e32 - e_in)) < 5e-6
    assert e_in.max() > 0.8 * e32.max()


def test_table_near_light_underestimates(grid):
    """Rays within 1 um of the light (``polar_radius`` < model.MIN_DISTANCE): the tail K is evaluated
    at R = 1 um, so the glow comes out too small, by up to the whole of it, never too large."""
    for name in ("table_f64", "table_f32"):
        m = grid["near_light"] & (grid["ln_l"] > math.log(sm.TINY["float32"]))
        ratio = grid[name][m] * np.exp(-grid["ln_l"][m])
        print(f"\n{name}, rays within 1 um of the light: L / L_ref in [{ratio.min():.3g}, {ratio.max():.6g}] "
              f"over {int(m.sum())} samples")
        assert ratio.max() < 1.0 + EXTENDED[name]
        assert ratio.min() > 0.0


def test_table_float32_short_segment_blend(grid, table):
    """Float32, short segments on rays aimed at a light, where the long branch cancels (one ulp of
    K ~ pi / 2h): the select c a + (1 - c) b multiplies it by exactly 0 (the earlier a + c (b - a) leaked
    it: 3e-14 T_sv / (T_vp gamma), 2 % in random samples); error <= EXTENDED + BLEND_SLOPE T_sv / (T_vp gamma).

    On the grid, and on 200 000 random samples of the region against the float64 evaluation of
    the same float32 inputs (the short branch, exact there to 1e-12)."""
    name = "table_f32"
    m = grid["blend"] & ~grid["near_light"] & ~grid["denormal_prefactor"]
    err = grid["err_" + name] - BLEND_SLOPE * grid["blend_x"]
    worst, msg = _worst(grid, err, m, "table_f32 short-segment blend, error - slope x")
    assert worst < EXTENDED[name], msg
    _worst(grid, grid["err_" + name], m, "table_f32 short-segment blend, error")
    rng = np.random.default_rng(12)
    n = 200_000
    beta = np.asarray(10 ** rng.uniform(-4, 2, n), np.float32).astype(float)
    t_sv = 10 ** rng.uniform(0, 2, n)
    t_vp = 10 ** rng.uniform(-4, -1, n)
    gamma = 10 ** rng.uniform(-7, -4, n)
    d_sv = np.asarray(t_sv / beta, np.float32).astype(float)
    d_vp = np.asarray(t_vp / beta, np.float32).astype(float)
    keep = (d_sv * np.sin(gamma) >= model.MIN_DISTANCE)
    p = [x[keep] for x in (beta, d_sv, d_vp, gamma)]
    got = sm.evaluate(name, p, table)
    f32in = [np.asarray(x, np.float32).astype(float) for x in p]
    want = sm.evaluate("table_f64", f32in[:3] + [p[3]], table)
    with np.errstate(all="ignore"):
        e = np.abs(got / want - 1.0)
        x = p[0] * p[1] / (p[0] * p[2] * p[3])
    ok = want > 1e-30
    i = int(np.argmax(np.where(ok, e, 0)))
    print(f"\nrandom: float32 vs float64 max {e[i]:.3g} at T_sv={p[0][i] * p[1][i]:.4g} "
          f"T_vp={p[0][i] * p[2][i]:.4g} gamma={p[3][i]:.3g} (T_sv/(T_vp gamma) = {x[i]:.3g})")
    assert np.all(e[ok] < 1e-5 + BLEND_SLOPE * x[ok])


def test_float32_denormal_prefactor(table):
    """Float32 where (beta / 2 pi) e^{-T_sv} < 1.2e-38 but L is not (T_sv ~ 77-105, rays toward the light,
    L < 1e-31): digits lost to denormals, down to 0 (as on a GPU that flushes them).  The grid has no
    such sample; 100 000 random ones against the float64 evaluation of the same float32 inputs:
    finite, non-negative, within 100 % of the truth (0 at worst)."""
    rng = np.random.default_rng(13)
    n = 100_000
    beta = np.asarray(10 ** rng.uniform(-4, 2, n), np.float32).astype(float)
    t_sv = rng.uniform(70.0, 120.0, n)
    t_vp = 10 ** rng.uniform(-4, 3, n)
    gamma = 10 ** rng.uniform(-7, 0, n)
    d_sv = np.asarray(t_sv / beta, np.float32).astype(float)
    d_vp = np.where(rng.uniform(size=n) < 0.2, np.inf, np.asarray(t_vp / beta, np.float32).astype(float))
    p = [beta, d_sv, d_vp, gamma]
    tiny = sm.TINY["float32"]
    for name, ref64 in (("table_f32", "table_f64"), ("quad_f32", "quad_f64")):
        want = sm.evaluate(ref64, p, table)
        m = (np.log(beta / (2 * math.pi)) - beta * d_sv < math.log(tiny)) & (want >= tiny)
        if name.startswith("table"):
            m &= sm.polar_radius(d_sv, d_vp, gamma) >= model.MIN_DISTANCE
        got = sm.evaluate(name, p, table)
        assert np.all(np.isfinite(got)) and np.all(got >= 0.0)
        e = np.abs(got[m] / want[m] - 1.0)
        i = int(np.argmax(e))
        print(f"\n{name} with a denormal prefactor: max {e[i]:.3g} over {int(m.sum())} samples at "
              f"T_sv={beta[m][i] * d_sv[m][i]:.4g} gamma={gamma[m][i]:.3g} L={want[m][i]:.3g}")
        assert m.sum() > 100 and e.max() <= 1.0


STRICT_FAILURES = {
    "table_f64": "rays within 1 um of the light: glow too small by up to 100 %; 1.86e-4 at T_sv = 68, gamma >= pi - 0.1",
    "table_f32": "as table_f64, plus denormal prefactors (up to 100 %)",
    "quad_f32": "3.4e-5 from the float32 inputs; denormal prefactors (up to 100 %)",
}


@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.xfail(strict=True, reason=STRICT_FAILURES[n]))
                                  if n in STRICT_FAILURES else n for n in SHIPPED])
def test_documented_bound_everywhere(grid, name):
    worst, msg = _worst(grid, grid["err_" + name], np.ones(grid["ln_l"].shape, bool), f"{name} everywhere")
    assert worst < DOCUMENTED[name], msg


# --- anisotropic fog (issue 9): Sun's Appendix D against ours ---------------------------------------
#
# tools/stability_map.py --anisotropic maps Sun et al. 2005 Appendix D (the phase function as a degree-n
# polynomial in cos alpha, Eq. 36-44; fog_addon/precompute/phase_series.py) next to our N table of g and
# our quadrature for Henyey-Greenstein g in {0.3, 0.7, 0.85, 0.95}.  Here: App. D is Sun's isotropic
# model at g = 0, its power series is HG's Legendre series, it converges to Eq. 5 where that series
# does, and it fails (the documented failure, README "Stability map") where ours does not.

from tools.research import phase_series as ps  # noqa: E402
from fog_addon.precompute.core import tables  # noqa: E402
from fog_addon.precompute.model import rungs  # noqa: E402

_HG_TABLES = {}


def _hg_table(g):
    """The N table baked for g, shared by the tests below (about 2.5 s of CPU each)."""
    if g not in _HG_TABLES:
        _HG_TABLES[g] = al.bake_airlight_table(tables.anisotropic(tables.AIRLIGHT, g))
    return _HG_TABLES[g]


def _rays():
    """A handful of rays: toward the light, across, away from it; thin and thick; surface and sky."""
    rows = [(1.0, 0.01, 0.02, 1e-3), (1.0, 0.01, np.inf, 1e-3), (1.0, 1.0, 3.0, 0.1), (0.1, 5.0, 40.0, 0.5),
            (1.0, 1.0, np.inf, 0.5 * math.pi), (0.5, 4.0, 2.0, 1.2), (1.0, 2.0, np.inf, 2.5),
            (1.0, 0.5, 1.0, math.pi - 1e-3), (0.01, 300.0, np.inf, math.pi - 0.1), (1.0, 3.0, 0.5, 0.05)]
    return [np.array(c, float) for c in zip(*rows)]


def test_hg_power_series_is_the_legendre_series():
    """Sun Eq. 36 for HG: the Legendre series (2l + 1) g^l P_l in powers of cos alpha reproduces 4 pi p_HG
    at n = 60 for g = 0.5 (terms ~ g^l); W = (1, 0, ...) at g = 0; n = 1 is 1 + 3 g cos alpha."""
    mu = np.linspace(-1.0, 1.0, 2001)
    w = ps.hg_power_coefficients(0.5, 60)
    err = np.max(np.abs(ps.phase_polynomial(w, mu) / ps.hg_4pi(0.5, mu) - 1.0))
    print(f"\nn = 60, g = 0.5: max relative error {err:.2g}")
    assert err < 1e-6
    assert np.array_equal(ps.hg_power_coefficients(0.0, 3), [1.0, 0.0, 0.0, 0.0])
    assert np.allclose(ps.hg_power_coefficients(0.3, 1), [1.0, 0.9], rtol=0, atol=1e-15)
    # the limits the map reaches (stability_map.phase_truncation_error): n = 3, g = 0.85
    back, fwd = sm.phase_truncation_error(0.85, 3)
    assert back < -50.0 and -0.9 < fwd < -0.8


def test_appendix_d_at_g0_is_the_isotropic_model(cache, table):
    """g = 0: with F^k tables App. D is Sun's Eq. 11/12 with the same F table, to rounding; with F^k
    integrated exactly it is the isotropic model (the map's cached Eq. 5 reference, on every
    (T_sv, T_vp) cell of the anisotropic map, and our N table on the same samples) within 1e-3."""
    p = sm.samples(sm.ANISO_T_GRID, sm.ANISO_T_VP_GRID)
    flat = [np.ravel(x) for x in p]
    fk = ps.bake_sun_f_k_tables(3, 64, 64)
    with np.errstate(all="ignore"):
        sun = al.airlight_sun(*flat, al.bake_sun_f_table(64, 64))
        appd = ps.airlight_sun_appendix_d(*flat, 0.0, 3, fk)
    same = np.isfinite(sun)
    assert np.array_equal(np.isfinite(appd), same)
    assert np.max(np.abs(appd[same] - sun[same]) / np.maximum(np.abs(sun[same]), 1e-300)) < 1e-12
    sub = {"scaled": cache["scaled"][:, ::2][:, :, sm._ANISO_VP_INDEX]}
    ln_l = sm.log_truth(sub, sm.ANISO_T_GRID, sm.ANISO_T_VP_GRID)
    exact = ps.airlight_appendix_d_exact(*p, 0.0, 3)
    err = sm.rel_error(exact, ln_l, sm.TINY["float64"])
    print(f"\nApp. D exact F^k at g = 0 against Eq. 5: max {np.nanmax(err):.2g} over {err.size} samples")
    assert np.all(np.isfinite(err)) and err.max() < 1e-3
    ours = sm.evaluate("table_f64", p, table)
    m = ~sm.near_light(p) & (ln_l > math.log(1e-300))
    assert np.max(np.abs(exact[m] / ours[m] - 1.0)) < 1e-3


def test_appendix_d_converges_where_the_series_does():
    """g = 0.5: App. D with F^k exact converges to Eq. 5 with 4 pi p_HG as n grows (n = 40: g^n ~ 1e-12)."""
    p = _rays()
    want = np.array([ref.eq5_quad(*r, g=0.5)[0] for r in zip(*p)])
    errs = {n: np.max(np.abs(ps.airlight_appendix_d_exact(*p, 0.5, n) / want - 1.0)) for n in (3, 8, 40)}
    print("\n" + ", ".join(f"n = {n}: {e:.2g}" for n, e in errs.items()))
    assert errs[3] > errs[8] > errs[40] and errs[40] < 1e-6


def test_appendix_d_fails_at_g085_where_ours_does_not():
    """g = 0.85 (fog and dense-fog presets): App. D with n = 3 ("n <= 3 typically suffices") is off by more
    than 10 % on these rays (negative behind the light: the cubic is -2.3 at alpha = pi where HG is 0.04;
    86 % too dim toward the light), with exact F^k and with Sun's 64 x 64 F^k tables; our N table of g
    stays within 0.5 % and our quadrature within rungs.HG_QUADRATURE_ERROR on the same rays (eq5_quad)."""
    g = 0.85
    p = _rays()
    want = np.array([ref.eq5_quad(*r, g=g)[0] for r in zip(*p)])
    with np.errstate(all="ignore"):
        exact = ps.airlight_appendix_d_exact(*p, g, 3)
        tabled = ps.airlight_sun_appendix_d(*p, g, 3, ps.bake_sun_f_k_tables(3, 64, 64))
        ours = al.airlight(*p, table=_hg_table(g), g=g)
        quad = al.airlight(*p, quadrature=True, g=g)
    e = {k: np.abs(v / want - 1.0) for k, v in
         (("App. D n = 3", exact), ("App. D n = 3, F^k tables", tabled), ("ours", ours), ("quadrature", quad))}
    print("\n" + "\n".join(f"{k}: " + " ".join(f"{x:.2g}" for x in v) for k, v in e.items()))
    assert e["App. D n = 3"].max() > 0.1 and (exact < 0).any()
    assert e["App. D n = 3, F^k tables"].max() > 0.1
    assert e["ours"].max() < 5e-3
    assert e["quadrature"].max() < rungs.HG_QUADRATURE_ERROR


def _modest():
    return _dense(16, 8, 4)


HG_SHIPPED = [(-0.8, False), (0.85, False), (0.95, False), (-0.95, True), (-0.8, True), (0.85, True), (0.95, True)]
# g < 0, table: on rays within 1 um of the light (R clamped at model.MIN_DISTANCE), mostly with the surface at
# the light's distance, the two tails cancel below zero (down to -18x the truth, 1 240 of 510 384 samples of
# test_never_nan_or_inf's grid at g = -0.8; g = -0.5 too): model.airlight_segment clamps them at 0 there.


def _shipped(g, quadrature):
    p = _modest()
    with np.errstate(over="ignore"):
        v = (al.airlight(*p, quadrature=True, g=g) if quadrature else al.airlight(*p, table=_hg_table(g), g=g))
    return p, v


def _fail_at(p, v, bad, what):
    i = tuple(np.argwhere(bad)[0])
    pytest.fail(f"{what}: {int(bad.sum())} of {v.size}, e.g. beta={p[0][i]:.3g} D_sv={p[1][i]:.4g} "
                f"D_vp={p[2][i]:.4g} gamma={p[3][i]:.3g} -> {v[i]}")


@pytest.mark.parametrize("g, quadrature", HG_SHIPPED)
def test_anisotropic_never_nan_or_inf(g, quadrature):
    """As test_never_nan_or_inf for the shipped anisotropic formulations (tables serve g >= -0.8): 16 x 17
    depths (T_vp = inf included) x 19 angles (0, 1e-7 ... pi - 1e-7, pi) x 4 beta, float64."""
    p, v = _shipped(g, quadrature)
    bad = ~np.isfinite(v)
    if bad.any():
        _fail_at(p, v, bad, f"g = {g}, quadrature={quadrature}: NaN/Inf")


@pytest.mark.parametrize("g, quadrature", HG_SHIPPED)
def test_anisotropic_never_negative(g, quadrature):
    """Same grid: no negative value (as test_never_nan_or_inf asserts for g = 0; the g < 0 table clamps
    its near-light cancellation at 0, see above)."""
    p, v = _shipped(g, quadrature)
    bad = v < 0.0
    if bad.any():
        _fail_at(p, v, bad, f"g = {g}, quadrature={quadrature}: negative")


