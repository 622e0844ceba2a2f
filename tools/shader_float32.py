"""The airlight kernels evaluated in float32, every intermediate, as a GPU / SVM shader does.

Shared by tests/test_airlight.py, tests/test_stability.py and
tools/stability_map.py.  ``Float32Ops`` is ``NumpyOps`` with float32 values,
a float32 LESS_THAN and float32 table taps; the kernels are the model's own
(``model.airlight_segment`` / ``airlight_background`` for the node groups'
table method, ``model.airlight_quadrature`` for the OSL method).

Inputs are float64 (beta, D_sv, D_vp, gamma) as elsewhere; what the shader
receives is (beta, D_sv, along = D_sv cos gamma, h = D_sv sin gamma, D_vp)
rounded once to float32 (``model.ray_light_geometry`` derives them from
vectors; tests/test_airlight.py::test_float32_from_vectors checks that path).
"""
import numpy as np

from fog_addon.precompute.core import tables
from fog_addon.precompute.physics.point import model
from fog_addon.precompute.core.ops import NumpyOps


class Float32Ops(NumpyOps):
    """NumpyOps that keeps every intermediate in float32, as a GPU/SVM shader does."""

    def __init__(self, tables_):
        super().__init__(tables_, dtype=np.float32)

    @staticmethod
    def less(a, b):
        return (np.asarray(a) < np.asarray(b)).astype(np.float32)

    def table(self, spec, x, y, row0=0, rows=None):
        return np.asarray(super().table(spec, x, y, row0, rows), np.float32)


def shader_inputs(beta, d_sv, d_vp, gamma):
    """(beta, d_sv, along, h, d_vp or 0, finite mask): float32 arrays at least 1-D (no 0-d scalar casting)."""
    beta, d_sv, d_vp, gamma = np.broadcast_arrays(*(np.atleast_1d(np.asarray(v, float)) for v in (beta, d_sv, d_vp, gamma)))
    along, h = d_sv * np.cos(gamma), d_sv * np.sin(gamma)
    finite = np.isfinite(d_vp)
    f = lambda x: np.asarray(x, np.float32)
    return f(beta), f(d_sv), f(along), f(h), f(np.where(finite, d_vp, 0.0)), finite


def airlight_float32(beta, d_sv, d_vp, gamma, table):
    """``airlight.airlight(..., table=table)`` (the node groups' table method) in float32; d_vp may be inf."""
    m = Float32Ops({tables.AIRLIGHT.name: table})
    beta, d_sv, along, h, dvp, finite = shader_inputs(beta, d_sv, d_vp, gamma)
    with np.errstate(over="ignore", invalid="ignore", divide="ignore", under="ignore"):
        seg = model.airlight_segment(m, beta, d_sv, along, h, dvp)
        bg = model.airlight_background(m, beta, d_sv, along, h)
    assert seg.dtype == np.float32 and bg.dtype == np.float32
    return np.where(finite, seg, bg)


def airlight_quadrature_float32(beta, d_sv, d_vp, gamma):
    """``airlight.airlight(..., quadrature=True)`` (the OSL method) in float32; d_vp = inf is model.FAR."""
    m = Float32Ops({})
    beta, d_sv, along, h, dvp, finite = shader_inputs(beta, d_sv, d_vp, gamma)
    dvp = np.where(finite, dvp, np.float32(model.FAR))
    with np.errstate(over="ignore", invalid="ignore", divide="ignore", under="ignore"):
        out = model.airlight_quadrature(m, beta, d_sv, along, h, dvp)
    assert out.dtype == np.float32
    return out
