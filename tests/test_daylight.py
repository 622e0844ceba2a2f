"""Daylight kernels (fog_addon/precompute/physics/daylight/daylight.py, issue 29) against independent quadrature.

Every expected value here comes from scipy: adaptive quadrature (QUADPACK) of the defining integrals,
written afresh below in plain Python (``ref_*``: the medium, its column depth, the camera's optical
depth by branches on the geometry, the integrands of Dobashi et al. 2002 Eq. 11), scipy.special.expn for
the exponential integrals, or a limit in closed form.  Nothing below calls the kernels to make a
reference.

The random samples (40 000 for the sun's single scattering, the strict protocol of tests/test_airlight.py:
max relative error <= 0.5 % sample by sample; 3 000 each for the sky and the haze) are cached in
tests/data/daylight_reference.npz; ``--regen-references`` (or ``python tests/test_daylight.py``) recomputes
them, and a fresh subset with another seed is integrated live on every run so the cache cannot go stale.
"""
import math
import pathlib
import sys
import warnings

import numpy as np
import pytest
from scipy import integrate, special

ROOT = pathlib.Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from fog_addon.precompute.physics.daylight import aerial, daylight as dl   # noqa: E402
from fog_addon.precompute.core.ops import NumpyOps      # noqa: E402
from tools.shader_float32 import Float32Ops        # noqa: E402

CACHE = ROOT / "tests" / "data" / "daylight_reference.npz"
CACHE_SEED = 20021127
LIVE_SEED = 771
N_SUN, N_SKY, N_HAZE = 40000, 3000, 3000
TOL = 5e-3          # the sun's single scattering: 0.5 % max relative error, sample by sample
SKY_TOL = 5e-3      # the sky's single scattering (10 directions)
HAZE_TOL = 1.5e-2   # the haze (12 panels)
EPSREL = 1e-10
FLOOR = 1e-25       # relative errors are taken above this: below it the kernels' e^-80 floor (EXP_CLAMP) shows
FAR = dl.UNBOUNDED
m = NumpyOps()


# --- references: plain Python, no fog_addon ---------------------------------------------------------------

def ref_beta(z, b, h0, hh):
    """The layer's extinction at height z (1/m)."""
    if z <= h0:
        return b
    return b * math.exp(-(z - h0) / hh) if hh > 0 else 0.0


def ref_column(z, b, h0, hh):
    """int_z^inf beta dz'."""
    if z <= h0:
        return b * (h0 - z) + b * hh
    return b * hh * math.exp(-(z - h0) / hh) if hh > 0 else 0.0


def ref_tau(pz, vz, t, b, h0, hh):
    """Optical depth from pz along vz for t metres, by cases (the part below h0 as a length, the part above
    by e^{-a} - e^{-b} through expm1)."""
    pz, vz, t = float(pz), float(vz), float(t)
    z1 = pz + vz * t
    lo, hi = min(pz, z1), max(pz, z1)
    if hi == lo:                        # level (or its height change below the float's resolution)
        return ref_beta(pz, b, h0, hh) * t
    l_below = t * min(max((h0 - lo) / (hi - lo), 0.0), 1.0)
    if hi <= h0 or hh == 0.0:
        return b * l_below
    a_lo = max(lo, h0)
    rise = abs(vz) * t if lo >= h0 else hi - h0     # the height the part above the top spans
    # int_{a_lo}^{a_lo + rise} b e^{-(z - h0)/H} dz / |vz|
    above = -b * hh * math.exp(-(a_lo - h0) / hh) * math.expm1(-rise / hh) / abs(vz)
    return b * l_below + above


def ref_hg(g, c):
    return (1 - g * g) / (4 * math.pi * (1 + g * g - 2 * g * c) ** 1.5)


def _points(pz, vz, length, b, h0, hh):
    """Break points of the integrands: the top's crossing, optical-depth and falloff scales."""
    pts = set()
    if vz != 0.0:
        tc = (h0 - pz) / vz
        if 0.0 < tc < length:
            pts.add(tc)
            if hh > 0:
                s = hh / abs(vz) / 16.0
                while s < 1e4 * hh / abs(vz):
                    pts.add(tc + s)
                    s *= 2.0
    s = 1.0 / b / 32.0
    while s < 400.0 / b:
        pts.add(s)
        s *= 2.0
    if hh > 0 and vz > 0 and pz > h0:
        s = hh / vz / 16.0
        while s < 1e4 * hh / vz:
            pts.add(s)
            s *= 2.0
    return sorted(p for p in pts if 0.0 < p < min(length, 1e13))


def _quad(f, pts, length):
    end = np.inf if length >= FAR else length
    edges = [0.0] + pts + [end]
    total = 0.0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", integrate.IntegrationWarning)
        for a, c in zip(edges[:-1], edges[1:]):
            if c > a:
                total += integrate.quad(f, a, c, epsabs=0.0, epsrel=EPSREL, limit=400)[0]
    return total


def ref_sun(pz, vz, length, mu, b, h0, hh):
    """int_0^D beta(z(t)) e^{-tau_c(t) - C(z(t))/mu} dt (Dobashi et al. 2002 Eq. 11, one species)."""
    def f(t):
        z = pz + vz * t
        return ref_beta(z, b, h0, hh) * math.exp(-ref_tau(pz, vz, t, b, h0, hh) - ref_column(z, b, h0, hh) / mu)
    return _quad(f, _points(pz, vz, length, b, h0, hh), length)


def ref_sky(pz, vz, length, b, h0, hh):
    """int_0^D beta (1/2) E2(C(z(t))) e^{-tau_c(t)} dt (a uniform sky, black ground, isotropic)."""
    def f(t):
        z = pz + vz * t
        return ref_beta(z, b, h0, hh) * 0.5 * special.expn(2, ref_column(z, b, h0, hh)) * math.exp(
            -ref_tau(pz, vz, t, b, h0, hh))
    return _quad(f, _points(pz, vz, length, b, h0, hh), length)


HR, HM, ALB, GM = 8000.0, 1200.0, 0.9, 0.76


def ref_haze(pz, vz, length, mu, ct, br, bm):
    """Dobashi et al. 2002 Eq. 11: Rayleigh and Mie, exponential densities from the ground z = 0, flat."""
    pr = 3 / (16 * math.pi) * (1 + ct * ct)
    pm = 3 * (1 - GM * GM) * (1 + ct * ct) / (8 * math.pi * (2 + GM * GM) * (1 + GM * GM - 2 * GM * ct) ** 1.5)
    bme = bm / ALB

    def tau_species(t, b, hh):
        if vz == 0.0:
            return b * math.exp(-pz / hh) * t
        return -b * math.exp(-pz / hh) * hh * math.expm1(-vz * t / hh) / vz

    def f(t):
        z = pz + vz * t
        er, em = math.exp(-z / HR), math.exp(-z / HM)
        ts = (br * HR * er + bme * HM * em) / mu
        tc = tau_species(t, br, HR) + tau_species(t, bme, HM)
        return (br * er * pr + bm * em * pm) * math.exp(-ts - tc)
    b0 = br * math.exp(-pz / HR) + bme * math.exp(-pz / HM)
    pts, s = set(), 1.0 / b0 / 64.0
    while s < min(length, 1e9):
        pts.add(s)
        s *= 2.0
    if vz > 0:
        s = HM / vz / 8.0
        while s < min(length, 1e9):
            pts.add(s)
            s *= 2.0
    return _quad(f, sorted(p for p in pts if p < length), length)


# --- the sample design ------------------------------------------------------------------------------------

def _direction(rng):
    v = rng.normal(size=3)
    return v[2] / np.linalg.norm(v)


def sample_layer(rng):
    """One random (pz, vz, D, mu_s, cos_theta, beta0, h0, H, albedo, g) in the layer, or None."""
    b = 10 ** rng.uniform(-4, 0)
    kind = rng.random()
    if kind < 0.15:
        h0, hh = FAR, 0.0                                        # unbounded
        pz = rng.uniform(0, 1000)
    else:
        h0 = 10 ** rng.uniform(0, 3)
        hh = 0.0 if kind < 0.4 else 10 ** rng.uniform(0, 3.3)    # hard top or an exponential falloff
        pz = rng.uniform(0, h0 + 3 * hh + 100)
    r = rng.random()
    vz = _direction(rng)
    if r < 0.1:
        vz = rng.choice([-1.0, 1.0]) * 10 ** rng.uniform(-8, -2)
    elif r < 0.12:
        vz = 0.0
    length = 10 ** rng.uniform(-2, math.log10(50)) / b
    if vz > 0 and rng.random() < 0.1:
        length = FAR
    if vz < 0:
        length = min(length, pz / -vz)
    mu = rng.uniform(0.02, 1.0) if rng.random() < 0.9 else 10 ** rng.uniform(-3, -1.7)
    if rng.random() < 0.03:
        mu = vz if vz > 0.001 else mu                            # k = 0: looking up as steeply as the sun
    c = rng.uniform(-1, 1)
    if length <= 0.0 or ref_column(pz, b, h0, hh) / mu > 50 and ref_column(pz + vz * min(length, 1e13), b, h0, hh) / mu \
            + ref_tau(pz, vz, min(length, 1e13), b, h0, hh) > 50:
        return None                                              # the sun never reaches the ray (e^-50)
    return (pz, vz, length, mu, c, b, h0, hh, rng.uniform(0.5, 1.0), rng.uniform(-0.9, 0.9))


def sample_haze(rng):
    pz = rng.uniform(0, 3000)
    vz = _direction(rng)
    if rng.random() < 0.2:
        vz = rng.choice([-1.0, 1.0]) * 10 ** rng.uniform(-5, -1)
    length = 10 ** rng.uniform(2, math.log10(2e5))
    if vz > 0 and rng.random() < 0.25:
        length = FAR
    if vz < 0:
        length = min(length, pz / -vz)
    return (pz, vz, length, rng.uniform(0.01, 1.0), rng.uniform(-1, 1),
            float(rng.choice([5.8e-6, 13.5e-6, 33.1e-6])), 10 ** rng.uniform(math.log10(2e-6), math.log10(2e-4)))


def _layer_samples(n, seed):
    rng = np.random.default_rng(seed)
    out = []
    while len(out) < n:
        s = sample_layer(rng)
        if s is not None:
            out.append(s)
    return np.array(out)


def reference_sun(rows):
    return np.array([r[8] * ref_hg(r[9], r[4]) * ref_sun(r[0], r[1], r[2], r[3], r[5], r[6], r[7]) for r in rows])


def reference_sky(rows):
    return np.array([r[8] * ref_sky(r[0], r[1], r[2], r[5], r[6], r[7]) for r in rows])


def reference_haze(rows):
    return np.array([ref_haze(*r) for r in rows])


def build_cache(path=CACHE, seed=CACHE_SEED, log=print):
    sun = _layer_samples(N_SUN, seed)
    log(f"sun: {len(sun)} samples")
    sun_ref = reference_sun(sun)
    sky = _layer_samples(N_SKY, seed + 1)
    sky_ref = reference_sky(sky)
    log("sky done")
    rng = np.random.default_rng(seed + 2)
    haze = np.array([sample_haze(rng) for _ in range(N_HAZE)])
    haze_ref = reference_haze(haze)
    np.savez_compressed(path, sun=sun, sun_ref=sun_ref, sky=sky, sky_ref=sky_ref, haze=haze, haze_ref=haze_ref)
    return dict(np.load(path))


@pytest.fixture(scope="module")
def cache(regen):
    if regen or not CACHE.exists():
        return build_cache()
    return dict(np.load(CACHE))


# --- the kernels on sample arrays ---------------------------------------------------------------------------

def k_sun(rows, mm=m, **kw):
    pz, vz, d, mu, c, b, h0, hh, a, g = (np.asarray(rows[:, i], mm.dtype) for i in range(10))
    # g is a per-sample array here (the kernel folds a Python float in a shader: same formula)
    return dl.sun_airlight(mm, pz, vz, d, mu, c, b, h0, hh, a, g, **kw)


def k_sky(rows, mm=m, **kw):
    pz, vz, d, mu, c, b, h0, hh, a, g = (np.asarray(rows[:, i], mm.dtype) for i in range(10))
    return dl.sky_airlight(mm, pz, vz, d, b, h0, hh, a, **kw)


def k_haze(rows, mm=m, **kw):
    pz, vz, d, mu, c, br, bm = (np.asarray(rows[:, i], mm.dtype) for i in range(7))
    return aerial.haze_airlight(mm, pz, vz, d, mu, c, 0.0, br, bm, **kw)


def _rel(a, b):
    return np.abs(np.asarray(a, float) / np.asarray(b, float) - 1.0)


def _report(label, rows, err):
    i = int(np.argmax(err))
    msg = (f"{label}: {len(err)} samples, max {err[i]:.3g}, p99 {np.percentile(err, 99):.3g}, "
           f"median {np.median(err):.3g}; worst {np.round(rows[i], 6).tolist()}")
    print("\n" + msg)
    return msg


# --- the functions of one variable --------------------------------------------------------------------------

def test_phi1_against_expm1():
    """phi1 (series below 0.05, quotient above) against -expm1(-x)/x; exactly 1 at 0; no NaN anywhere."""
    x = np.concatenate([[0.0, 1e-300, 1e-12, dl.SERIES_X * (1 - 1e-9), dl.SERIES_X], np.geomspace(1e-10, 1e3, 5001)])
    with np.errstate(all="raise"):
        p1 = dl.phi1(m, x)
    xs = np.maximum(x, 1e-300)
    assert np.max(_rel(p1, np.where(x > 0, -np.expm1(-xs) / xs, 1.0))) < 1e-9
    assert p1[0] == 1.0
    with np.errstate(over="raise", invalid="raise"):
        assert np.all(np.isfinite(dl.phi1(Float32Ops({}), np.float32([0, 1e-30, 1, 1e20, 3e38]))))


def test_expint_against_scipy():
    """E2, E3 (A&S 5.1.53 below 1, a fitted rational above) against scipy.special.expn, 0 <= x <= 75; the
    power-series logarithm against numpy's."""
    x = np.concatenate([[0.0, 1e-30, 1e-12], np.geomspace(1e-12, 1, 4001), np.linspace(1, 75, 4001)])
    with np.errstate(all="raise"):
        e2, e3 = dl.expint2(m, x), dl.expint3(m, x)
    assert np.max(_rel(e2, special.expn(2, x))) < 2e-6
    assert np.max(_rel(e3, special.expn(3, x))) < 1e-4        # 1 - R cancels a little as x grows: 6.3e-5 at 75
    assert e2[0] == 1.0 and e3[0] == 0.5
    y = np.geomspace(1e-30, 1e30, 1001)
    assert np.max(np.abs(dl.log(m, y) - np.log(y))) < 1e-9


def test_e2_is_the_hemisphere_integral():
    """(1/2pi) int_upper e^{-C/mu} dw = int_0^1 e^{-C/mu} dmu = E2(C): the sky source's definition by quad."""
    for c in (0.0, 1e-4, 0.03, 0.5, 1.0, 3.0, 20.0):
        q = integrate.quad(lambda mu: math.exp(-c / mu) if mu > 0 else 0.0, 0, 1, epsabs=0, epsrel=1e-12,
                           points=[min(c, 0.5) + 1e-9])[0]
        assert abs(float(dl.expint2(m, np.float64(c))) / q - 1) < 2e-6


# --- the layer: extinction, column, optical depth ---------------------------------------------------------

LAYERS = [(0.05, 100.0, 0.0), (0.05, 100.0, 30.0), (1e-3, 5.0, 500.0), (0.3, 1.0, 1.0), (0.01, FAR, 0.0)]


@pytest.mark.parametrize("b,h0,hh", LAYERS)
def test_column_depth_against_quad(b, h0, hh):
    for z in (0.0, 0.5 * min(h0, 1e3), min(h0, 1e3), min(h0, 1e3) + 0.3 * hh, min(h0, 1e3) + 5 * hh + 1.0):
        top = h0 + 60 * hh if h0 < FAR else None
        if top is None:
            expect = b * (h0 - z)
        else:
            pts = [p for p in (h0,) if z < p < top]
            expect = integrate.quad(lambda y: ref_beta(y, b, h0, hh), z, top, points=pts or None,
                                    epsabs=1e-14, epsrel=1e-12)[0]
        got = float(dl.column_depth(m, np.float64(z), b, h0, hh))
        assert got == pytest.approx(expect, rel=1e-9, abs=1e-12)
        assert float(dl.extinction(m, np.float64(z), b, h0, hh)) == pytest.approx(ref_beta(z, b, h0, hh), rel=1e-12)


def test_optical_depth_random_against_quad():
    """2 000 random segments (every kind of layer and direction) against quad of beta along the segment."""
    rows = _layer_samples(2000, 99)
    got = dl.optical_depth(m, rows[:, 0], rows[:, 1], np.minimum(rows[:, 2], 1e7), rows[:, 5], rows[:, 6], rows[:, 7])
    err = []
    for r, gval in zip(rows, got):
        pz, vz, d, _, _, b, h0, hh = r[:8]
        d = min(d, 1e7)
        pts = [p for p in _points(pz, vz, d, b, h0, hh)]
        q = _quad(lambda t: ref_beta(pz + vz * t, b, h0, hh), pts, d)
        assert abs(ref_tau(pz, vz, d, b, h0, hh) - q) <= 1e-9 * q + 1e-13   # the reference's own closed form
        err.append(abs(gval - q) / q if q > FLOOR else abs(gval) / FLOOR * 1e-10)   # e^-80 floor: absolute
    err = np.array(err)
    print(_report("optical_depth vs quad", rows, err))
    assert err.max() < 1e-7      # heights rounded: a near-level segment's rise loses digits to its height


def test_optical_depth_limits():
    b, h0, hh = 0.02, 100.0, 40.0
    od = lambda *a: float(dl.optical_depth(m, *(np.float64(x) for x in a)))
    assert od(50.0, 0.0, 300.0, b, h0, hh) == pytest.approx(b * 300.0, rel=1e-14)             # level, inside
    assert od(160.0, 0.0, 300.0, b, h0, hh) == pytest.approx(b * math.exp(-60 / 40) * 300.0, rel=1e-12)
    assert od(h0, 0.0, 300.0, b, h0, hh) == pytest.approx(b * 300.0, rel=1e-14)               # level on the top
    assert od(h0, 0.0, 300.0, b, h0, 0.0) == pytest.approx(b * 300.0, rel=1e-14)              # (it belongs to it)
    assert od(150.0, 0.3, 1e3, b, h0, 0.0) == 0.0                                             # above a hard top
    assert od(150.0, -0.5, 200.0, b, h0, 0.0) == pytest.approx(b * 100.0, rel=1e-12)          # down through it
    assert od(50.0, 1.0, FAR, b, h0, 0.0) == pytest.approx(b * 50.0, rel=1e-12)               # out of the top
    assert od(50.0, 1.0, FAR, b, h0, hh) == pytest.approx(b * (50.0 + hh), rel=1e-12)         # out through H
    assert od(50.0, 1e-9, 1e4, b, FAR, 0.0) == pytest.approx(b * 1e4, rel=1e-12)              # unbounded
    assert od(50.0, 0.0, 0.0, b, h0, hh) == 0.0
    assert od(50.0, 1e-300, 1e3, b, h0, hh) == pytest.approx(b * 1e3, rel=1e-12)             # vz denormal


def test_sun_transmittance():
    b, h0, hh = 0.02, 100.0, 40.0
    st = lambda z, mu, hh=hh: float(dl.sun_transmittance(m, np.float64(z), np.float64(mu), b, h0, hh))
    for z, mu in ((0.0, 0.5), (70.0, 0.9), (130.0, 0.2), (400.0, 0.05)):
        q = integrate.quad(lambda y: ref_beta(y, b, h0, hh), z, h0 + 80 * hh, points=[h0] if z < h0 else None,
                           epsabs=0, epsrel=1e-12)[0]
        assert st(z, mu) == pytest.approx(math.exp(-q / mu), rel=1e-9)
    assert st(50.0, 0.0) == 0.0 and st(50.0, -0.3) == 0.0 and st(150.0, -1e-9, 0.0) == 0.0     # sun down
    assert st(150.0, 1e-9, 0.0) == 1.0                            # above a hard top: a grazing sun is whole
    assert st(150.0, 0.3, 0.0) == 1.0


# --- the sun's single scattering ------------------------------------------------------------------------------

def test_sun_cache_is_sound(cache):
    rows, ref = cache["sun"], cache["sun_ref"]
    assert len(rows) == N_SUN and np.all(np.isfinite(ref)) and np.all(ref >= 0)
    # (the unbounded fog never lets the sun in: its samples are all rejected, its limit is tested below)
    assert np.sum(rows[:, 7] == 0) > 5000 and np.sum(rows[:, 1] == 0) > 300
    assert np.sum(rows[:, 2] >= FAR) > 1000 and np.sum(ref == 0) > 100 and np.sum(rows[:, 1] == rows[:, 3]) > 100


def test_sun_airlight_random(cache):
    """The strict protocol: every one of the 40 000 cached samples within 0.5 % of quadrature (the rays
    that never meet the layer: exactly 0)."""
    rows, ref = cache["sun"], cache["sun_ref"]
    with np.errstate(all="raise"):
        got = k_sun(rows)
    zero, tiny = ref == 0.0, (ref > 0.0) & (ref <= FLOOR)
    assert np.all(got[zero] == 0.0)
    assert np.all(np.abs(got[tiny]) < 1e3 * FLOOR)      # e^-80 (EXP_CLAMP) floors what float32 cannot hold
    ok = ref > FLOOR
    err = _rel(got[ok], ref[ok])
    msg = _report("sun_airlight vs quad", rows[ok], err)
    assert ok.sum() > 30000 and err.max() < TOL, msg


def test_sun_airlight_live_subset():
    rows = _layer_samples(200, LIVE_SEED)
    ref = reference_sun(rows)
    got = k_sun(rows)
    assert np.all(got[ref == 0] == 0.0)
    nz = ref > FLOOR
    err = _rel(got[nz], ref[nz])
    assert err.max() < TOL, _report("sun live", rows[nz], err)


def test_sun_airlight_float32_finite(cache):
    """Every intermediate in float32 (as the GPU): finite everywhere, and close where float32 can be."""
    rows, ref = cache["sun"], cache["sun_ref"]
    with np.errstate(over="raise", invalid="raise", divide="raise"):
        got = k_sun(rows, Float32Ops({}))
    assert got.dtype == np.float32 and np.all(np.isfinite(got))
    ok = ref > FLOOR
    assert np.max(_rel(got[ok], ref[ok])) < TOL          # the strict protocol holds in float32 too


def _sun(pz, vz, d, mu, b, h0, hh, c=0.3, a=1.0, g=0.0):
    return float(dl.sun_airlight(m, *(np.float64(x) for x in (pz, vz, d, mu, c, b, h0, hh, a)), g))


def test_sun_airlight_limits():
    b, h0, hh, mu = 0.02, 100.0, 40.0, 0.6
    p = ref_hg(0.0, 0.3)
    # level ray in the slab: p b e^{-tau_s} (1 - e^{-b D}) / b
    ts = (b * (h0 - 30.0) + b * hh) / mu
    assert _sun(30.0, 0.0, 250.0, mu, b, h0, hh) == pytest.approx(p * math.exp(-ts) * -math.expm1(-b * 250.0), rel=1e-12)
    # level ray in the falloff: the same with beta(z)
    bz = b * math.exp(-(180.0 - h0) / hh)
    ts = b * hh * math.exp(-(180.0 - h0) / hh) / mu
    assert _sun(180.0, 0.0, 900.0, mu, b, h0, hh) == pytest.approx(p * math.exp(-ts) * -math.expm1(-bz * 900.0), rel=1e-12)
    # k = 0 exactly (vz = mu_s): tau_D e^{-tau_s0}
    for hh_ in (0.0, hh):
        td = ref_tau(30.0, mu, 500.0, b, h0, hh_)
        assert _sun(30.0, mu, 500.0, mu, b, h0, hh_) == pytest.approx(p * td * math.exp(-ref_column(30.0, b, h0, hh_) / mu), rel=1e-12)
    # H = 0: above the top nothing scatters; a ray from above the top down into the slab, in closed form
    assert _sun(150.0, 0.5, 1e3, mu, b, h0, 0.0) == 0.0
    d_in = 300.0 - 50.0 / 0.5       # the part below the top of a ray from z = 150 going down at vz = -0.5
    k = 1 + 0.5 / mu
    expect = p * b * -math.expm1(-b * k * d_in) / (b * k)          # tau_s = 0 at the top
    assert _sun(150.0, -0.5, 300.0, mu, b, h0, 0.0) == pytest.approx(expect, rel=1e-12)
    # rays that never reach the layer; the sun on or below the horizon; nothing to scatter
    assert _sun(150.0, 0.2, FAR, mu, b, h0, 0.0) == 0.0
    assert _sun(30.0, 0.2, 100.0, 0.0, b, h0, hh) == 0.0 and _sun(30.0, 0.2, 100.0, -0.4, b, h0, hh) == 0.0
    assert _sun(30.0, 0.2, 0.0, mu, b, h0, hh) == 0.0 and _sun(30.0, 0.2, 100.0, mu, 0.0, h0, hh) == 0.0
    # unbounded fog: the sun never arrives (e^-80 floor); the camera in it sees none of it
    assert _sun(30.0, 0.2, 100.0, mu, b, FAR, 0.0) < 1e-30


def test_sun_airlight_near_limits_continuous():
    """vz -> mu_s, vz -> 0, H -> 0: the kernel's value approaches its value at the limit (no jump at the
    series switch), and stays within 0.5 % of quadrature there."""
    b, h0, hh, mu = 0.02, 100.0, 40.0, 0.6
    for eps in (1e-3, 1e-6, 1e-9, 1e-12):
        for args, lim in (((30.0, mu + eps, 500.0, mu, b, h0, hh), (30.0, mu, 500.0, mu, b, h0, hh)),
                          ((30.0, eps, 500.0, mu, b, h0, hh), (30.0, 0.0, 500.0, mu, b, h0, hh)),
                          ((60.0, 0.3, 500.0, mu, b, h0, eps), (60.0, 0.3, 500.0, mu, b, h0, 0.0))):
            assert _sun(*args) == pytest.approx(_sun(*lim), rel=max(10 * eps, 1e-12))
            q = ref_hg(0.0, 0.3) * ref_sun(*args[:4], *args[4:])
            assert _sun(*args) == pytest.approx(q, rel=TOL)


def test_sun_airlight_wrong_variant_fails(cache):
    """The test can fail: the sun attenuated only down to the layer's top (no fog between the point and
    the top: k = 1), or the sign of vz / mu_s flipped, is far outside the tolerance on the cache."""
    rows, ref = cache["sun"], cache["sun_ref"]
    nz = ref > FLOOR
    r = rows[nz]
    pz, vz, d, mu, c, b, h0, hh, a, g = r.T
    tau_d = dl.optical_depth(m, pz, vz, d, b, h0, hh)
    wrong = a * dl.hg_phase(m, g, c) * dl.sun_integral(m, tau_d, 0.0 * tau_d, tau_d, 1.0 + 0 * tau_d)
    assert np.max(_rel(wrong, ref[nz])) > 100 * TOL
    flipped = a * dl.hg_phase(m, g, c) * dl.sun_integral(
        m, tau_d, dl.sun_depth(m, pz, mu, b, h0, hh), dl.sun_depth(m, pz + vz * d, mu, b, h0, hh) + tau_d, 1 + vz / mu)
    assert np.max(_rel(flipped, ref[nz])) > 100 * TOL


# --- the sky -------------------------------------------------------------------------------------------------

def test_sky_source_and_irradiance_against_quad():
    b, h0, hh = 0.02, 100.0, 40.0
    for z in (0.0, 60.0, 100.0, 130.0, 400.0):
        c = ref_column(z, b, h0, hh)
        src = integrate.quad(lambda mu: math.exp(-c / mu) if mu > 0 else 0.0, 0, 1, epsabs=0, epsrel=1e-12)[0]
        irr = integrate.quad(lambda mu: mu * math.exp(-c / mu) if mu > 0 else 0.0, 0, 1, epsabs=0, epsrel=1e-12)[0]
        assert float(dl.sky_source(m, np.float64(z), b, h0, hh, 0.7)) == pytest.approx(0.35 * src, rel=2e-6)
        assert float(dl.sky_irradiance(m, np.float64(z), b, h0, hh)) == pytest.approx(2 * irr, rel=1e-5)
    assert float(dl.sky_source(m, np.float64(150.0), b, h0, 0.0)) == 0.5          # above a hard top: the whole sky
    assert float(dl.sky_irradiance(m, np.float64(150.0), b, h0, 0.0)) == 1.0


def test_sky_airlight_random(cache):
    rows, ref = cache["sky"], cache["sky_ref"]
    with np.errstate(all="raise"):
        got = k_sky(rows)
    zero = ref == 0.0
    assert np.all(got[zero] == 0.0)
    ok = ref > FLOOR
    err = _rel(got[ok], ref[ok])
    msg = _report("sky_airlight vs quad", rows[ok], err)
    assert err.max() < SKY_TOL, msg
    assert np.max(_rel(k_sky(rows, nodes=3)[ok], ref[ok])) > 10 * SKY_TOL        # the test can fail
    with np.errstate(over="raise", invalid="raise", divide="raise"):
        g32 = k_sky(rows, Float32Ops({}))
    assert g32.dtype == np.float32 and np.all(np.isfinite(g32))
    assert np.percentile(_rel(g32[ok & (rows[:, 6] < FAR)], ref[ok & (rows[:, 6] < FAR)]), 99) < 5e-3
    with np.errstate(over="raise", invalid="raise", divide="raise"):
        x32 = np.concatenate([[0.0], np.geomspace(1e-30, 80, 2001)]).astype(np.float32)
        e32 = dl.expint2(Float32Ops({}), x32), dl.expint3(Float32Ops({}), x32)
    assert np.max(_rel(e32[0], special.expn(2, x32.astype(float)))) < 1e-3      # the float32 root of ``log``
    assert np.max(_rel(e32[1], special.expn(3, x32.astype(float)))) < 1e-3


def test_sky_airlight_live_subset():
    rows = _layer_samples(40, LIVE_SEED + 1)
    ref = reference_sky(rows)
    ok = ref > FLOOR
    assert np.max(_rel(k_sky(rows)[ok], ref[ok])) < SKY_TOL


def test_sky_limits():
    b, h0 = 0.02, 100.0
    # level ray in a deep unbounded fog: S = a/2 E2(inf) = 0; in a slab at depth c: (1/2) E2(c) (1 - e^{-b D})
    c = b * (h0 - 40.0)
    got = float(dl.sky_airlight(m, np.float64(40.0), np.float64(0.0), np.float64(300.0), b, h0, 0.0))
    assert got == pytest.approx(0.5 * special.expn(2, c) * -math.expm1(-b * 300.0), rel=3e-3)
    assert float(dl.sky_airlight(m, np.float64(150.0), np.float64(0.3), np.float64(FAR), b, h0, 0.0)) == 0.0
    assert float(dl.sky_transmittance(m, np.float64(40.0), np.float64(1.0), b, h0, 0.0)) == pytest.approx(
        math.exp(-c), rel=1e-12)
    assert float(dl.sky_transmittance(m, np.float64(40.0), np.float64(0.0), b, h0, 0.0)) < 1e-30   # horizon: opaque
    assert float(dl.sky_transmittance(m, np.float64(150.0), np.float64(1e-7), b, h0, 0.0)) == 1.0


# --- the haze -------------------------------------------------------------------------------------------------

def test_haze_airlight_random(cache):
    rows, ref = cache["haze"], cache["haze_ref"]
    with np.errstate(all="raise"):
        got = k_haze(rows)
    err = _rel(got, ref)
    msg = _report("haze_airlight vs quad", rows, err)
    assert err.max() < HAZE_TOL, msg
    assert np.max(_rel(k_haze(rows, panels=2), ref)) > 5 * HAZE_TOL               # the test can fail
    with np.errstate(over="raise", invalid="raise", divide="raise"):
        g32 = k_haze(rows, Float32Ops({}))
    assert np.all(np.isfinite(g32)) and np.percentile(_rel(g32, ref), 99) < 2e-2


def test_haze_live_subset():
    rng = np.random.default_rng(LIVE_SEED + 2)
    rows = np.array([sample_haze(rng) for _ in range(40)])
    assert np.max(_rel(k_haze(rows), reference_haze(rows))) < HAZE_TOL


def test_haze_depths_and_limits():
    br, bm = 13.5e-6, 2e-5
    # the sun's depth from the ground: (beta_R H_R + beta_M/0.9 H_M) / mu
    assert float(aerial.haze_sun_depth(m, np.float64(0.0), np.float64(0.5), 0.0, br, bm)) == pytest.approx(
        (br * HR + bm / ALB * HM) / 0.5, rel=1e-12)
    # a level ray at 500 m: Koschmieder with the local extinction
    b500 = br * math.exp(-500 / HR) + bm / ALB * math.exp(-500 / HM)
    assert float(aerial.haze_transmittance(m, np.float64(500.0), np.float64(0.0), np.float64(2e4), 0.0, br, bm)) == \
        pytest.approx(math.exp(-b500 * 2e4), rel=1e-12)
    # level ray: the weights are constant, the quadrature exact (up to the cut at optical depth 20)
    got = float(aerial.haze_airlight(m, *(np.float64(x) for x in (500.0, 0.0, 3e4, 0.4, 0.2)), 0.0, br, bm))
    assert got == pytest.approx(ref_haze(500.0, 0.0, 3e4, 0.4, 0.2, br, bm), rel=1e-9)
    assert float(aerial.haze_airlight(m, *(np.float64(x) for x in (500.0, 0.1, 3e4, -0.2, 0.2)), 0.0, br, bm)) == 0.0
    # the flat-Earth limit: the aerosols 2.6 % denser than the round Earth's at the end of a level 20 km ray
    assert aerial.flat_earth_error(20e3, HM) == pytest.approx(math.exp(20e3 ** 2 / (2 * 6.371e6 * HM)) - 1, rel=1e-12)


if __name__ == "__main__":
    build_cache()
    print("wrote", CACHE)
