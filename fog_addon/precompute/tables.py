"""Table layouts: the one definition of every table's size and coordinates.

The baker (``bake_*``), the node builder, the OSL generator and the tests all
take sizes and coordinate maps from here.

Convention for every table: a float32 array of shape (height, width); entry
``[j, i]`` holds the function at grid coordinates ``X = i / (width - 1)`` and
``Y = j / (height - 1)``.  In a Blender image row ``j`` is the ``j``-th row from
the bottom, so texel ``(i, j)`` sits at UV ``((i + .5) / width, (j + .5) / height)``.
Lookups are bilinear in (X, Y) with clamping at the edges, identical in numpy
(:func:`fog_addon.precompute.ops.NumpyOps.table`) and in the node tree.

Coordinate maps are written against an ``m`` ops namespace (numpy or node
sockets, see ``ops.py``) so the same code runs in both.
"""
from dataclasses import dataclass
import math

HALF_PI = 0.5 * math.pi


@dataclass(frozen=True)
class TableSpec:
    name: str          # Blender image name
    width: int         # samples along X
    height: int        # samples along Y


# Normalised airlight kernel N(rho, xi); see airlight.py.
AIRLIGHT = TableSpec("AnalyticFog Airlight N", 128, 64)

# Surface-scattering factor M_n(T, theta) for the Phong exponents below,
# stacked along Y: level k occupies rows [k * SURFACE_THETA, (k+1) * SURFACE_THETA).
SURFACE_T = 64
SURFACE_THETA = 64
PHONG_EXPONENTS = (1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0, 128.0, 256.0, 512.0, 1024.0)
SURFACE = TableSpec("AnalyticFog Surface M", SURFACE_T, SURFACE_THETA * len(PHONG_EXPONENTS))


def airlight_x(m, rho):
    """Grid X of the airlight table for optical radius rho >= 0: sqrt(rho/(1+rho))."""
    return m.sqrt(rho / (rho + 1.0))


def airlight_rho(x):
    """Inverse of :func:`airlight_x` (numpy floats); x = 1 maps to a large finite rho."""
    import numpy as np
    s = np.minimum(np.asarray(x, float) ** 2, 1.0 - 1e-12)
    return s / (1.0 - s)


def airlight_y(m, xi):
    """Grid Y of the airlight table for the angle xi in [0, pi/2]."""
    return xi * (1.0 / HALF_PI)
