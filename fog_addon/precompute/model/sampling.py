"""Sampling one light of many per sample (the viewport preview's other lights, ``nodes/preview_sampled.py``; the
lights whose fog past glass a sample takes, ``nodes/glass_tails.py``): each light's importance, Walker's alias table
that draws it and the table the shaders read, and a draw among a few lights by stretches of [0, 1) (``picked``).

A pixel's fog light is a sum over the lights; a shader that takes one light j per sample, drawn with probability
p_j, and adds its light times 1 / p_j estimates that sum without bias (its mean over the draws is the sum), and the
samples a viewport adds up average the estimates.  Its noise is least when p_j follows each light's share of the
sum; ``importance`` guesses that share over the whole picture from the camera.
"""
import numpy as np

ROWS = 3             # the table's rows: 0 positions, 1 intensities over their probability, 2 (keep, alias)
MIN_DISTANCE = 1.0   # m: the distance below which a light's weight stops growing (1 / max(d, this))


def importance(positions, intensities, camera, beta):
    """Each light's share of the glows over the picture, up to a factor: I e^{-beta d} / max(d, MIN_DISTANCE)
    (I the RGB intensities' sum, d the distance to the camera, m)."""
    d = np.linalg.norm(np.asarray(positions, float) - np.asarray(camera, float), axis=-1)
    return np.asarray(intensities, float).sum(axis=-1) * np.exp(-beta * d) / np.maximum(d, MIN_DISTANCE)


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


def table_rows(positions, intensities, camera, beta):
    """(ROWS, N, 4) float32 of the lights (positions, m; RGB intensities I, W/sr; the camera's position; beta, 1/m):
    row 0 their positions, row 1 their intensities over their probability (I / p), row 2 (keep, alias column) of
    ``alias_table`` (``importance``)."""
    positions = np.asarray(positions, float).reshape(-1, 3)
    intensities = np.asarray(intensities, float).reshape(-1, 3)
    p, keep, alias = alias_table(importance(positions, intensities, camera, beta))
    rows = np.zeros((ROWS, len(p), 4), np.float32)
    rows[0, :, :3] = positions
    rows[1, :, :3] = intensities / np.maximum(p, 1e-30)[:, None]
    rows[2, :, 0], rows[2, :, 1] = keep, alias
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
