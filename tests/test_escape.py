"""Dense Fog beside surfaces (``precompute/physics/point/escape.py``), numpy only: the second order's share of a
light's field that a floor under it leaves, against a dense quadrature of the same integral (Gauss-Legendre, the floor's cut exact), and the
escape fraction against its closed form.

The second order at a receiver x: sources at y = light + r u, density beta e^{-beta r} where y is before the
floor, each adding HG(u . (x - y)/d) e^{-beta d} / max(d, NEAR_FRACTION |x - light|)^2; the share is its sum over
the receivers with the floor over the same without it."""
import math

import numpy as np
import pytest
from scipy import special

from fog_addon.precompute.physics.point import escape
from fog_addon.precompute.physics.shafts import shaft_maps

DIRECTIONS, _ = shaft_maps.point_map_casts(48, 24)
LIGHT = np.array([0.0, 0.0, 1.0])   # 1 m above the floor z = 0


def _floor_depth(directions, height=1.0):
    dz = directions[:, 2]
    return np.where(dz < 0.0, height / np.maximum(-dz, 1e-12), np.inf)


def _quadrature(x, beta, g, height, n=160):
    """(with the floor, without) at receiver x: Gauss-Legendre in mu = cos(polar angle) and in s = 1 - e^{-beta r}
    up to the floor (the cut exact in each direction), the trapezoid rule in longitude (periodic)."""
    near2 = (escape.NEAR_FRACTION * np.linalg.norm(x - LIGHT)) ** 2
    t, w = np.polynomial.legendre.leggauss(n)
    mu, w_mu = t, w                                        # on [-1, 1]
    phi = 2 * math.pi * np.arange(n) / n
    sin = np.sqrt(1 - mu * mu)
    u = np.stack([sin[:, None] * np.cos(phi)[None, :], sin[:, None] * np.sin(phi)[None, :],
                  np.broadcast_to(mu[:, None], (n, n))], axis=-1)             # (n_mu, n_phi, 3)
    out = []
    for floor in (True, False):
        top = np.where(floor & (mu < 0), -np.expm1(-beta * height / np.maximum(-mu, 1e-12)), 1.0)   # s at the cut
        s = 0.5 * (t[None, :] + 1.0) * top[:, None]                                  # (n_mu, n_s)
        r = -np.log1p(-np.minimum(s, 1 - 1e-15)) / beta
        y = LIGHT + r[:, None, :, None] * u[:, :, None, :]                           # (n_mu, n_phi, n_s, 3)
        v = x - y
        d2 = (v * v).sum(-1)
        d = np.sqrt(d2)
        cos = (v * u[:, :, None, :]).sum(-1) / d
        f = escape.hg_phase(g, cos) * np.exp(-beta * d) / np.maximum(d2, near2)      # ds = beta e^{-beta r} dr
        inner = (f * w[None, None, :]).sum(-1) * (0.5 * top)[:, None]
        out.append(float((inner.sum(-1) * (2 * math.pi / n) * w_mu).sum()))
    return out


def test_nothing_in_the_way_leaves_the_whole_field():
    x = np.array([[3.0, 0.5, 1.2], [0.2, -4.0, 2.0]])
    share = escape.second_order_share(LIGHT, DIRECTIONS, np.ones(len(DIRECTIONS)), np.full(len(DIRECTIONS), np.inf),
                                      x, 0.1, 0.5)
    assert share == pytest.approx(1.0, abs=1e-12)


@pytest.mark.parametrize("g", [0.0, 0.7])
def test_second_order_share_over_a_floor_against_quadrature(g):
    beta = 0.2
    receivers = np.array([[3.0, 0.0, 1.0], [0.0, 2.0, 0.3], [-2.0, -2.0, 2.5]])
    with_floor = without = 0.0
    for x in receivers:
        a, b = _quadrature(x, beta, g, 1.0)
        with_floor, without = with_floor + a, without + b
    want = with_floor / without
    got = escape.second_order_share(LIGHT, DIRECTIONS, np.ones(len(DIRECTIONS)), _floor_depth(DIRECTIONS),
                                    receivers, beta, g)
    print(f"g {g}: share {got:.4f}, quadrature {want:.4f}")
    assert abs(got - want) < 0.03, (got, want)


@pytest.mark.parametrize("beta", [0.08, 0.3])
def test_escape_fraction_over_a_floor_against_its_closed_form(beta):
    directions, _ = shaft_maps.point_map_casts(128, 64)
    got = escape.escape_fraction(beta, _floor_depth(directions, 3.0), np.ones(len(directions)))
    want = 1.0 - 0.5 * special.expn(2, beta * 3.0)
    assert abs(got - want) < 0.005, (got, want)
