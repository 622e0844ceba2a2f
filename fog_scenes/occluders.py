"""Closed-form occluders for the light shafts' tests and benchmarks: exact visibility, independent of the maps
and quadratures under test (tests/test_shafts.py, benchmarks/shafts_stability.py)."""
import numpy as np

NO_HIT = 1.0e30   # m: a direction that meets nothing (as ``shaft_maps.NO_HIT``, the maps' value for it)


def sphere_hit(origin, dirs, centre, radius):
    """Distance (m) along the unit rows of ``dirs`` from ``origin`` to a sphere's near side, NO_HIT where the ray
    misses it or starts inside or past it."""
    oc = np.asarray(origin, float) - np.asarray(centre, float)
    b = dirs @ oc
    c = oc @ oc - radius * radius
    disc = b * b - c
    t = -b - np.sqrt(np.maximum(disc, 0.0))
    return np.where((disc > 0) & (t > 0), t, NO_HIT)


def box_hit(origins, direction, lo, hi):
    """Distance along the unit ``direction`` from each row of ``origins`` (N, 3) to an axis-aligned box [lo, hi]
    (slab test), NO_HIT where the ray misses it; 0 for an origin inside it."""
    o = np.asarray(origins, float).reshape(-1, 3)
    d = np.asarray(direction, float)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / np.where(np.abs(d) < 1e-15, 1e-15, d)
        t0 = (np.asarray(lo, float) - o) * inv
        t1 = (np.asarray(hi, float) - o) * inv
    near = np.minimum(t0, t1).max(axis=1)
    far = np.maximum(t0, t1).min(axis=1)
    return np.where((far >= np.maximum(near, 0.0)), np.maximum(near, 0.0), NO_HIT)
