"""Area lights' glow (fog_addon/precompute/physics/area/area.py) against quadrature over the emitter.

The cache tests/data/area_reference.npz holds 2000 random rays (tools/area_reference.py, independent of
fog_addon: Gauss-Legendre over the emitter's area graded towards the fog point's foot, scipy's adaptive
quadrature along the ray); ``test_cache_is_sound`` recomputes some of them.  Regenerate with

    .venv/bin/python tools/area_reference.py --n 2000 --out tests/data/area_reference.npz
"""
import math
import pathlib
import sys

import numpy as np
import pytest

from fog_addon.precompute.model import rungs
from fog_addon.precompute.physics.area import area
from fog_addon.precompute.physics.point import model
from fog_addon.precompute.core.ops import NumpyOps

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))
import area_reference  # noqa: E402

M = NumpyOps()
BANDS = ((0.0, 0.5), (0.5, 1.0), (1.0, 2.0))   # the ray's distance to the emitter, in half-diagonals


@pytest.fixture(scope="module")
def cache():
    data = np.load(area_reference.CACHE)
    return data["params"], data["values"]


def _kernel(params, nodes=area.NODES):
    beta, g, a, b, d_vp = params[:, :5].T
    o, u = params[:, 5:8], params[:, 8:11]
    d_vp = np.where(np.isinf(d_vp), model.FAR, d_vp)
    d_sv, along, h = model.ray_light_geometry(M, o, u, np.zeros(3))
    out = np.zeros(len(params))
    for gg in np.unique(g):
        k = g == gg
        out[k] = area.airlight(M, beta[k], d_sv[k], along[k], h[k], d_vp[k], *o[k].T, *u[k].T, a[k], b[k],
                               g=float(gg), nodes=nodes)
    return out


def _nearness(params):
    """Each ray's least distance to the emitter's rectangle over its length (to 100 m), in half-diagonals."""
    out = []
    for row in params:
        a, b, d_vp, o, u = row[2], row[3], row[4], row[5:8], row[8:11]
        t = np.linspace(0.0, min(d_vp, 100.0), 4001)[:, None]
        x = o + t * u
        foot = np.clip(x, [-a, -b, 0.0], [a, b, 0.0])
        out.append(np.min(np.linalg.norm(x - foot, axis=1)) / math.hypot(a, b))
    return np.array(out)


def test_cache_is_sound(cache):
    """Some cached values recomputed by the tool agree (the cache is what the tool computes)."""
    params, values = cache
    for i in range(0, len(params), 250):
        assert area_reference._one(params[i]) == pytest.approx(values[i], rel=1e-9, abs=1e-300)


def test_reference_emitter_quadrature_is_the_solid_angle():
    """The reference's area integral in clear isotropic fog is the emitter's solid angle / (4 pi), which the
    closed form of ``area.solid_angle_rectangle`` gives: two independent computations of one quantity."""
    rng = np.random.default_rng(3)
    for _ in range(40):
        a, b = rng.uniform(0.05, 2.0, 2)
        x = np.array([rng.uniform(-3, 3), rng.uniform(-3, 3), -10.0 ** rng.uniform(-3, 1)])
        ref = area_reference.inscatter(x, np.array([0.0, 0.0, 1.0]), a, b, 0.0, 0.0) * 4.0 * math.pi
        assert float(area.solid_angle_rectangle(M, *x, a, b)) == pytest.approx(ref, rel=1e-9)


def test_solid_angle_in_the_emitters_plane():
    """Finite in the emitter's plane: 2 pi on the rectangle, 0 beside it (atan2, no division by z)."""
    assert float(area.solid_angle_rectangle(M, 0.1, 0.1, 0.0, 0.5, 0.25)) == pytest.approx(2.0 * math.pi)
    assert float(area.solid_angle_rectangle(M, 0.1, 0.1, -0.0, 0.5, 0.25)) == pytest.approx(2.0 * math.pi)
    assert float(area.solid_angle_rectangle(M, 0.9, 0.1, 0.0, 0.5, 0.25)) == pytest.approx(0.0, abs=1e-12)


def test_glow_against_quadrature_far_from_the_emitter(cache):
    """Rays passing two half-diagonals or more from the emitter: within ``rungs.area_glow_error(g)``; the
    median far tighter."""
    params, values = cache
    near = _nearness(params)
    got = _kernel(params)
    g = params[:, 1]
    for gg in np.unique(g):
        k = (g == gg) & (values > 0.0) & (near >= 2.0)
        rel = np.abs(got[k] - values[k]) / values[k]
        assert k.sum() > 250
        assert rel.max() <= rungs.area_glow_error(gg), (gg, rel.max())
        assert np.median(rel) < 5e-3, (gg, np.median(rel))


def test_glow_near_the_emitter_as_documented(cache):
    """Nearer the emitter the errors grow with the phase function's forward peak; they stay within the
    figures ``rungs.AREA_NEAR_ERRORS`` states (and the isotropic ones within 7 %)."""
    params, values = cache
    near = _nearness(params)
    got = _kernel(params)
    g = params[:, 1]
    for gg, bounds in rungs.AREA_NEAR_ERRORS.items():
        for (lo, hi), bound in zip(BANDS, bounds):
            k = (g == gg) & (values > 0.0) & (near >= lo) & (near < hi)
            assert k.sum() >= 15
            rel = np.abs(got[k] - values[k]) / values[k]
            assert rel.max() <= bound, (gg, lo, hi, rel.max())


def test_glow_zero_where_the_reference_is(cache):
    """Rays that never pass in front of the emitter get no glow."""
    params, values = cache
    got = _kernel(params)
    assert (values == 0.0).sum() > 5
    assert np.all(got[values == 0.0] == 0.0)


def test_more_points_do_not_help(cache):
    """The ray's 8 points against 24, band by band: the largest error against the reference moves by under
    10 % of itself plus 0.01 (what is left is the emitter model's, not the quadrature's), for g up to 0.7.  At
    g = 0.9 the ray's points count too: beyond two half-diagonals 4.8 % with 8 points, 3.0 % with 24."""
    params, values = cache
    near = _nearness(params)
    errs = [np.abs(_kernel(params, nodes=n) - values) / np.where(values > 0, values, 1.0) for n in (area.NODES, 24)]
    for gg in np.unique(params[:, 1])[:-1]:
        assert gg <= 0.7
        for lo, hi in (*BANDS, (2.0, np.inf)):
            k = (params[:, 1] == gg) & (values > 0.0) & (near >= lo) & (near < hi)
            assert errs[0][k].max() <= 1.1 * errs[1][k].max() + 0.01, (gg, lo, errs[0][k].max(), errs[1][k].max())


def test_small_emitter_is_a_lambertian_point_light():
    """A 2 mm emitter's glow is a point light's with Lambert's cosine: the closed-form limit's quadrature."""
    from scipy import integrate
    rng = np.random.default_rng(7)
    for g in (0.0, 0.7):
        for _ in range(10):
            o = np.array([rng.uniform(-5, 5), rng.uniform(-5, 5), rng.uniform(-5, -0.5)])
            u = np.array([rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-0.3, 1)])
            u /= np.linalg.norm(u)
            beta = 0.2

            def f(t):
                x = o + t * u
                r = np.linalg.norm(x)
                if x[2] >= 0.0:
                    return 0.0
                cos_s = -(x @ u) / r
                p = (1 - g * g) / (1 + g * g - 2 * g * cos_s) ** 1.5 / (4 * math.pi)
                return beta * math.exp(-beta * (t + r)) * (-x[2] / r) * p / (r * r)

            cross = -o[2] / u[2] if u[2] > 0 else 300.0
            t_c = -(o @ u)
            ref = integrate.quad(f, 0.0, min(cross, 300.0), points=[min(max(t_c, 0.0), min(cross, 300.0))],
                                 limit=400, epsrel=1e-10)[0]
            d_sv, along, h = model.ray_light_geometry(M, o, u, np.zeros(3))
            got = float(area.airlight(M, beta, d_sv, along, h, model.FAR, *o, *u, 1e-3, 1e-3, g=g))
            assert got == pytest.approx(ref, rel=2e-3)


@pytest.mark.parametrize("ray", [
    ((0.0, 0.0, -2.0), (0.0, 0.0, 1.0)),      # straight into the emitter's centre
    ((3.0, 0.0, 0.0), (-1.0, 0.0, 0.0)),      # in the emitter's plane, through it
    ((3.0, 0.0, -1e-9), (-1.0, 0.0, 0.0)),    # a hair in front of that plane
    ((0.0, 0.0, -1e-9), (1.0, 0.0, 0.0)),     # starting on the emitter
    ((0.0, 0.0, 0.0), (0.0, 0.0, -1.0)),      # from the centre along the normal
    ((0.0, 0.0, 2.0), (0.0, 0.0, -1.0)),      # from behind, through it
])
@pytest.mark.parametrize("g", [0.0, 0.9])
def test_limits_finite(ray, g):
    """Rays through, along and from the emitter: finite, non-negative glows (no NaN, no Inf)."""
    o, u = np.array(ray[0]), np.array(ray[1])
    d_sv, along, h = model.ray_light_geometry(M, o, u, np.zeros(3))
    for d_vp in (1.0, model.FAR):
        v = float(area.airlight(M, 0.1, d_sv, along, h, d_vp, *o, *u, 0.5, 0.25, g=g))
        assert math.isfinite(v) and v >= 0.0
    pair = area.airlight_pair(M, 0.1, d_sv, along, h, 1.5, *o, *u, 0.5, 0.25, g=g)
    assert all(math.isfinite(float(v)) for v in pair)


def test_pair_is_airlight_and_background(cache):
    """``airlight_pair`` = (airlight to the surface, airlight to the sky) of the same ray."""
    params, _ = cache
    sub = params[::40]
    beta, g, a, b = sub[:, :4].T
    o, u = sub[:, 5:8], sub[:, 8:11]
    d_sv, along, h = model.ray_light_geometry(M, o, u, np.zeros(3))
    d_vp = np.full(len(sub), 3.0)
    for gg in np.unique(g):
        k = g == gg
        args = (beta[k], d_sv[k], along[k], h[k])
        ray = (*o[k].T, *u[k].T, a[k], b[k])
        surface, sky = area.airlight_pair(M, *args, d_vp[k], *ray, g=float(gg))
        np.testing.assert_allclose(surface, area.airlight(M, *args, d_vp[k], *ray, g=float(gg)), rtol=1e-12)
        np.testing.assert_allclose(sky, area.airlight_background(M, *args, *ray, g=float(gg)), rtol=1e-12)


def test_scaled_light_space():
    """The kernels take the light-space ray of any positive multiple of the inverse rotation: the same glow."""
    o, u = np.array([1.0, -2.0, -3.0]), np.array([0.1, 0.5, 0.8])
    u /= np.linalg.norm(u)
    d_sv, along, h = model.ray_light_geometry(M, o, u, np.zeros(3))
    one = float(area.airlight(M, 0.2, d_sv, along, h, model.FAR, *o, *u, 0.5, 0.25, g=0.5))
    k = 7.3
    scaled = float(area.airlight(M, 0.2, d_sv, along, h, model.FAR, *(k * o), *(k * u), 0.5, 0.25, g=0.5))
    assert scaled == pytest.approx(one, rel=1e-12)


def test_half_sizes_of_blender_shapes():
    """A disk or an ellipse is the rectangle of its area; a square's y is its x; scale multiplies."""
    a, b = area.half_sizes("DISK", 2.0, 5.0)
    assert 4.0 * a * b == pytest.approx(math.pi) and a == b
    a, b = area.half_sizes("ELLIPSE", 2.0, 1.0, scale=2.0)
    assert 4.0 * a * b == pytest.approx(math.pi * 2.0 * 1.0) and a == pytest.approx(2.0 * b)
    assert area.half_sizes("SQUARE", 1.0, 9.0) == (0.5, 0.5)
    assert area.half_sizes("RECTANGLE", 2.0, 1.0, scale=3.0) == (3.0, 1.5)


# --- the fog light an area light scatters onto surfaces -------------------------------------------------------

def _scatter_case(rng, m, g):
    """(ours, exact, the point light's, Lambert's cosine times the point light's) of the diffuse lobe at a random
    Lambertian point 0.5-30 m from a small area light (1 cm, so the emitter's size plays no part), on any
    side of it.  Exact: Sun et al. 2005 Eq. 15, the area light's airlight (``area.airlight_background``,
    against quadrature above) along every direction of the hemisphere, times cos / pi
    (tests/test_spot_scatter.py's quadrature)."""
    import functools
    from test_spot_scatter import _hemisphere
    from fog_addon.precompute.physics.point import surface
    beta = math.exp(rng.uniform(math.log(0.01), math.log(0.5)))
    dist = math.exp(rng.uniform(math.log(0.5), math.log(30.0)))
    psi, az = math.acos(rng.uniform(-1.0, 1.0)), rng.uniform(0.0, 2.0 * math.pi)
    p = dist * np.array([math.sin(psi) * math.cos(az), math.sin(psi) * math.sin(az), -math.cos(psi)])
    n = rng.normal(size=3)
    n /= np.linalg.norm(n)
    if n @ -p < 0:
        n = -n
    w, wt = _hemisphere(p, np.zeros(3), n)
    o = np.broadcast_to(p, w.shape)
    d_sv, along, h = model.ray_light_geometry(m, o, w, np.zeros((1, 3)))
    half = 0.005
    with np.errstate(all="ignore"):
        exact = float(np.sum(area.airlight_background(m, beta, d_sv, along, h, *o.T, *w.T, half, half, g=g) * wt))
    d_sp = float(np.linalg.norm(p))
    cos_n = np.asarray(n @ -p / d_sp)
    point_fn = functools.partial(surface.surface_scatter, g=g)
    point = float(point_fn(m, np.asarray(beta), np.asarray(d_sp), cos_n, 0.0))
    c_axis = np.asarray(-p[2] / d_sp)
    on_axis = np.asarray(-n[2])
    ours = float(area.scatter(m, np.asarray(beta), np.asarray(d_sp), cos_n, cos_n, 0.0, c_axis, half, half, on_axis,
                              on_axis, point=point_fn, g=g)[0])
    return ours, exact, point, max(float(c_axis), 0.0) * point


@pytest.mark.parametrize("g", [0.0, pytest.param(0.85, marks=pytest.mark.slow)])
def test_area_diffuse_scatter_against_hemisphere_quadrature(g):
    """24 random points a g: the diffuse lobe within 0.12 of the point light's fog light (the spot's bound,
    tests/test_spot_scatter.py), and on the whole closer than Lambert's cosine at the point times the point
    light's (the light's direct weight, the simple model)."""
    from fog_addon.precompute.model import bakers
    m = NumpyOps(bakers.numpy_tables(g))
    rng = np.random.default_rng(31 + int(10 * g))
    ours, plain = [], []
    for _ in range(24):
        got, exact, point, simple = _scatter_case(rng, m, g)
        ours.append(abs(got - exact) / point)
        plain.append(abs(simple - exact) / point)
    print(f"g={g}: max {max(ours):.3f} median {np.median(ours):.3f}; cosine alone: max {max(plain):.3f} "
          f"median {np.median(plain):.3f}")
    assert max(ours) <= 0.12
    assert np.median(ours) < 0.5 * np.median(plain)
