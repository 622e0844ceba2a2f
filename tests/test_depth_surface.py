"""EEVEE's surface point in the Compositor method (``pixel.depth_surface``) at the pass values that gave NaN.

The haze valley (``fog_scenes/haze.py``: a 1 mm - 200 km camera, clip end / clip start 2e8) rendered in EEVEE left
the ground plane out (it reaches behind the camera): on those 1216 of 3600 pixels (80 x 45) the Depth pass read
+inf, the View Z Depth AOV 0 and the coverage AOV 0.  The surface point's choice between the Depth pass and the
mean View Z Depth is a Mix node, (1 - c) a + c b, so with c = 0 it gave 0 x inf = NaN, and NaN spread to every
term of those pixels' fog.  The values below are that render's (``ViewLayer.Depth``, ``Fog Depth``,
``Fog Coverage`` of its multilayer EXR), evaluated by the same kernel numpy runs."""
import numpy as np
import pytest

from fog_addon.precompute.model import pixel
from fog_addon.precompute.physics.point import model
from fog_addon.precompute.core.ops import NumpyOps

CAM = np.array([0.0, 0.0, 300.0])
# the bottom-left pixel's ray at unit view depth (the valley's camera: 4 degrees down, 39.6 x 22.9 degree view)
RAY = np.array([-0.36, 0.922, -0.269])


def _inputs(depth_pass, fog_depth, coverage, dtype):
    """The fog group's inputs as ``build_fog_group`` forms them: the mean View Z Depth = AOV / max(coverage, 1e-6)."""
    mean_depth = np.asarray(fog_depth, dtype) * (1.0 / np.maximum(np.asarray(coverage, dtype), 1e-6))
    return np.asarray(depth_pass, dtype), mean_depth.astype(dtype)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_an_infinite_depth_pass_where_nothing_was_drawn_gives_the_camera(dtype):
    """The render's values: Depth +inf, View Z Depth AOV 0, coverage 0: a finite point (the camera, as for any
    pixel that sees no surface), not NaN."""
    m = NumpyOps(dtype=dtype)
    depth, mean = _inputs(np.inf, 0.0, 0.0, dtype)
    with np.errstate(invalid="raise", over="raise"):
        pos = pixel.depth_surface(m, CAM.astype(dtype), RAY.astype(dtype), depth, mean)
    assert np.isfinite(pos).all()
    assert np.array_equal(pos, CAM.astype(dtype))


def test_the_unguarded_choice_is_nan():
    """The cause: the Mix node's choice multiplies the branch not taken by 0, and 0 x inf is NaN."""
    with np.errstate(invalid="ignore"):
        assert np.isnan(NumpyOps.select(0.0, np.inf, 0.0))


def test_a_surface_with_an_infinite_depth_pass_takes_the_mean_depth():
    """A pixel whose samples met a surface (coverage 1, View Z Depth 1144 m) but whose Depth pass is +inf."""
    m = NumpyOps()
    depth, mean = _inputs(np.inf, 1144.0, 1.0, np.float64)
    pos = pixel.depth_surface(m, CAM, RAY, depth, mean)
    assert np.allclose(pos, CAM + RAY * 1144.0, rtol=0, atol=1e-9)


def test_finite_depths_are_unchanged():
    """Where the Depth pass is finite the guard changes nothing: within 2 % of the mean View Z Depth the Depth pass
    (bit for bit), else the mean (the 22 km ridge read 16384 in the Depth pass at the 2e8 clip ratio, 21952 in
    the AOV); a value at model.FAR itself passes too."""
    m = NumpyOps(dtype=np.float32)
    depth_pass = np.array([1560.381, 16384.0, 8192.0, 2.000122, model.FAR], np.float32)
    fog_depth = np.array([1555.0, 21952.0, 0.0, 2.0, 0.0], np.float32)
    coverage = np.array([1.0, 1.0, 0.0, 1.0, 0.0], np.float32)
    depth, mean = _inputs(depth_pass, fog_depth, coverage, np.float32)
    cam, ray = CAM.astype(np.float32), RAY.astype(np.float32)
    pos = pixel.depth_surface(m, cam, ray, depth, mean)
    agree = m.less(m.abs(depth - mean), pixel.DEPTH_AGREE * mean)   # the formula before the guard
    assert agree.tolist() == [1.0, 0.0, 0.0, 1.0, 0.0]
    assert np.array_equal(pos, cam + m.scale(ray, m.select(agree, depth, mean)))
    assert np.allclose(pos, CAM + RAY * np.where(agree > 0, depth, mean)[:, None], rtol=1e-6)
