"""The windows of the Compositor method (``precompute/footprint.py``) against brute force: every pixel whose
centre ray meets a spot's cone, or sees a point of a box, lies in the pixels the window crops to.

The brute force is independent of the module: rays through pixel centres, points along them (log-spaced out
to twice the cut), the cone's test c >= cos(half) in the light's space.  Cases: random spots (cones from 1 to
180 degrees, non-uniform scales), cameras inside cones, cones behind the camera, random boxes.
"""
import math

import numpy as np
import pytest

from fog_addon.precompute import footprint

W, H = 64, 36
FRAME = (-0.6, 0.6, -0.3375, 0.3375)   # a 36 mm sensor at a 30 mm lens, 16:9


def _look(eye, target):
    f = np.subtract(target, eye, dtype=float)
    f /= np.linalg.norm(f)
    r = np.cross(f, (0.0, 0.0, 1.0))
    r /= np.linalg.norm(r)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = r, np.cross(r, f), -f, eye
    return m


def _rays(cam):
    u = (np.arange(W) + 0.5) / W
    v = (np.arange(H) + 0.5) / H
    x = FRAME[0] + u * (FRAME[1] - FRAME[0])
    y = FRAME[2] + v * (FRAME[3] - FRAME[2])
    local = np.stack(np.broadcast_arrays(x[None, :], y[:, None], -1.0), axis=-1)   # (H, W, 3)
    d = local @ cam[:3, :3].T
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def _cone_hits(cam, light, cos_half):
    """(H, W) bool: the pixel's centre ray meets the cone within GLOW_RADIUS (light space) of the apex."""
    t = np.concatenate([[0.0], np.geomspace(1e-3, 2.0 * footprint.GLOW_RADIUS, 1500)])
    p = cam[:3, 3] + _rays(cam)[..., None, :] * t[:, None]                     # (H, W, T, 3)
    q = (p - light[:3, 3]) @ np.linalg.inv(light[:3, :3]).T
    r = np.linalg.norm(q, axis=-1)
    inside = (-q[..., 2] >= cos_half * r) & (r <= footprint.GLOW_RADIUS) & (r > 0.0)
    return inside.any(axis=-1)


def _in_crop(hits, win):
    x, y, w, h = footprint.pixels(win, W, H)
    rows, cols = np.nonzero(hits)
    return bool(((cols >= x) & (cols < x + w) & (rows >= y) & (rows < y + h)).all()), (x, y, w, h)


def _random_spot(rng):
    light = np.eye(4)
    a, b, c = rng.uniform(-math.pi, math.pi, 3)
    rz = np.array([[math.cos(c), -math.sin(c), 0], [math.sin(c), math.cos(c), 0], [0, 0, 1]])
    rx = np.array([[1, 0, 0], [0, math.cos(a), -math.sin(a)], [0, math.sin(a), math.cos(a)]])
    ry = np.array([[math.cos(b), 0, math.sin(b)], [0, 1, 0], [-math.sin(b), 0, math.cos(b)]])
    light[:3, :3] = rz @ ry @ rx @ np.diag(rng.uniform(0.3, 2.0, 3))
    light[:3, 3] = rng.uniform(-8.0, 8.0, 3) + (0.0, 12.0, 0.0)
    return light


@pytest.mark.parametrize("seed", range(6))
def test_spot_windows_hold_every_hit(seed):
    rng = np.random.default_rng(seed)
    cam = _look((0.0, -10.0, 2.0), (0.0, 5.0, 1.0))
    for _ in range(5):
        light = _random_spot(rng)
        cos_half = math.cos(math.radians(rng.choice([1.0, 10.0, 60.0, 120.0, 179.0, 180.0])) / 2)
        hits = _cone_hits(cam, light, cos_half)
        win = footprint.window(footprint.spot_points(light, cos_half), cam, FRAME)
        ok, crop = _in_crop(hits, win)
        assert ok, (seed, crop, np.argwhere(hits)[:5])


def test_spot_window_is_tight():
    """A 60-degree spot aimed down, seen from the side: the crop is within 3 px of the hits' bounding box
    (the polygon about the axis circumscribes the circle)."""
    cam = _look((0.0, -11.0, 3.0), (0.0, 2.0, 0.8))
    light = np.eye(4)
    light[:3, 3] = (2.0, 4.0, 3.5)
    cos_half = math.cos(math.radians(30.0))
    hits = _cone_hits(cam, light, cos_half)
    rows, cols = np.nonzero(hits)
    x, y, w, h = footprint.pixels(footprint.window(footprint.spot_points(light, cos_half), cam, FRAME), W, H)
    assert 0 <= cols.min() - x <= 3 and 0 <= x + w - 1 - cols.max() <= 3
    assert 0 <= rows.min() - y <= 3 and 0 <= y + h - 1 - rows.max() <= 3


def test_camera_inside_the_cone_and_cone_behind_it():
    cam = _look((0.0, 0.0, 0.0), (0.0, 10.0, 0.0))
    light = np.eye(4)
    light[:3, :3] = [[1, 0, 0], [0, 0, 1], [0, -1, 0]]   # the cone's axis (-Z) along -Y: toward the camera
    light[:3, 3] = (0.0, 5.0, 0.0)
    win = footprint.window(footprint.spot_points(light, math.cos(math.radians(20.0))), cam, FRAME)
    assert footprint.pixels(win, W, H) == (0, 0, W, H)
    light[:3, 3] = (0.0, -3.0, 0.0)   # behind the camera, pointing away from it
    assert footprint.window(footprint.spot_points(light, math.cos(math.radians(20.0))), cam, FRAME) == \
        footprint.EMPTY


@pytest.mark.parametrize("seed", range(4))
def test_box_windows_hold_every_point(seed):
    rng = np.random.default_rng(100 + seed)
    cam = _look((0.0, -10.0, 2.0), (0.0, 5.0, 1.0))
    for _ in range(10):
        matrix = _random_spot(rng)
        lo = rng.uniform(-3.0, 0.0, 3)
        hi = lo + rng.uniform(0.01, 6.0, 3)
        box = np.array([[(lo[k], hi[k])[(i >> k) & 1] for k in range(3)] for i in range(8)])
        win = footprint.window(footprint.box_points(box, matrix), cam, FRAME)
        pts = rng.uniform(lo, hi, (20000, 3)) @ matrix[:3, :3].T + matrix[:3, 3]
        local = (pts - cam[:3, 3]) @ cam[:3, :3]
        front = local[:, 2] < -1e-6
        u = (local[front, 0] / -local[front, 2] - FRAME[0]) / (FRAME[1] - FRAME[0])
        v = (local[front, 1] / -local[front, 2] - FRAME[2]) / (FRAME[3] - FRAME[2])
        seen = (u >= 0) & (u <= 1) & (v >= 0) & (v <= 1)
        if seen.any():
            assert win[0] <= u[seen].min() and u[seen].max() <= win[1], (seed, win)
            assert win[2] <= v[seen].min() and v[seen].max() <= win[3], (seed, win)


@pytest.mark.parametrize("size", [1, 2, 57, 320, 1081])
def test_pixels_hold_the_window_with_the_pictures_parity(size):
    rng = np.random.default_rng(size)
    for _ in range(200):
        lo, hi = np.sort(rng.uniform(0.0, 1.0, 2))
        x, y, w, h = footprint.pixels((lo, hi, lo, hi), size, size)
        centres = (np.arange(size) + 0.5) / size
        want = np.nonzero((centres >= lo) & (centres <= hi))[0]
        assert x >= 0 and x + w <= max(size, 2) and (size - w) % 2 == 0
        if len(want):
            assert x <= want.min() and want.max() < x + w


def test_boxes_window_holds_each_boxs_window():
    """The union over boxes at once (in front: their corners' bounding box) holds each box's own window,
    and ignores boxes outside the frame."""
    rng = np.random.default_rng(7)
    cam = _look((0.0, -10.0, 2.0), (0.0, 5.0, 1.0))
    unit = np.array([[(0.0, 1.0)[(i >> k) & 1] for k in range(3)] for i in range(8)])
    boxes = []
    for _ in range(30):
        matrix = _random_spot(rng)
        boxes.append(footprint.box_points(unit * rng.uniform(0.1, 4.0, 3), matrix))
    boxes = np.array(boxes)
    whole = footprint.boxes_window(boxes, cam, FRAME)
    for box in boxes:
        assert footprint.union(whole, footprint.window(box, cam, FRAME)) == whole
    off = footprint.box_points(unit, np.eye(4)) + (-40.0, 10.0, 0.0)   # far to the left, in front
    assert footprint.boxes_window(off[None], cam, FRAME) == footprint.EMPTY
