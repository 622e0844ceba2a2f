"""The error predictor and the chooser of the Quality (fog_addon/precompute/model/predict.py), numpy only.

The renders that prove the prediction are in tests/test_quality.py; here:
the predictor's terms are the shaders' twin (``shading.shade_point``), the
chooser keeps the sum of what it drops within the target at every judged
sample, and bad Quality values are refused with a clear message.
"""
import numpy as np
import pytest

from fog_addon.precompute.core import spec as spec_
from fog_addon.precompute.core import tables
from fog_addon.precompute.model import predict, rungs, shading
from fog_addon.precompute.physics.point import airlight, surface
from fog_addon.precompute.physics.spot import spot
from fog_addon.precompute.core.medium import Medium
from fog_addon.precompute.core.ops import NumpyOps



def _eevee(*args, **kw):
    """``budgets.eevee_budget`` without the user's allowance: the measured per-light costs against the limit."""
    from fog_addon.nodes import budgets  # noqa: PLC0415 (bpy)
    return budgets.eevee_budget(*args, allowance=0, **kw)


def _osl(*args, **kw):
    """``budgets.osl_budget`` without the user's allowance."""
    from fog_addon.nodes import budgets  # noqa: PLC0415 (bpy)
    return budgets.osl_budget(*args, allowance=0, **kw)

def _samples(rng, p=400, n=12):
    cam = np.tile(rng.uniform(-1, 1, 3), (p, 1))
    d = rng.normal(size=(p, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    dist = rng.uniform(0.5, 40.0, p)
    dist[: p // 8] = np.inf
    normal = -d + 0.5 * rng.normal(size=(p, 3))
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    lights = np.broadcast_to(rng.uniform(-25, 25, (n, 3)), (p, n, 3))
    return predict.ViewSamples(cam, d, dist, normal, rng.uniform(0, 1, (p, 3)), rng.uniform(0, 0.3, (p, 3)),
                               rng.uniform(0, 40, p), lights)


def test_terms_are_the_shaders_twin():
    rng = np.random.default_rng(3)
    s = _samples(rng)
    intensity = rng.uniform(1, 200, (s.lights.shape[1], 3))
    glow, scatter = predict.light_fog(s, intensity, 0.07)
    m = NumpyOps({tables.AIRLIGHT.name: airlight.bake_airlight_table(), tables.SURFACE.name: surface.surface_table()})
    for p in range(0, len(s.distance), 37):
        for i in range(0, s.lights.shape[1], 5):
            light = shading.Light(s.lights[p, i], intensity[i])
            if np.isfinite(s.distance[p]):
                pos = s.camera[p] + s.direction[p] * s.distance[p]
                geo = shading.Geometry(s.camera[p], pos, -s.direction[p], s.distance[p], s.normal[p])
                mat = shading.Material(s.rho_d[p], s.rho_s[p], s.level[p])
                t = shading.shade_point(m, geo, mat, light, Medium(0.07), rungs.choose("nodes"))
                np.testing.assert_allclose(glow[p, i], t.airlight, rtol=1e-9)
                np.testing.assert_allclose(scatter[p, i], t.scattered * np.exp(-0.07 * s.distance[p]), rtol=1e-9)
            else:
                want = shading.background_point(m, s.camera[p], s.direction[p], light, Medium(0.07),
                                                rungs.choose("nodes"))
                np.testing.assert_allclose(glow[p, i], want, rtol=1e-9)
                assert not scatter[p, i].any()


@pytest.mark.parametrize("target", [0.2, 0.05, 0.01, 0.001])
def test_chooser_keeps_the_dropped_fog_within_the_target(target):
    rng = np.random.default_rng(int(target * 1e4))
    p, n = 300, 30
    scale = rng.lognormal(0, 4, (1, n, 1))     # lights from very dim to very bright
    glow = rng.lognormal(0, 0.5, (p, n, 3)) * scale
    scatter = rng.lognormal(0, 0.5, (p, n, 3)) * scale * (rng.random((p, 1, 1)) < 0.7)
    pred = predict.choose_steps(glow, scatter, target)
    fog = (glow + scatter).sum(axis=1)
    judged = fog >= predict.FLOOR * fog.max()
    dropped = (np.where(pred.steps[None, :, None] >= 1, scatter, 0)
               + np.where(pred.steps[None, :, None] >= 2, glow, 0)).sum(axis=1)
    measured = (dropped / fog)[judged].max()
    assert measured <= target * (1 + 1e-12)
    assert pred.error == pytest.approx(measured, rel=1e-12)
    assert (pred.steps > 0).any(), "nothing dropped: the test would prove nothing"


def test_a_negligible_light_goes_off_and_exact_keeps_everything():
    glow = np.ones((10, 3, 3))
    glow[:, 2] = 1e-6          # light 2 adds a millionth of each pixel's fog
    scatter = np.full((10, 3, 3), 0.5)
    scatter[:, 2] = 1e-6
    pred = predict.choose_steps(glow, scatter, 0.01)
    assert list(pred.steps) == [0, 0, 2]
    assert pred.error == pytest.approx(2e-6 / 3.000002, rel=1e-6)
    assert list(predict.choose_steps(glow, scatter, None).steps) == [0, 0, 0]


def test_rims_take_the_fewest_points_their_deviation_allows():
    """Each spot's rim (spot.RIM_LADDER): the fewest points whose deviation, counted predict.RIM_SAFETY times
    with what the steps dropped, keeps every judged sample within the target; the error predicted is that sum.
    Light 0's rim moves nothing (4 points), light 1's a little at 4 points (6), light 2's much at both (10);
    light 3 is off (its glow dropped, its rim moot); with no target every rim keeps its exact count."""
    p, n = 50, 4
    glow, scatter = np.ones((p, n, 3)), np.zeros((p, n, 3))
    glow[:, 3] = 1e-6
    dev = np.zeros((2, p, n, 3))            # (6 points, 4 points)
    dev[1, :, 1] = 0.03
    dev[0, :, 1] = 1e-4
    dev[:, :, 2] = 0.05
    dev[:, :, 3] = 1.0
    pred = predict.choose_steps(glow, scatter, 0.01, rim_dev=dev)
    assert list(pred.steps) == [1, 1, 1, 2]   # no scatter to leave out: "glow only" costs nothing
    assert list(pred.rims[:3]) == [4, 6, 10]
    fog = (glow + scatter).sum(axis=1)
    moved = predict.RIM_SAFETY * 1e-4 + 1e-6
    assert pred.error == pytest.approx(moved / fog[0, 0], rel=1e-9) and pred.error <= 0.01
    assert pred.light_error[1] == pytest.approx(predict.RIM_SAFETY * 1e-4 / fog[0, 0], rel=1e-9)
    assert list(predict.choose_steps(glow, scatter, None, rim_dev=dev).rims) == [spot.RIM_NODES] * n


@pytest.mark.parametrize("bad", [0.0, -0.1, 1.0, float("nan"), float("inf"), "best", "1 %"])
def test_bad_quality_is_refused(bad):
    with pytest.raises(ValueError, match="quality|target error"):
        spec_.target_error(bad)


def test_quality_presets():
    assert spec_.target_error("Draft") == 0.05 and spec_.target_error("final") == 0.01
    assert spec_.target_error("exact") is None and spec_.target_error(None) is None
    assert spec_.target_error(0.02) == 0.02


def test_a_budget_steps_lights_down_beyond_the_target_least_error_first():
    """EEVEE's uniform block as a budget: the steps fit it, the lights that leave out least go first, and the
    error is still the one predicted (above the target when the budget forced it)."""
    rng = np.random.default_rng(7)
    p, n = 200, 12
    scale = np.linspace(1.0, 12.0, n)[None, :, None]          # light i matters more as i grows
    glow = rng.lognormal(0, 0.3, (p, n, 3)) * scale
    scatter = rng.lognormal(0, 0.3, (p, n, 3)) * scale
    budget = predict.Budget(cost=((10, 5, 1, 0),), limit=(60,), name="test")   # full 10, glow only 5, off 1, out 0
    free = predict.choose_steps(glow, scatter, 1e-9)
    assert not free.steps.any(), "the target alone would keep every light: the budget must do the work"
    pred = predict.choose_steps(glow, scatter, 1e-9, budget)
    cost = np.array((10, 5, 1, 0))[pred.steps].sum()
    assert cost <= 60 and pred.fits and pred.limited
    assert cost + 4 > 60 or (pred.steps >= 2).all(), "stepped further down than the budget needs"
    assert pred.steps[0] >= pred.steps[-1], "the brightest light stepped down before the dimmest"
    fog = (glow + scatter).sum(axis=1)
    dropped = (np.where(pred.steps[None, :, None] >= 1, scatter, 0)
               + np.where(pred.steps[None, :, None] >= 2, glow, 0)).sum(axis=1)
    assert pred.error == pytest.approx((dropped / fog).max(), rel=1e-12)
    assert pred.error > 1e-9
    exact = predict.choose_steps(glow, scatter, None, budget)      # Quality Exact too must fit
    assert np.array((10, 5, 1, 0))[exact.steps].sum() <= 60 and exact.limited
    roomy = predict.choose_steps(glow, scatter, 1e-9, predict.Budget(((10, 5, 1, 0),), (1000,), "roomy"))
    assert not roomy.steps.any() and not roomy.limited


def test_a_budget_too_small_for_every_light_off_leaves_lights_out():
    """Off still costs (EEVEE: 334 bytes a light); a light off is then left out of the groups (rungs.LEFT_OUT,
    free), which adds no error of its own; a budget too small even for that says so."""
    glow = np.ones((5, 4, 3))
    pred = predict.choose_steps(glow, glow, 0.01, predict.Budget(((10, 5, 2, 0),), (7,), "tiny"))
    assert pred.fits and np.array((10, 5, 2, 0))[pred.steps].sum() <= 7, pred
    assert (pred.steps >= 2).any() and rungs.LEFT_OUT in pred.steps, pred
    costly = predict.choose_steps(glow, glow, 0.01, predict.Budget(((10, 5, 2, 2),), (7,), "out costs as off"))
    assert pred.error < costly.error, "leaving an off light out should spare another light's glow"
    none = predict.choose_steps(glow, glow, 0.01, predict.Budget(((10, 5, 2, 1),), (3,), "none"))
    assert list(none.steps) == [3, 3, 3, 3] and not none.fits and none.error == pytest.approx(1.0)
    free = predict.choose_steps(glow, glow, 0.99)
    assert rungs.LEFT_OUT not in free.steps, "the target alone never leaves a light out (only a budget does)"


def test_eevee_budget_holds_fewer_full_lights_than_glow_only_ones():
    """The measured EEVEE constants (a saved file's, docs/measurements/2026-11-29-shader-budgets.md): at g = 0
    full point lights fit 24 times into the block (measured: 25 overflow), glow-only ones 33, off ones 193,
    left out any number; at g = 0.85, 21 full (22 overflow) and 27 glow only (28 overflow)."""
    b = _eevee()
    assert b.fits([0] * 24) and not b.fits([0] * 25)
    assert b.fits([1] * 33) and not b.fits([1] * 34)
    assert b.fits([2] * 193) and not b.fits([2] * 194)
    assert b.fits([3] * 10000)
    # anisotropic fog: the phase weight's constants (measured +457 bytes a full light at g = 0.85)
    hg = _eevee(0.85)
    assert hg.fits([0] * 21) and not hg.fits([0] * 22)
    assert hg.fits([1] * 27) and not hg.fits([1] * 28)
    # Dense Fog: its tables (measured 4 184 bytes a full point at g = 0.85: 15 fit, 16 overflow)
    dense = _eevee(0.85, dense=True)
    assert dense.fits([0] * 15) and not dense.fits([0] * 16)


def test_osl_budget_keeps_a_material_under_osl_group_limit():
    """Cycles' OSL crashed on a 256-light material (53 195 nodes > 32 767 layers): full point lights fit 153
    times (213 nodes each over the material's 156), glow-only ones 534, and 256 lights fit with most of them
    glow only."""
    b = _osl()
    assert b.fits([0] * 153) and not b.fits([0] * 154)
    assert b.fits([1] * 534) and not b.fits([1] * 535)
    assert b.fits([1] * 256) and b.fits([0] * 70 + [1] * 186) and not b.fits([0] * 256)


def test_budgets_charge_spots_their_own_cost():
    """A spot costs more than a point light (measured, files saved and reopened: EEVEE 12 128 bytes a fully
    modelled spot in a material at g = 0.85 against 3 075 a point; OSL 668 nodes against 213): a budget over a
    mix of lights charges each its own, so fewer spots than point lights fit (5 against 21), and a choice that
    fits with points may not with spots."""
    points = _eevee(0.85, [False] * 8)
    assert points.fits([0] * 8)
    spots = _eevee(0.85, [True] * 8)
    assert not spots.fits([0] * 8) and not _eevee(0.85, [True] * 6).fits([0] * 6)
    assert _eevee(0.85, [True] * 5).fits([0] * 5)
    spots = _eevee(0.85, [True] * 15)
    assert spots.fits([0] * 5 + [2] * 9) and not spots.fits([0] * 5 + [2] * 10)   # off: 434 bytes a spot
    mixed = _eevee(0.85, [True] * 2 + [False] * 6)
    assert mixed.fits([0] * 8) and not _eevee(0.85, [True] * 5 + [False] * 2).fits([0] * 7)
    osl = _osl([True] * 110)
    assert not osl.fits([0] * 110) and _osl([False] * 110).fits([0] * 110)


def test_osl_budget_charges_an_area_light_its_own_glow():
    """Measured (docs/measurements/2026-11-29-shader-budgets.md): a fully modelled area light adds 3 812 OSL
    layers to a material, so about 8 fit in OSL's 32 767 (a spot adds 668: about 48).  The budget must not let 9
    area lights through at full models, where charging them as spots let 31 through."""
    from fog_addon.nodes import budgets  # noqa: PLC0415 (bpy)
    measured_limit = (budgets.OSL_LAYER_LIMIT - 156) // 3812   # 156: the material with no light (measured)
    assert measured_limit == 8
    areas = _osl([True] * (measured_limit + 1), [True] * (measured_limit + 1))
    assert not areas.fits([0] * (measured_limit + 1))
    assert _osl([True] * 6, [True] * 6).fits([0] * 6)
    assert _osl([True] * 48, [False] * 48).fits([0] * 48)   # spots: 668 nodes each
    assert not _osl([True] * 49, [False] * 49).fits([0] * 49)


def test_eevee_budget_charges_an_area_light_its_own_cost():
    """Measured (files saved and reopened, g = 0.85): a fully modelled area light adds 19 936 bytes to a
    material's uniform block and 17 072 to the World's, so 3 fit and 4 overflow (a spot: 12 128, 5 fit).  The
    budget charges an area light its own, not a spot's."""
    assert _eevee(0.85, [True] * 3, [True] * 3).fits([0] * 3)
    assert not _eevee(0.85, [True] * 4, [True] * 4).fits([0] * 4)
    assert _eevee(0.85, [True] * 4, [False] * 4).fits([0] * 4)   # as spots, 4 would fit
    mixed = _eevee(0.85, [True] * 4, [True, True, False, False])   # 2 areas, 2 spots
    assert mixed.fits([0] * 4) and not _eevee(0.85, [True] * 4, [True, True, True, False]).fits([0] * 4)


def test_opaque_fog_predicts_no_nan():
    """An opaque fog's far samples carry fog light that underflows (e^{-beta d} ~ 1e-310): they are not judged,
    so the predicted errors stay finite (they were NaN, with overflow warnings, at density 100 1/m)."""
    glow = np.array([[[1e-310] * 3, [3e-311] * 3], [[2e-310] * 3, [1e-320] * 3]])
    scatter = np.zeros_like(glow)
    with np.errstate(all="raise"):
        pred = predict.choose_steps(glow, scatter, 0.01)
    assert np.isfinite(pred.error) and np.isfinite(pred.light_error).all()


def test_budgets_keep_room_for_the_users_own_nodes():
    """The shipped budgets keep an allowance for a material's own nodes: fewer lights than the measured limit."""
    from fog_addon.nodes import budgets  # noqa: PLC0415 (bpy)
    assert not budgets.eevee_budget(0.85, [False] * 21).fits([0] * 21) and _eevee(0.85, [False] * 21).fits([0] * 21)
    assert not budgets.osl_budget([False] * 153).fits([0] * 153) and _osl([False] * 153).fits([0] * 153)


def test_the_fog_no_step_leaves_out_is_in_every_samples_denominator():
    """``choose_steps``' ``other`` (a fog layer's sun and sky, ``ViewSamples.other``) adds to each sample's fog: a
    lamp whose fog light on surfaces is 0.1 of its glow of 1 keeps it at a 6 % target alone (0.1 / 1.1 = 9.1 %),
    and drops it beside a daylight fog of 1 (0.1 / 2.1 = 4.8 %), whose share is the error predicted."""
    glow, scatter = np.ones((4, 1, 3)), np.full((4, 1, 3), 0.1)
    assert list(predict.choose_steps(glow, scatter, 0.06).steps) == [0]
    pred = predict.choose_steps(glow, scatter, 0.06, other=np.ones((4, 3)))
    assert list(pred.steps) == [1]
    assert pred.error == pytest.approx(0.1 / 2.1, rel=1e-12)


@pytest.mark.parametrize("g", [0.0, 0.6])
def test_sampled_daylight_is_the_suns_single_scattering_in_the_layer(g):
    """``daylight_terms.sampled_light`` at a ray to the sky (straight up from 5 units inside a 20-unit layer) and a
    ray to a black wall (level, 30 units): the sun's single scattering along the ray, E p(d.s) beta
    int e^(-beta s) e^(-beta (top - z(s)) / mu_s) ds (Sun et al. 2005 Eq. 5 with the sun's path to the top), by
    scipy's adaptive quadrature; no sky, albedo 1, a hard top."""
    from scipy.integrate import quad
    from fog_addon.precompute.model import daylight_terms
    from fog_addon.precompute.physics.daylight import daylight_tables, sunlight
    beta, top, e_sun = 0.05, 20.0, 3.0
    sun = np.array([0.0, -np.cos(0.6), np.sin(0.6)])
    table = daylight_tables.table_spec(beta, top, 0.0, tuple(sun), g)
    m = NumpyOps({table.name: np.zeros((table.height, table.width, 4), np.float32)})
    day = sunlight.Daylight(beta, top, 0.0, 0.0, sun, np.full(3, e_sun), np.zeros(3), g, 1.0)
    camera = np.array([[0.0, 0.0, 5.0], [0.0, 0.0, 5.0]])
    direction = np.array([[0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])
    normal = np.array([[0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
    light = daylight_terms.sampled_light(m, day, table, camera, direction, np.array([np.inf, 30.0]), normal,
                                         np.zeros((2, 3)))

    def hg(c):
        return (1 - g * g) / (4 * np.pi * (1 + g * g - 2 * g * c) ** 1.5)

    def glow(d, length):
        z = lambda s: camera[0, 2] + s * d[2]   # noqa: E731
        f = lambda s: beta * np.exp(-beta * s - beta * (top - z(s)) / sun[2])   # noqa: E731
        return e_sun * hg(d @ sun) * quad(f, 0.0, length, epsabs=0, epsrel=1e-10)[0]

    want = [glow(direction[0], top - camera[0, 2]), glow(direction[1], 30.0)]
    np.testing.assert_allclose(light, np.repeat(np.array(want)[:, None], 3, axis=1), rtol=1e-6)


def test_the_ladder_judges_dense_fog_as_the_surfaces_scale_it():
    """``predict.predict``'s ``multiple_scale`` (``escape.field_scales``: the share of Dense Fog's field the
    surfaces leave): at scale 0 the ladder judges the single scattering alone, at 1 the unbounded field, the
    limits of ``rungs.choose``'s scaled field; between them the fog the ladder judges lies between theirs."""
    rng = np.random.default_rng(11)
    s = _samples(rng, p=240, n=6)
    intensity = rng.lognormal(0, 3, (6, 1)) * np.ones(3)   # lights from very dim to very bright
    args = (s, intensity, 0.12, 0.05)
    alone, unbounded = predict.predict(*args), predict.predict(*args, multiple_albedo=0.9)
    assert alone.error != pytest.approx(unbounded.error), "Dense Fog changes nothing here: the test proves nothing"
    for scale, want in ((0.0, alone), (1.0, unbounded)):
        got = predict.predict(*args, multiple_albedo=0.9, multiple_scale=[scale] * 6)
        assert list(got.steps) == list(want.steps), scale
        assert got.error == pytest.approx(want.error, rel=1e-9), scale
    half = predict.predict(*args, multiple_albedo=0.9, multiple_scale=[0.5] * 6)
    glow = predict.scaled_fog(half.single, half.fog, [0.5] * 6)[0]
    assert ((glow >= np.minimum(half.single[0], half.fog[0]) - 1e-12)
            & (glow <= np.maximum(half.single[0], half.fog[0]) + 1e-12)).all()
