"""The viewport preview's sampled lights (``precompute/model/sampling.py``, read by ``nodes/preview_sampled.py``): Walker's alias table draws each light with
the probability its importance asks, and the table's intensities over those probabilities make the one-light
estimate unbiased: its mean over the draws is every light's sum.  Numpy only (the module's table maths)."""
import numpy as np
import pytest

from fog_addon.precompute.model import sampling as ps


def drawn(keep, alias):
    """Each column's probability of coming out of the alias table: 1/N of its own keep plus 1/N of (1 - keep) of
    every column whose alias it is."""
    n = len(keep)
    p = np.asarray(keep, float) / n
    for j in range(n):
        p[int(alias[j])] += (1.0 - keep[j]) / n
    return p


@pytest.mark.parametrize("weights", [[1.0], [1.0, 1.0], [5.0, 1.0, 0.0, 2.0], list(np.linspace(0.1, 9.0, 45)),
                                     [1e-6, 1.0, 1e6]])
def test_alias_table_draws_each_light_by_its_weight(weights):
    p, keep, alias = ps.alias_table(weights)
    w = np.asarray(weights) / np.sum(weights)
    assert np.allclose(p, w) and np.allclose(drawn(keep, alias), w, atol=1e-12)
    assert ((0.0 <= keep) & (keep <= 1.0 + 1e-12)).all()


def test_one_sampled_light_estimates_the_sum_of_all():
    """E[I_j / p_j] over j drawn from the table is sum I_j, for each colour (a Monte Carlo draw of 200 000 too)."""
    rng = np.random.default_rng(3)
    positions = rng.uniform(-50, 50, (30, 3))
    intensities = rng.uniform(0.0, 200.0, (30, 3))
    rows = ps.table_rows(positions, intensities, (0.0, 0.0, 1.7), 0.02)
    keep, alias = rows[2, :, 0], rows[2, :, 1].astype(int)
    p = drawn(keep, alias)
    assert np.allclose((p[:, None] * rows[1, :, :3]).sum(axis=0), intensities.sum(axis=0), rtol=1e-5)
    assert np.allclose(rows[0, :, :3], positions)
    u1, u2 = rng.random(200_000), rng.random(200_000)
    column = np.minimum(np.floor(u1 * len(p)), len(p) - 1).astype(int)
    j = np.where(u2 < keep[column], column, alias[column])
    assert np.allclose(rows[1, j, :3].mean(axis=0), intensities.sum(axis=0), rtol=0.02)


def test_importance_favours_near_bright_lights_and_dims_far_ones():
    w = ps.importance([(0, 2, 0), (0, 20, 0), (0, 0.1, 0)], [(1, 1, 1)] * 3, (0, 0, 0), 0.1)
    assert w[0] > w[1] and w[2] == pytest.approx(w[0] * 2.0 * np.exp(0.2 - 0.01))   # (d < 1 m counts as 1 m)


@pytest.mark.parametrize("weight", [[1.0, 1.0], [5.0, 1.0, 0.0, 2.0], [1e-9, 3.0, 1e3], list(np.linspace(0.1, 9.0, 8))])
def test_a_sample_takes_one_tail_light_and_its_mean_is_every_light(weight):
    """The glass tails' draw (``sampling.picked``, ``mixed_chances``): every pick in [0, 1) takes exactly one light,
    light k with probability p_k (the length of its stretch), and gate x 1 / p_k has mean 1 for each light (the
    estimate is unbiased); half the probability is shared evenly, so no light is starved."""
    from fog_addon.precompute.core.ops import NumpyOps
    chances = ps.mixed_chances(weight)
    assert chances is not None and abs(sum(chances) - 1.0) < 1e-12 and min(chances) >= 0.5 / len(weight) - 1e-15
    m = NumpyOps({})
    pick = (np.arange(200_000) + 0.5) / 200_000   # stratified: the mean over [0, 1) to 1e-5
    taken = np.array([ps.picked(m, pick, chances, k)[0] for k in range(len(chances))])
    weights = np.array([ps.picked(m, pick, chances, k)[1] for k in range(len(chances))])
    assert np.array_equal(taken.sum(axis=0), np.ones(len(pick)))   # one light a sample, never two, never none
    np.testing.assert_allclose(taken.mean(axis=1), chances, atol=1e-5)
    np.testing.assert_allclose((taken * weights[:, None]).mean(axis=1), 1.0, rtol=1e-4)
    assert ps.mixed_chances([2.0]) is None   # one light: taken on every sample


@pytest.mark.parametrize("light, direction", [((3.0, 10.0, 0.5), (0.0, 1.0, 0.0)), ((0.0, -4.0, 2.0), (0.0, 1.0, 0.0)),
                                              ((1.0, 2.0, 0.0), (0.6, 0.8, 0.0))])
def test_tile_importance_is_the_airlight_integral_of_thin_fog(light, direction):
    """Each tile's weight is the integral over the ray of 1 / (distance to the light)^2, times I e^{-beta d}
    (quadrature, scipy: independent of the closed form), where the tile is narrow."""
    from scipy.integrate import quad
    p, u = np.asarray(light), np.asarray(direction) / np.linalg.norm(direction)
    exact, _ = quad(lambda t: 1.0 / np.sum((t * u - p) ** 2), 0.0, np.inf, limit=200)
    w = ps.tile_importance([light], [(1.0, 2.0, 3.0)], (0.0, 0.0, 0.0), [u], 1e-6, 0.05)
    assert w.shape == (1, 1)
    assert w[0, 0] == pytest.approx(6.0 * np.exp(-0.05 * np.linalg.norm(p)) * exact, rel=1e-6)


def test_each_tile_estimates_the_sum_of_all_and_favours_its_own_lights():
    """In every tile, E[I_j / p_j] over the tile's draws is sum I_j; a tile whose ray passes by a light draws it
    more often than a tile looking away from it, and every light keeps at least EVEN_SHARE of its picture's share."""
    rng = np.random.default_rng(5)
    positions = np.column_stack([rng.uniform(-30, 30, 20), rng.uniform(2, 60, 20), rng.uniform(0, 6, 20)])
    intensities = rng.uniform(1.0, 100.0, (20, 3))
    nx, ny = ps.TILES   # the tiles' centre rays of a camera looking along +y (view.frame_rays' order)
    xx, zz = np.meshgrid((np.arange(nx) + 0.5) / nx - 0.5, 0.6 * ((np.arange(ny) + 0.5) / ny - 0.5))
    dirs = np.column_stack([xx.ravel(), np.ones(xx.size), zz.ravel()])
    dirs /= np.linalg.norm(dirs, axis=1)[:, None]
    rows = ps.table_rows(positions, intensities, (0.0, 0.0, 0.0), 0.02, dirs, 0.05)
    assert rows.shape == (ps.ROWS, 20, 4)
    whole = ps.alias_table(ps.importance(positions, intensities, (0.0, 0.0, 0.0), 0.02))[0]
    chances = []
    for t in range(ps.TILE_COUNT):
        keep, alias = rows[2 + 2 * t, :, 0], rows[2 + 2 * t, :, 1].astype(int)
        p = drawn(keep, alias)
        chances.append(p)
        assert np.allclose((p[:, None] * rows[1 + 2 * t, :, :3]).sum(axis=0), intensities.sum(axis=0), rtol=1e-5)
        assert (p >= ps.EVEN_SHARE * whole - 1e-9).all()
    chances = np.array(chances)
    near = np.argmin(np.linalg.norm(np.cross(dirs[:, None], positions[None]), axis=-1)
                     / np.linalg.norm(positions, axis=1)[None], axis=0)   # each light's nearest tile by angle
    assert all(chances[near[j], j] > np.median(chances[:, j]) for j in range(20))

