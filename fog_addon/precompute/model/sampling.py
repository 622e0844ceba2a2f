"""Sampling one light of many per sample (the viewport preview's other lights, ``nodes/preview_sampled.py``; the
lights whose fog past glass a sample takes, ``nodes/glass_tails.py``): each light's importance, Walker's alias table
that draws it and the table the shaders read, and a draw among a few lights by stretches of [0, 1) (``picked``).

A pixel's fog light is a sum over the lights; a shader that takes one light j per sample, drawn with probability
p_j, and adds its light times 1 / p_j estimates that sum without bias (its mean over the draws is the sum), and the
samples a viewport adds up average the estimates.  Its noise is least when p_j follows each light's share of the
pixel's sum; ``importance`` guesses that share over the whole picture from the camera, ``tile_importance`` over each
tile of a grid over the camera's frame (``TILES``), where the shaders find a pixel's row by its window coordinates.
"""
import numpy as np

TILES = (12, 8)      # the grid of tiles over the camera's frame (x, y) whose each row of the table draws for
TILE_COUNT = TILES[0] * TILES[1]
ROWS = 1 + 2 * TILE_COUNT   # the table's rows: 0 positions; per tile t: 1 + 2t intensities over their probability,
#                             2 + 2t (keep, alias)
MIN_DISTANCE = 1.0   # m: the distance below which a light's weight stops growing (1 / max(d, this))
EVEN_SHARE = 0.3     # of each tile's probabilities, the share that follows the whole picture's (``importance``):
#                      a light a tile's guess underrates (another view than the camera's, a surface it lights
#                      beyond the glow) keeps samples, and I / p stays within 1 / EVEN_SHARE of the picture's


def importance(positions, intensities, camera, beta):
    """Each light's share of the glows over the picture, up to a factor: I e^{-beta d} / max(d, MIN_DISTANCE)
    (I the RGB intensities' sum, d the distance to the camera, m)."""
    d = np.linalg.norm(np.asarray(positions, float) - np.asarray(camera, float), axis=-1)
    return np.asarray(intensities, float).sum(axis=-1) * np.exp(-beta * d) / np.maximum(d, MIN_DISTANCE)


def tile_importance(positions, intensities, camera, directions, half_angle, beta):
    """(T, N) each light's glow along each tile's centre ray, up to a factor: the single scattering of a point light
    I on a ray from the camera through fog thin enough that its extinction is e^{-beta d} throughout (d the light's
    distance to the camera, m), isotropic,  I e^{-beta d} (pi / 2 + atan(t0 / h)) / h,  the integral over t >= 0 of
    1 / (h^2 + (t - t0)^2): the inverse square of the distance from the ray's point t to the light, t0 the ray's
    nearest approach and h its distance there (Sun et al. 2005 Eq. 5's airlight integral with its exponentials held
    at the light's distance).  h is at least the tile's own radius at the light, d sin(``half_angle``) (and
    MIN_DISTANCE / 100): a tile averages the glow over its pixels, which a lamp's core does not fill."""
    r = np.asarray(positions, float).reshape(-1, 3) - np.asarray(camera, float)
    d = np.linalg.norm(r, axis=1)
    t0 = np.asarray(directions, float) @ r.T
    h = np.sqrt(np.maximum(d ** 2 - t0 ** 2, 0.0))
    h = np.maximum(h, np.maximum(d * np.sin(half_angle), MIN_DISTANCE / 100.0))
    power = np.asarray(intensities, float).reshape(-1, 3).sum(axis=-1) * np.exp(-beta * d)
    return power * (0.5 * np.pi + np.arctan(t0 / h)) / h


def alias_table(weights):
    """(probabilities p, keep, alias) of Walker's alias method for ``weights`` (N >= 1, not all 0): column i is kept
    with probability keep[i], else alias[i] is taken, so that i comes out with probability p[i] = w_i / sum w
    (Vose's construction)."""
    w = np.nan_to_num(np.maximum(np.asarray(weights, float), 0.0))   # (a light of no or negative power: never)
    n = len(w)
    p = w / w.sum() if w.sum() > 0 else np.full(n, 1.0 / n)
    scaled = p * n
    keep, alias = np.ones(n), np.arange(n)
    small = [i for i in range(n) if scaled[i] < 1.0]
    large = [i for i in range(n) if scaled[i] >= 1.0]
    while small and large:
        s, g = small.pop(), large.pop()
        keep[s], alias[s] = scaled[s], g
        scaled[g] -= 1.0 - scaled[s]
        (small if scaled[g] < 1.0 else large).append(g)
    return p, keep, alias


def tile_chances(tile_weights, weights):
    """(T, N) each tile's probabilities: (1 - EVEN_SHARE) of its own weights' shares (``tile_importance``), EVEN_SHARE
    of the whole picture's (``importance``; even where they are all 0)."""
    def shares(w):
        w = np.nan_to_num(np.maximum(np.asarray(w, float), 0.0))
        total = w.sum(axis=-1, keepdims=True)
        return np.where(total > 0.0, w / np.where(total > 0.0, total, 1.0), 1.0 / w.shape[-1])
    return (1.0 - EVEN_SHARE) * shares(tile_weights) + EVEN_SHARE * shares(weights)[None, :]


def table_rows(positions, intensities, camera, beta, directions=None, half_angle=0.0):
    """(ROWS, N, 4) float32 of the lights (positions, m; RGB intensities I, W/sr; the camera's position; beta, 1/m):
    row 0 their positions; for each tile t, row 1 + 2t their intensities over their
    probability there (I / p) and row 2 + 2t (keep, alias column) of ``alias_table``.  The probabilities are
    ``tile_chances`` of the tiles' centre rays ``directions`` (TILE_COUNT, 3, row by row from the bottom-left tile:
    ``view.frame_rays``) of angular radius ``half_angle`` (rad), or the whole picture's ``importance`` in every tile
    without them."""
    positions = np.asarray(positions, float).reshape(-1, 3)
    intensities = np.asarray(intensities, float).reshape(-1, 3)
    weights = importance(positions, intensities, camera, beta)
    if directions is None:
        chances = np.repeat(alias_table(weights)[0][None, :], TILE_COUNT, axis=0)
    else:
        chances = tile_chances(tile_importance(positions, intensities, camera, directions, half_angle, beta), weights)
    rows = np.zeros((ROWS, len(positions), 4), np.float32)
    rows[0, :, :3] = positions
    for t, p in enumerate(chances):
        p, keep, alias = alias_table(p)
        rows[1 + 2 * t, :, :3] = intensities / np.maximum(p, 1e-30)[:, None]
        rows[2 + 2 * t, :, 0], rows[2 + 2 * t, :, 1] = keep, alias
    return rows


def picked(m, pick, chances, k):
    """(0 or 1, 1 / p_k): whether light ``k`` is the one a sample takes, for ``pick`` uniform in [0, 1) and the
    lights' probabilities ``chances`` (Python floats summing to 1): light k where pick falls in its stretch of
    [0, 1).  A light's glows times 1 / p_k on the samples that take it have the mean of its glows on every sample
    (a Monte Carlo estimate, as Cycles samples one light of many for direct light), at the cost of one light's
    kernels a sample: Cycles' SVM jumps over the closures of the others (a gate of 0)."""
    lo = sum(chances[:k])
    hi = 1.0 if k == len(chances) - 1 else sum(chances[:k + 1])
    gate = m.less(pick, hi) if lo <= 0.0 else m.less(pick, hi) * (1.0 - m.less(pick, lo))
    return gate, 1.0 / chances[k]


def mixed_chances(weight):
    """Each light's probability of being the one a sample takes (``picked``), from its importance ``weight``
    (``importance``), half of it shared evenly (a light the importance underrates keeps its share of the samples);
    None for one light (it is taken on every sample)."""
    w = np.nan_to_num(np.maximum(np.asarray(weight, float), 0.0))
    if len(w) < 2:
        return None
    share = w / w.sum() if w.sum() > 0 else np.full(len(w), 1.0 / len(w))
    return [float(p) for p in 0.5 * share + 0.5 / len(w)]
