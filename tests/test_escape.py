"""Dense Fog beside surfaces (``precompute/physics/point/escape.py``), numpy only: the traced share of a light's
field that a floor under it leaves, its second order against a dense quadrature of the same integral
(Gauss-Legendre, the floor's cut exact), every order against the second alone, nothing in the way exactly 1; the
photons' directions against their distributions; the escape fraction against its closed form.

The second order at a surface point x (normal n): sources at y = light + r u, density beta e^{-beta r} where y is
before the floor, each adding HG(u . (x - y)/d) max(n . (y - x)/d, 0) e^{-beta d} / max(d, NEAR_FRACTION
|x - light|)^2; the share is its sum over the points with the floor over the same without it."""
import math

import numpy as np
import pytest
from scipy import integrate, special

from fog_addon.precompute.physics.point import escape
from fog_addon.precompute.physics.shafts import shaft_maps

DIRECTIONS, _ = shaft_maps.point_map_casts(48, 24)
LIGHT = np.array([0.0, 0.0, 1.0])   # 1 m above the floor z = 0


def _floor_depth(directions, height=1.0):
    dz = directions[:, 2]
    return np.where(dz < 0.0, height / np.maximum(-dz, 1e-12), np.inf)


def _quadrature(x, beta, g, height, normal, n=96):
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
        cos_in = np.maximum(-(v * normal).sum(-1) / d, 0.0)
        f = escape.hg_phase(g, cos) * cos_in * np.exp(-beta * d) / np.maximum(d2, near2)   # ds = beta e^{-beta r} dr
        inner = (f * w[None, None, :]).sum(-1) * (0.5 * top)[:, None]
        out.append(float((inner.sum(-1) * (2 * math.pi / n) * w_mu).sum()))
    return out


POINTS = np.array([[3.0, 0.0, 1.0], [0.0, 2.0, 0.3], [-2.0, -2.0, 2.5]])
NORMALS = np.array([[-1.0, 0.0, 0.0], [0.0, -0.6, 0.8], [0.6, 0.0, -0.8]])   # each facing the light


def _points(points=POINTS, normals=NORMALS):
    """Receivers of surface points alone, each weighing as the quadrature's (albedo pi, at the camera)."""
    n = len(points)
    return escape.Receivers(np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0), points, normals, np.full(n, math.pi),
                            np.zeros(n))


def _floor_free(origins, directions, lengths):
    """True where the segment stays above the floor z = 0 (``traced_share``'s ``free``)."""
    end = origins[:, 2] + directions[:, 2] * lengths
    return (origins[:, 2] > 0.0) & (end > 0.0)


def _traced(receivers, beta, g, albedo=1.0, free=_floor_free, orders=1, photons=4096, seed=3):
    rng = np.random.default_rng(seed)
    emitted = escape.emitted_directions(photons, rng)
    kept, unbounded = escape.traced_share(LIGHT, emitted, receivers, beta, g, albedo, free, orders=orders, rng=rng)
    return kept / unbounded


def test_nothing_in_the_way_leaves_the_whole_field():
    rays = escape.Receivers(np.array([[0.0, -6.0, 1.5]] * 2), np.array([[0.0, 1.0, 0.0], [0.6, 0.8, 0.0]]),
                            np.array([12.0, 30.0]), POINTS, NORMALS, np.full(3, 0.5), np.full(3, 4.0))
    assert _traced(rays, 0.1, 0.5, free=None, orders=6, photons=256) == 1.0


@pytest.mark.parametrize("g", [0.0, 0.7])
def test_second_order_over_a_floor_against_quadrature(g):
    beta = 0.2
    with_floor = without = 0.0
    for x, n in zip(POINTS, NORMALS):
        a, b = _quadrature(x, beta, g, 1.0, n)
        with_floor, without = with_floor + a, without + b
    want = with_floor / without
    got = _traced(_points(), beta, g)
    print(f"g {g}: share {got:.4f}, quadrature {want:.4f}")
    assert abs(got - want) < 0.02, (got, want)


RAY_CAMERA = np.array([[0.0, -6.0, 1.5], [2.0, -5.0, 0.5]])
RAY_DIRECTION = np.array([[0.0, 1.0, 0.0], [-0.28, 0.96, 0.0]])
RAY_LENGTH = np.array([12.0, 9.0])


def _ray_integral(y, u, c, o, length, beta, g):
    """The second order a view ray (origin c, unit o, visible for ``length`` m) gathers from a scattering at y of a
    photon going along u, 1/m^2: beta / 4 pi int_0^L HG(u . (x - y)/d) e^{-beta (t + d)} / d^2 dt, x = c + t o,
    by adaptive quadrature (scipy), the ray's nearest point to y a break point."""
    def f(t):
        v = c + t * o - y
        d = np.linalg.norm(v)
        return beta / (4 * math.pi) * escape.hg_phase(g, v @ u / d) * math.exp(-beta * (t + d)) / (d * d)
    near = min(max(float((y - c) @ o), 1e-3), length - 1e-3)
    return integrate.quad(f, 0.0, length, points=[near], limit=400)[0]


@pytest.mark.parametrize("g", [0.0, 0.7])
def test_a_scattering_sends_the_rays_their_second_order(g):
    """What a scattering sends the view rays (``ray_weights`` draws the rays, ``ray_sample`` an equiangular point of
    each), photon by photon, against adaptive quadrature of each ray's integral: the mean over 40 draws within 2 %
    of it for the photons' median, and their sum within 2 %.  (Over the photons' positions the sum has a heavy
    tail, the 1/h of a ray passing h from a scattering: that part is the share's, a ratio over the same photons.)"""
    beta, rng = 0.2, np.random.default_rng(5)
    rays = escape.Receivers(RAY_CAMERA, RAY_DIRECTION, RAY_LENGTH, np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0),
                            np.zeros(0))
    heading = escape.emitted_directions(200, rng)
    position = LIGHT + (-np.log1p(-rng.random(200)) / beta)[:, None] * heading
    want = np.array([sum(_ray_integral(y, u, c, o, n, beta, g) for c, o, n in zip(RAY_CAMERA, RAY_DIRECTION,
                                                                                  RAY_LENGTH))
                     for y, u in zip(position, heading)])
    weights, geometry = escape.ray_weights(position, heading, rays, beta, g)
    got = np.mean([escape.send_to_receivers(position, heading, weights, weights.sum(axis=1), rays, len(RAY_LENGTH),
                                       list(geometry), beta, g, 4, rng)[0].sum(axis=1) for _ in range(40)], axis=0)
    ratio = got / want
    print(f"g {g}: median ratio {np.median(ratio):.4f}, sums {got.sum():.5g} and {want.sum():.5g}")
    assert abs(np.median(ratio) - 1.0) < 0.02
    assert got.sum() == pytest.approx(want.sum(), rel=0.02)


def test_later_orders_lose_more_to_the_floor():
    """Light scattered once keeps scattering down into the floor: every order's share is below the second's alone,
    by more than the estimate's spread (seeds)."""
    rays = escape.Receivers(np.array([[0.0, -8.0, 1.6]] * 3), np.array([[0.0, 1.0, 0.0], [0.3, 0.95, -0.1],
                                                                          [-0.3, 0.95, -0.05]]),
                            np.array([20.0, 12.0, 25.0]), POINTS, NORMALS, np.full(3, 0.5), np.full(3, 6.0))
    rays = rays._replace(direction=rays.direction / np.linalg.norm(rays.direction, axis=1, keepdims=True))
    second = [_traced(rays, 0.15, 0.0, orders=1, photons=1024, seed=s) for s in (1, 2)]
    every = [_traced(rays, 0.15, 0.0, orders=16, photons=1024, seed=s) for s in (1, 2)]
    print("second order", second, "every order", every)
    assert max(every) < min(second) - 0.05, (second, every)


def test_nothing_reaches_the_fog_behind_an_endless_wall():
    """A wall x = 2 between the lamp and everything the camera sees: no photon's flight and no scattering's light
    crosses it, so the share is exactly 0."""
    def wall_free(origins, directions, lengths):
        end = origins[:, 0] + directions[:, 0] * lengths
        return (origins[:, 0] < 2.0) & (end < 2.0)
    rays = escape.Receivers(np.array([[6.0, -6.0, 1.5]] * 2), np.array([[0.0, 1.0, 0.0], [0.6, 0.8, 0.0]]),
                            np.array([12.0, 20.0]), np.array([[3.0, 1.0, 0.5]]), np.array([[-1.0, 0.0, 0.0]]),
                            np.array([0.5]), np.array([7.0]))
    assert _traced(rays, 0.1, 0.0, free=wall_free, orders=8, photons=512) == 0.0


def test_photons_leave_as_the_light_emits():
    rng = np.random.default_rng(5)
    axis = np.array([0.3, -0.2, -0.9])
    axis /= np.linalg.norm(axis)
    sphere = escape.emitted_directions(20000, rng)
    cone = escape.emitted_directions(20000, rng, axis, math.cos(math.radians(30.0)))
    lambert = escape.emitted_directions(20000, rng, axis, lambertian=True)
    assert np.allclose(np.linalg.norm(sphere, axis=1), 1.0)
    assert np.abs(sphere.mean(axis=0)).max() < 0.02                                  # uniform: no mean direction
    assert (cone @ axis).min() >= math.cos(math.radians(30.0)) - 1e-9
    assert (cone @ axis).mean() == pytest.approx((1 + math.cos(math.radians(30.0))) / 2, abs=0.005)
    assert (lambert @ axis).mean() == pytest.approx(2.0 / 3.0, abs=0.005)               # E[cos] of cos-weighted


@pytest.mark.parametrize("g", [0.0, 0.6, -0.4])
def test_scattered_directions_follow_henyey_greenstein(g):
    rng = np.random.default_rng(7)
    heading = np.tile([0.0, 0.0, 1.0], (40000, 1))
    out = escape.hg_scattered(heading, g, rng)
    assert np.allclose(np.linalg.norm(out, axis=1), 1.0)
    assert out[:, 2].mean() == pytest.approx(g, abs=0.01)                              # HG's mean cosine is g


@pytest.mark.parametrize("beta", [0.08, 0.3])
def test_escape_fraction_over_a_floor_against_its_closed_form(beta):
    directions, _ = shaft_maps.point_map_casts(128, 64)
    got = escape.escape_fraction(beta, _floor_depth(directions, 3.0), np.ones(len(directions)))
    want = 1.0 - 0.5 * special.expn(2, beta * 3.0)
    assert abs(got - want) < 0.005, (got, want)
