"""Multiple scattering around a point source (issue 28): the Monte Carlo transport that bakes the
multiply-scattered field (``precompute/physics/point/point_source_mc.py``) against independent closed forms and
quadrature, and Narasimhan et al.'s APSF series (``precompute/apsf.py``, Eq. 24-27) against its own limits.

Expected values: the single-scattering radiance at distance T from an isotropic point source, by scipy
quadrature of its line integral (Sun et al. 2005 Eq. 5 written out, Henyey-Greenstein phase); the series'
m = 1 term in a medium without absorption, I0 / T^2 (Eq. 25: beta_1 = 0, alpha_1 = 2); Legendre polynomials
from numpy.  Figures (the seed's own check against our Monte Carlo): docs/measurements/2026-11-27-apsf.md.
"""
import math

import numpy as np
import pytest
from numpy.polynomial import legendre
from scipy.integrate import quad

from tools.research import apsf
from fog_addon.precompute.physics.point import point_source_mc as mc


def single_scattering_quadrature(T, theta, q, albedo):
    """I_1(T, theta) / I0 at extinction 1: int_0^inf W0 e^{-t - d} p_HG(cos alpha) / d^2 dt, the viewer at
    distance T from the source looking theta away from it (d: the source to the ray point, alpha the
    scattering angle there)."""
    c = math.cos(theta)

    def f(t):
        d2 = T * T + t * t - 2.0 * T * t * c
        d = math.sqrt(d2)
        ca = (T * c - t) / d
        p = (1.0 - q * q) / (4.0 * math.pi * (1.0 + q * q - 2.0 * q * ca) ** 1.5)
        return albedo * math.exp(-t - d) * p / d2
    foot = max(T * c, 0.0)
    return quad(f, 0.0, foot, limit=200)[0] + quad(f, foot, 60.0, limit=200)[0] if foot else quad(f, 0.0, 60.0,
                                                                                                     limit=200)[0]


def annulus_means(values, edges_deg, theta_ranges):
    """Solid-angle weighted means of bin values over angle ranges (deg)."""
    solid = np.cos(np.radians(edges_deg[:-1])) - np.cos(np.radians(edges_deg[1:]))
    out = []
    for lo, hi in theta_ranges:
        k = (edges_deg[:-1] >= lo) & (edges_deg[1:] <= hi)
        out.append(float(np.sum(values[k] * solid[k]) / np.sum(solid[k])))
    return np.array(out)


RANGES = [(0.25, 1.0), (1.0, 4.0), (4.0, 15.0), (15.0, 45.0), (45.0, 120.0)]


@pytest.mark.parametrize("T,q,albedo", [(1.0, 0.8, 0.9), (3.0, 0.5, 0.95)])
def test_monte_carlo_single_scattering_matches_quadrature(T, q, albedo):
    """The transport's order-1 radiance (a crossing estimator) is the closed line integral, annulus by
    annulus, within its noise (100 000 photons: about 2 %)."""
    r = mc.radiance([T], q, albedo, photons=100_000, seed=3, max_order=2)
    edges = r["edges"]
    got = annulus_means(r[T][0], edges, RANGES)
    want = []
    for lo, hi in RANGES:   # the union of the whole bins annulus_means takes
        inside = (edges[:-1] >= lo) & (edges[1:] <= hi)
        lo, hi = edges[:-1][inside].min(), edges[1:][inside].max()
        num = quad(lambda th: single_scattering_quadrature(T, th, q, albedo) * math.sin(th),
                   math.radians(lo), math.radians(hi), limit=100)[0]
        want.append(num / (math.cos(math.radians(lo)) - math.cos(math.radians(hi))))
    np.testing.assert_allclose(got, want, rtol=0.06)


def test_multiple_scattering_vanishes_without_albedo():
    """Order >= 2 carries W0^2 against order 1's W0: at W0 = 0.02 it is a few percent of the single."""
    r = mc.radiance([2.0], 0.5, 0.02, photons=50_000, seed=4)
    single, multiple = (annulus_means(x, r["edges"], RANGES) for x in r[2.0])
    assert np.all(multiple < 0.1 * single)
    assert np.all(multiple > 0.0)


def test_multiple_scattering_grows_with_distance_and_albedo():
    """The multiply scattered share of the glow rises with T and with W0 (what the renderer adds in dense fog)."""
    r = mc.radiance([1.0, 4.0], 0.85, 0.95, photons=50_000, seed=5)
    share = {T: annulus_means(r[T][1], r["edges"], RANGES) / annulus_means(r[T][0], r["edges"], RANGES)
             for T in (1.0, 4.0)}
    assert np.all(share[4.0] > share[1.0])
    r2 = mc.radiance([4.0], 0.85, 0.6, photons=50_000, seed=5)
    low = annulus_means(r2[4.0][1], r2["edges"], RANGES) / annulus_means(r2[4.0][0], r2["edges"], RANGES)
    assert np.all(low < share[4.0])


def test_hg_sampling_has_mean_cosine_q():
    rng = np.random.default_rng(0)
    for q in (0.0, 0.5, 0.9):
        assert abs(mc.sample_hg(rng, q, 400_000).mean() - q) < 4e-3


def test_legendre_table_matches_numpy():
    mu = np.linspace(-1.0, 1.0, 11)
    table = apsf.legendre_table(mu, 8)
    for m in range(8):
        np.testing.assert_allclose(table[m], legendre.legval(mu, np.eye(8)[m]), atol=1e-12)


def test_series_first_term_is_inverse_square_without_absorption():
    """Eq. 25 at W0 = 1: beta_1 = 3 (1 - W0) = 0 and alpha_1 = 2, so g_1 = I0 / T^2."""
    T = np.array([1.5, 3.0, 8.0])
    g = apsf.apsf_g(T, 0.7, 1.0, 4)
    np.testing.assert_allclose(g[1], 1.0 / T ** 2, rtol=1e-12)
    assert np.all(g[0] == 0.0)


def test_series_converges_above_one_and_refuses_below():
    mu = np.cos(np.radians([0.5, 5.0, 60.0]))
    a, b = apsf.apsf_series(3.0, mu, 0.8, 0.95, terms=100), apsf.apsf_series(3.0, mu, 0.8, 0.95, terms=400)
    np.testing.assert_allclose(a, b, rtol=1e-9)
    with pytest.raises(ValueError, match="T > 1"):
        apsf.apsf_series(1.0, mu, 0.8, 0.95)
