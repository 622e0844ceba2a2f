"""The sun's shafts in a fog layer (precompute/physics/shafts/shafts.py, "the sun") against adaptive quadrature with
exact visibility: box occluders (buildings) whose shadows are known in closed form (``fog_scenes.occluders.box_hit``);
the expected share is scipy's quad of the layer's single-scattering integrand of the sun (its density, the camera
segment's and the sun's optical depths, written out here) times the exact visibility, over the same without it.
The map is baked by the same closed-form ray casts at its grid points."""
import math

import numpy as np
import pytest
from scipy import integrate

from fog_addon.precompute.physics.daylight import sun_shafts
from fog_addon.precompute.core.ops import NumpyOps
from fog_addon.precompute.core.tables import TableSpec
from fog_scenes.occluders import NO_HIT, box_hit

BETA = 0.02
TOP = 60.0
ELEVATION_DEG = 20.0
AZIMUTH_DEG = 60.0
SUN = np.array([math.cos(math.radians(ELEVATION_DEG)) * math.sin(math.radians(AZIMUTH_DEG)),
                math.cos(math.radians(ELEVATION_DEG)) * math.cos(math.radians(AZIMUTH_DEG)),
                math.sin(math.radians(ELEVATION_DEG))])
BOXES = [((8.0, 20.0, 0.0), (14.0, 26.0, 30.0)), ((-20.0, 40.0, 0.0), (-10.0, 55.0, 45.0)),
         ((15.0, 60.0, 0.0), (17.0, 90.0, 25.0)), ((-1.0, 30.0, 0.0), (-0.6, 30.4, 12.0))]   # the last: a 0.4 m pole
CAMERA = np.array([0.0, 0.0, 1.6])
REGION = np.array([[x, y, z] for x in (-150.0, 150.0) for y in (-20.0, 300.0) for z in (0.0, TOP)])


def visible(points):
    """1 where the sun reaches each world point (N, 3) past every box."""
    hit = np.full(len(points), NO_HIT)
    for lo, hi in BOXES:
        hit = np.minimum(hit, box_hit(points, SUN, lo, hi))
    return (hit >= NO_HIT).astype(float)


@pytest.fixture(scope="module")
def sun_map():
    frame, (w, h) = sun_shafts.sun_frame(SUN, REGION)
    origins = sun_shafts.sun_map_origins(frame, w, h).reshape(-1, 3)
    depth = np.full(len(origins), NO_HIT)
    for lo, hi in BOXES:
        depth = np.minimum(depth, box_hit(origins, frame.forward, lo, hi))
    spec = TableSpec("sun", w, h)
    return spec, frame, depth.reshape(h, w)


def density(z, falloff):
    return BETA if z < TOP else (BETA * math.exp(-(z - TOP) / falloff) if falloff else 0.0)


def column(z, falloff):
    """Optical depth straight up from height z."""
    if falloff:
        return BETA * (max(TOP - z, 0.0) + falloff * math.exp(-max(z - TOP, 0.0) / falloff))
    return BETA * max(TOP - z, 0.0)


def expected_share(direction, length, falloff=0.0):
    """quad of the sun's single scattering with exact visibility over quad without (module doc)."""
    direction = np.asarray(direction, float)

    def tau_view(t):
        return integrate.quad(lambda s: density(CAMERA[2] + s * direction[2], falloff), 0.0, t, limit=200)[0]

    def integrand(t, shadowed):
        x = CAMERA + t * direction
        f = density(x[2], falloff) * math.exp(-tau_view(t) - column(x[2], falloff) / SUN[2])
        return f * (visible(x[None])[0] if shadowed else 1.0)
    grid = np.linspace(0.0, length, 801)
    h = visible(CAMERA + grid[:, None] * direction)
    edges = list(grid[1:][np.diff(h) != 0])
    num = sum(integrate.quad(integrand, a, b, args=(True,), limit=200, epsrel=1e-8)[0]
              for a, b in zip([0.0] + edges, edges + [length]))
    den = integrate.quad(integrand, 0.0, length, args=(False,), limit=200, epsrel=1e-10)[0]
    return num / den


def got_share(sun_map, direction, length, nodes=24):
    """The 2 x 2 interleaved mean of the shares (the compositor's ``_interleave_mean``): 4 nodes sets."""
    spec, frame, depth = sun_map
    m = NumpyOps({"sun": depth})
    direction = np.asarray(direction, float)
    rate = sun_shafts.sun_attenuation_rate(m, BETA, direction[2], SUN[2])
    return np.mean([sun_shafts.sun_lit_share(m, spec, frame, CAMERA, direction, length, rate, nodes, shift)
                    for shift in (0.125, 0.375, 0.625, 0.875)])


def _dir(target):
    d = np.asarray(target, float) - CAMERA
    return d / np.linalg.norm(d)


RAYS = [(_dir((10.0, 60.0, 5.0)), 150.0), (_dir((0.0, 100.0, 10.0)), 250.0), (_dir((-15.0, 80.0, 20.0)), 300.0),
        (_dir((12.0, 40.0, 1.0)), 40.0), (_dir((-5.0, 50.0, 3.0)), 120.0), (_dir((5.0, 50.0, 60.0)), 60.0)]


@pytest.mark.parametrize("falloff", [0.0, 20.0])
@pytest.mark.parametrize("ray", range(len(RAYS)))
def test_sun_share_matches_quadrature(sun_map, ray, falloff):
    direction, length = RAYS[ray]
    want = expected_share(direction, length, falloff)
    got = got_share(sun_map, direction, length)
    assert 0.0 <= got <= 1.0
    assert want < 0.98 or ray == 5, "a ray whose share does not test the shadows"
    assert abs(got - want) < 0.02, (want, got)


def test_open_ray_is_exactly_one(sun_map):
    direction = _dir((100.0, 10.0, 2.0))   # to the right, on the sun's side of every box
    assert visible(CAMERA + np.linspace(0.0, 100.0, 1000)[:, None] * direction).min() == 1.0
    got = got_share(sun_map, direction, 100.0)
    assert got == 1.0


def test_node_places_are_the_quantiles():
    """Nodes at the quantiles of e^{-a t}: the density's integral up to each is u, from either sign of a."""
    m = NumpyOps()
    u = np.linspace(0.05, 0.95, 7)
    for A in (-30.0, -2.0, -1e-5, 0.0, 1e-5, 3.0, 39.0):
        t = sun_shafts.sun_node_place(m, u, A)
        cdf = u if abs(A) < 1e-9 else (1.0 - np.exp(-A * t)) / (1.0 - math.exp(-A))
        assert np.all(np.isfinite(t)) and np.allclose(cdf, u, atol=2e-3), (A, t)


def ray_sun_glow(origin, direction, length, shadowed, g=0.0):
    """quad of the sun's single scattering along a ray from ``origin`` (hard top; the sun's transmittance to the
    origin's height divided out), with the exact visibility if ``shadowed``; the phase function of g."""
    direction = np.asarray(direction, float)
    mu = float(np.dot(direction, SUN))
    phase = (1 - g * g) / (1 + g * g - 2 * g * mu) ** 1.5 if g else 1.0

    def integrand(t):
        x = origin + t * direction
        return BETA * math.exp(-BETA * t - BETA * (TOP - x[2]) / SUN[2] + BETA * (TOP - origin[2]) / SUN[2])
    grid = np.linspace(0.0, length, 401)
    h = visible(origin + grid[:, None] * direction) if shadowed else np.ones(len(grid))
    edges = list(grid[1:][np.diff(h) != 0])
    total = 0.0
    for a, b in zip([0.0] + edges, edges + [length]):
        if visible((origin + 0.5 * (a + b) * direction)[None])[0] or not shadowed:
            total += integrate.quad(integrand, a, b, limit=100, epsrel=1e-7)[0]
    return phase * total


def expected_surface_share(point, normal, g, n_u=8, n_phi=16):
    """The cos / pi-weighted hemisphere of ``ray_sun_glow`` with shadows over it without (midpoints in sin^2 and
    azimuth: the density cos / pi), each ray to the layer's top or the ground, at most SUN_REACH mean free paths."""
    normal = np.asarray(normal, float)
    t1 = np.cross(normal, (0.0, 0.0, 1.0)) + np.cross(normal, (0.0, 1.0, 0.0)) * 0.01
    t1 /= np.linalg.norm(t1)
    t2 = np.cross(normal, t1)
    lit = total = 0.0
    for i in range(n_u):
        r2 = (i + 0.5) / n_u
        for j in range(n_phi):
            phi = 2 * math.pi * (j + 0.5) / n_phi
            u = t1 * math.cos(phi) * math.sqrt(r2) + t2 * math.sin(phi) * math.sqrt(r2) + normal * math.sqrt(1 - r2)
            length = (TOP - point[2]) / u[2] if u[2] > 1e-6 else (point[2] / -u[2] if u[2] < -1e-6 else 1e9)
            length = min(length, sun_shafts.SUN_REACH / BETA)
            lit += ray_sun_glow(point, u, length, True, g)
            total += ray_sun_glow(point, u, length, False, g)
    return lit / total


SURFACES = [((-3.0, 12.0, 0.0), (0.0, 0.0, 1.0)), ((-30.0, 20.0, 0.0), (0.0, 0.0, 1.0)),
            ((8.0, 23.0, 10.0), (-1.0, 0.0, 0.0))]


@pytest.mark.parametrize("surface", range(len(SURFACES)))
def test_sun_surface_share_matches_quadrature(sun_map, surface):
    point, normal = (np.asarray(v, float) for v in SURFACES[surface])
    g = 0.7
    want = expected_surface_share(point, normal, g)
    spec, frame, depth = sun_map
    m = NumpyOps({"sun": depth})
    parts = [sun_shafts.sun_surface_share(m, spec, frame, point, normal, CAMERA, BETA, SUN, g, TOP, 0.0, shift)
             for shift in (np.arange(16) + 0.5) / 16]
    got = sum(p[0] for p in parts) / sum(p[1] for p in parts)
    print(surface, want, got)
    assert want < 0.97, "a surface whose share does not test the shadows"
    assert abs(got - want) < 0.03, (want, got)


def test_degenerate_rays_give_finite_shares(sun_map):
    """Straight up and down, level, a sun on the horizon, no length, a vanishing or a huge density: S in [0, 1]."""
    spec, frame, depth = sun_map
    m = NumpyOps({"sun": depth})
    for direction in ((0.0, 0.0, 1.0), (0.0, 0.0, -1.0), (0.0, 1.0, 0.0), _dir((5.0, 50.0, 3.0))):
        for mu_s in (1e-6, 0.02, 1.0):
            for beta in (1e-12, BETA, 1e3):
                for length in (0.0, 1e-9, 40.0, 1e30):
                    rate = sun_shafts.sun_attenuation_rate(m, beta, direction[2], mu_s)
                    s = sun_shafts.sun_lit_share(m, spec, frame, CAMERA, np.asarray(direction), min(length, 6.0 / beta),
                                             rate, 24, 0.5)
                    assert np.isfinite(s) and 0.0 <= s <= 1.0, (direction, mu_s, beta, length, s)


def test_sun_straight_up_has_a_frame():
    frame, size = sun_shafts.sun_frame((0.0, 0.0, 1.0), REGION)
    assert np.allclose(frame.forward, (0.0, 0.0, -1.0)) and np.isclose(np.dot(frame.right, frame.up), 0.0)
    assert sun_shafts.sun_frame(SUN, REGION, np.array([[1000.0, 1000.0, 0.0], [1001.0, 1001.0, 1.0]])) is None
