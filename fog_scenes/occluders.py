"""Closed-form occluders for the light shafts' tests and benchmarks: exact visibility, independent of the maps
and quadratures under test (tests/test_shafts.py, benchmarks/shafts_stability.py)."""
import numpy as np

NO_HIT = 1.0e30   # m: a direction that meets nothing (as ``shafts.NO_HIT``, the maps' value for it)


def sphere_hit(origin, dirs, centre, radius):
    """Distance (m) along the unit rows of ``dirs`` from ``origin`` to a sphere's near side, NO_HIT where the ray
    misses it or starts inside or past it."""
    oc = np.asarray(origin, float) - np.asarray(centre, float)
    b = dirs @ oc
    c = oc @ oc - radius * radius
    disc = b * b - c
    t = -b - np.sqrt(np.maximum(disc, 0.0))
    return np.where((disc > 0) & (t > 0), t, NO_HIT)
