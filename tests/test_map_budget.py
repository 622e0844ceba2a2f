"""The still shadow maps' budget (``shaft_maps.map_levels``): every map full where they fit, within the budget
otherwise, each light's grid points going as its weight^(2/3) (the Lagrange optimum of the shadows' edges'
displacement, weight x grid-point angle, summed over the lights: closed form below)."""
import numpy as np
import pytest

from fog_addon.precompute.physics.shafts import shaft_maps as sm


def points(levels, spots):
    return sum(float(np.prod(sm.map_grid(s, k))) for k, s in zip(levels, spots))


def test_every_map_is_full_where_the_full_maps_fit():
    assert not sm.map_levels(np.linspace(1.0, 1e-6, 16), [False] * 16).any()
    assert not sm.map_levels(np.ones(32), [True] * 32).any()   # a spot's map is half a point light's


@pytest.mark.parametrize("n", [17, 64, 400, 1000])
def test_many_maps_stay_within_the_budget(n):
    w = np.random.default_rng(n).lognormal(0.0, 2.0, n)
    spots = np.arange(n) % 3 == 0
    levels = sm.map_levels(w, spots)
    assert levels.min() >= 0 and levels.max() <= sm.SMALLEST_LEVEL
    smallest = points([sm.SMALLEST_LEVEL] * n, spots)
    assert points(levels, spots) <= max(sm.MAP_BUDGET, smallest)
    assert points(levels, spots) >= min(0.5 * sm.MAP_BUDGET, smallest)   # (rounding down leaves at most half)
    order = np.argsort(w)   # a heavier light's map is never coarser than a lighter one's of the same kind
    for kind in (False, True):
        k = [i for i in order if spots[i] == kind]
        assert np.all(np.diff(levels[k]) <= 0)


def test_grid_points_go_as_the_weight_to_two_thirds():
    """Two groups of n point lights, weights 1 and 8: t_heavy / t_light = 8^(2/3) = 4, one level apart; with a
    budget of n (4 + 1) t, the light group at t = budget / 5n, a level exactly."""
    n = 40
    t_light = sm.POINT_MAP[0] * sm.POINT_MAP[1] / 16.0   # level 2
    w = np.array([1.0] * n + [8.0] * n)
    levels = sm.map_levels(w, [False] * (2 * n), budget=n * 5.0 * t_light)
    assert list(levels[:n]) == [2] * n and list(levels[n:]) == [1] * n


def test_unweighted_lights_take_no_finer_maps_than_weighted_ones():
    w = np.array([1.0] * 20 + [0.0] * 20 + [np.nan])
    levels = sm.map_levels(w, [False] * 41)
    assert levels[20:].min() >= levels[:20].max() and levels[-1] == sm.SMALLEST_LEVEL
    assert points(levels, [False] * 41) <= sm.MAP_BUDGET
