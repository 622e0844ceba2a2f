"""The numpy backend of the shader ops.

Per-pixel fog formulas (``model.py``) are written once against an ``m``
namespace: arithmetic operators on values plus the functions below.  This
module evaluates them with numpy; ``fog_addon/nodes/sockets.py`` builds the
very same formulas as shader nodes, and ``fog_addon/nodes/osl.py`` prints them
as OSL.  Every function here therefore does exactly what its node
counterpart does, including how a select mixes both branches (so a NaN or Inf
in the branch not taken poisons the numpy result just as it would the shader).

Scalars are arrays of shape (...); vectors are arrays of shape (..., 3).

:class:`ShaderOps` is the interface every backend implements.  A backend that
cannot do an operation says why when it is called: shader nodes have no loops
(``fori``), OSL cannot read packed images (``table``).  Kernels that need
either run through :meth:`ShaderOps.run`, which sends a model (``rungs.py``) to
a backend that can run it.
"""
from typing import Any, Callable, Protocol

import numpy as np


class ShaderOps(Protocol):
    """The operations per-pixel formulas may use (numpy, shader nodes, OSL).

    Values are backend objects with + - * / (scalar or vector; vector * vector
    is elementwise).  Semantics are those of Blender's Math / Vector Math nodes.
    """

    def const(self, x: float) -> Any: ...
    def exp(self, x) -> Any: ...
    def log(self, x) -> Any: ...             # natural logarithm; 0 at and below 0
    def sqrt(self, x) -> Any: ...            # 0 below 0
    def sin(self, x) -> Any: ...
    def cos(self, x) -> Any: ...
    def tan(self, x) -> Any: ...
    def mul_add(self, a, b, c) -> Any: ...     # a * b + c (scalars: one Multiply Add node)
    def floor(self, x) -> Any: ...
    def abs(self, x) -> Any: ...
    def minimum(self, a, b) -> Any: ...
    def maximum(self, a, b) -> Any: ...
    def atan2(self, y, x) -> Any: ...
    def power(self, x, y) -> Any: ...
    def less(self, a, b) -> Any: ...          # 1.0 where a < b else 0.0
    def select(self, cond, if_true, if_false) -> Any: ...
    def clamp01(self, x) -> Any: ...
    def smoothstep(self, edge0, edge1, x) -> Any: ...   # edge0 < edge1: one Map Range node (Smooth Step)
    def dot(self, a, b) -> Any: ...
    def cross(self, a, b) -> Any: ...
    def length(self, a) -> Any: ...
    def scale(self, v, s) -> Any: ...
    def combine(self, x, y, z) -> Any: ...
    def fori(self, count: int, body: Callable, state: tuple, done: Callable = None) -> tuple: ...
    def table(self, spec, x, y, row0: int = 0, rows: int = None, channel: int = 0,
              nearest: bool = False) -> Any: ...   # nearest: x, y on grid points (one texel read)
    def group(self, name, fn, *args) -> Any: ...   # fn(self, *args), shared as one sub-program (node group)
    def run(self, rung, *args) -> Any: ...    # a model's kernel on this backend (or one it delegates to)


class NumpyOps:
    """Shader ops on numpy arrays; ``tables`` maps TableSpec.name -> float32 array."""

    def __init__(self, tables=None, dtype=np.float64):
        self.tables = dict(tables or {})
        self.dtype = dtype

    # -- values ---------------------------------------------------------
    def const(self, x):
        return np.asarray(x, self.dtype)

    # -- scalar functions (Blender Math node operations) -------------------
    exp = staticmethod(np.exp)

    @staticmethod
    def log(x):
        """ln x, 0 at and below 0 (Blender's Math Logarithm)."""
        x = np.asarray(x, float)
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(x > 0.0, np.log(np.where(x > 0.0, x, 1.0)), 0.0)
    sqrt = staticmethod(lambda x: np.sqrt(np.maximum(x, 0.0)))   # Math SQRT returns 0 below 0
    sin = staticmethod(np.sin)
    cos = staticmethod(np.cos)
    tan = staticmethod(np.tan)

    @staticmethod
    def mul_add(a, b, c):
        return a * b + c
    floor = staticmethod(np.floor)
    abs = staticmethod(np.abs)
    minimum = staticmethod(np.minimum)
    maximum = staticmethod(np.maximum)

    @staticmethod
    def atan2(y, x):
        return np.arctan2(y, x)

    @staticmethod
    def power(x, y):
        """Math POWER; the kernel only calls it with x >= 0."""
        return np.power(x, y)

    @staticmethod
    def less(a, b):
        """1.0 where a < b, else 0.0 (Math LESS_THAN)."""
        return (np.asarray(a) < np.asarray(b)).astype(float)

    @staticmethod
    def select(cond, if_true, if_false):
        """cond in {0, 1}: cond * if_true + (1 - cond) * if_false, as the node tree does.

        The branch not taken is multiplied by exactly 0, so its rounding (a cancelled long-segment
        airlight, say) never leaks into the result; an Inf or NaN there still poisons it.
        """
        return cond * if_true + (1.0 - cond) * if_false

    @staticmethod
    def clamp01(x):
        return np.clip(x, 0.0, 1.0)

    @staticmethod
    def smoothstep(edge0, edge1, x):
        """t^2 (3 - 2 t), t = (x - edge0) / (edge1 - edge0) clamped to [0, 1] (Map Range, Smooth Step; GLSL's
        and OSL's smoothstep), for edge0 < edge1."""
        t = np.clip((np.asarray(x) - edge0) / (np.asarray(edge1) - edge0), 0.0, 1.0)
        return t * t * (3.0 - 2.0 * t)

    # -- vectors (Vector Math node operations) ------------------------------
    @staticmethod
    def dot(a, b):
        return np.sum(np.asarray(a) * np.asarray(b), axis=-1)

    @staticmethod
    def cross(a, b):
        return np.cross(a, b)

    @staticmethod
    def length(a):
        return np.sqrt(np.sum(np.asarray(a) ** 2, axis=-1))

    @staticmethod
    def scale(v, s):
        return np.asarray(v) * np.asarray(s)[..., None]

    @staticmethod
    def combine(x, y, z):
        return np.stack(np.broadcast_arrays(*(np.asarray(v, float) for v in (x, y, z))), axis=-1)

    # -- models ------------------------------------------------------------------
    def group(self, name, fn, *args):
        """``fn(self, *args)``: the node backend makes it one shared node group (``NodeOps.group``)."""
        return fn(self, *args)

    def run(self, rung, *args):
        """``rung.kernel`` on numpy (every kernel runs here: it is each model's reference twin)."""
        return rung.kernel(self, *args)

    # -- loops -------------------------------------------------------------------
    @staticmethod
    def fori(count, body, state, done=None):
        """Apply ``state = body(*state)`` ``count`` times; stop early once ``done(*state)`` is 1 everywhere.

        The OSL backend prints a ``for`` loop with ``if (done) break;`` per pixel:
        ``body`` must leave a finished state unchanged, so stopping early
        changes nothing (shader nodes have no loops).
        """
        state = tuple(state)
        for _ in range(count):
            state = tuple(body(*state))
            if done is not None and np.all(np.asarray(done(*state)) > 0.5):
                break
        return state

    # -- tables ---------------------------------------------------------------
    def table(self, spec, x, y, row0=0, rows=None, channel=0, nearest=False):
        """Bilinear lookup of table ``spec`` (its ``channel``) at grid coordinates x, y in [0, 1] (``nearest``:
        the caller put them on grid points, where the bilinear value is the texel's: the same value here).

        ``row0``/``rows`` select a horizontal band of the image (stacked tables).
        The same interpolation as the four Closest taps of the node version (a + t (b - a) here, a Multiply
        Add node there: equal but for rounding).
        """
        arr = self.tables[spec.name]
        arr = arr[..., channel] if arr.ndim == 3 else arr
        rows = arr.shape[0] if rows is None else rows
        w = arr.shape[1]
        fx = np.clip(x, 0.0, 1.0) * (w - 1)
        fy = np.clip(y, 0.0, 1.0) * (rows - 1)
        i = np.minimum(np.floor(fx), w - 2)
        j = np.minimum(np.floor(fy), rows - 2)
        tx, ty = fx - i, fy - j
        i = i.astype(int)
        j = j.astype(int) + row0
        v00, v10 = arr[j, i], arr[j, i + 1]
        v01, v11 = arr[j + 1, i], arr[j + 1, i + 1]
        a = v00 + tx * (v10 - v00)
        b = v01 + tx * (v11 - v01)
        return a + ty * (b - a)
