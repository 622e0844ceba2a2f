"""The windows of the Compositor method (``precompute/model/footprint.py``) against brute force: every pixel whose
centre ray meets a spot's cone, or sees a point of a box, lies in the pixels the window crops to.

The brute force is independent of the module: rays through pixel centres, points along them (log-spaced out
to twice the cut), the cone's test c >= cos(half) in the light's space.  Cases: random spots (cones from 1 to
180 degrees, non-uniform scales), cameras inside cones, cones behind the camera, random boxes; and spots seen past
an occluder (a flat quad ending the rays that meet it): a pixel needs the glow if its centre ray meets the cone
before the quad, or meets it anywhere while a ray within the margin of its centre misses the quad (the
compositor then mixes in the glow of the centre ray to the sky).
"""
import math

import numpy as np
import pytest

from fog_addon.precompute.model import footprint

W, H = 64, 36
FRAME = (-0.6, 0.6, -0.3375, 0.3375)   # a 36 mm sensor at a 30 mm lens, 16:9
# the random cases' seeds: three in the default tier (about 2 s each), six in the slow tier
SEEDS = [pytest.param(s, marks=[pytest.mark.slow] if s >= 3 else []) for s in range(6)]


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


@pytest.mark.parametrize("seed", SEEDS)
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


MARGIN = (2.5 / W, 2.5 / H)   # the occluder's picture is shrunk by this (``footprint.occluded_window``)
NEAR_CLIP = 0.1


def _quad_hit(cam, quad, rays, far=math.inf):
    """(...) distance along each ray (unit, from the camera) to the flat convex ``quad`` at depth >= NEAR_CLIP
    and distance <= ``far`` (the clip end), inf where it misses: the plane's crossing, inside every edge (brute
    force, independent of the module)."""
    eye = cam[:3, 3]
    normal = np.cross(quad[1] - quad[0], quad[2] - quad[0])
    with np.errstate(divide="ignore", invalid="ignore"):
        t = ((quad[0] - eye) @ normal) / (rays @ normal)
    p = eye + rays * t[..., None]
    inside = (t > 0.0) & ((rays @ -cam[:3, 2]) * t >= NEAR_CLIP) & (t <= far)
    for a, b in zip(quad, np.roll(quad, -1, axis=0)):
        inside &= (np.cross(b - a, p - a) @ normal) >= 0.0
    return np.where(inside, t, np.inf)


def _needs_glow(cam, light, cos_half, quad, far=math.inf):
    """(H, W) bool: the pixels whose glow can be non-zero with the quad ending rays (module docstring)."""
    t = np.concatenate([[0.0], np.geomspace(1e-3, 2.0 * footprint.GLOW_RADIUS, 1500)])
    rays = _rays(cam)
    p = cam[:3, 3] + rays[..., None, :] * t[:, None]
    q = (p - light[:3, 3]) @ np.linalg.inv(light[:3, :3]).T
    r = np.linalg.norm(q, axis=-1)
    inside = (-q[..., 2] >= cos_half * r) & (r <= footprint.GLOW_RADIUS) & (r > 0.0)
    hit = _quad_hit(cam, quad, rays, far)
    before = (inside & (t <= hit[..., None])).any(axis=-1)
    # partly covered: a ray within the margin's ellipse about the centre misses the quad
    u = (np.arange(W) + 0.5) / W
    v = (np.arange(H) + 0.5) / H
    open_sky = np.zeros((H, W), bool)
    for ang in np.linspace(0.0, 2.0 * math.pi, 24, endpoint=False):
        du, dv = 0.99 * MARGIN[0] * math.cos(ang), 0.99 * MARGIN[1] * math.sin(ang)
        x = FRAME[0] + (u + du) * (FRAME[1] - FRAME[0])
        y = FRAME[2] + (v + dv) * (FRAME[3] - FRAME[2])
        d = np.stack(np.broadcast_arrays(x[None, :], y[:, None], -1.0), axis=-1) @ cam[:3, :3].T
        open_sky |= np.isinf(_quad_hit(cam, quad, d / np.linalg.norm(d, axis=-1, keepdims=True), far))
    return before | (open_sky & inside.any(axis=-1))


def _random_quad(rng):
    """A flat rectangle: a floor or a ceiling, tilted, of random extent (its edges often in the picture)."""
    centre = rng.uniform((-6.0, 0.0, -1.0), (6.0, 30.0, 5.0))
    a, b = rng.uniform(-0.5, 0.5, 2)
    e1 = np.array([math.cos(a), 0.0, math.sin(a)]) * rng.uniform(1.0, 30.0)
    e2 = np.array([0.0, math.cos(b), math.sin(b)]) * rng.uniform(1.0, 30.0)
    return np.array([centre - e1 - e2, centre + e1 - e2, centre + e1 + e2, centre - e1 + e2])


@pytest.mark.parametrize("seed", SEEDS)
def test_occluded_windows_hold_every_pixel_needing_the_glow(seed):
    """Random spots (the cones of test_spot_windows_hold_every_hit, half of them aimed down) past a random
    quad: every pixel needing the glow (``_needs_glow``) lies in the crop of ``occluded_window``, which is never
    larger than the plain window; every third with the camera's clip end at 25 m (the quad's part beyond it
    ends no ray)."""
    rng = np.random.default_rng(200 + seed)
    cam = _look((0.0, -10.0, 2.0), (0.0, 5.0, 1.0))
    shrunk = 0
    for k in range(6):
        light = _random_spot(rng)
        if k % 2:
            light[:3, :3] = np.diag(rng.uniform(0.5, 1.5, 3))   # aimed straight down, squashed
        cos_half = math.cos(math.radians(rng.choice([1.0, 10.0, 60.0, 120.0, 179.0, 180.0])) / 2)
        quad = _random_quad(rng)
        far = 25.0 if k % 3 == 2 else math.inf
        pts = footprint.spot_points(light, cos_half)
        win = footprint.occluded_window(pts, quad, cam, FRAME, MARGIN, NEAR_CLIP, footprint.CONE_EDGES,
                                        footprint.clip_depth(far, FRAME))
        plain = footprint.window(pts, cam, FRAME)
        assert np.allclose(footprint.union(plain, win), plain, rtol=0.0, atol=1e-6), (win, plain)
        ok, crop = _in_crop(_needs_glow(cam, light, cos_half, quad, far), win)
        assert ok, (seed, k, crop)
        shrunk += win != plain
    assert shrunk, "no case shrank: the test would not see a window cut too far"


def test_spots_aimed_at_a_floor_are_cut_at_it():
    """The benchmark's spots (60 degrees, 3.5 m above the ground, aimed down): the crop holds the pixels needing
    the glow, is within 3 px of their bounding box, and a third of the plain window or less."""
    cam = _look((0.0, -11.0, 3.0), (0.0, 2.0, 0.8))
    ground = np.array([(-30.0, -20.0, 0.0), (30.0, -20.0, 0.0), (30.0, 40.0, 0.0), (-30.0, 40.0, 0.0)])
    cos_half = math.cos(math.radians(30.0))
    for where in ((2.0, 4.0, 3.5), (-6.0, 20.0, 3.5)):
        light = np.eye(4)
        light[:3, 3] = where
        pts = footprint.spot_points(light, cos_half)
        needs = _needs_glow(cam, light, cos_half, ground)
        rows, cols = np.nonzero(needs)
        x, y, w, h = footprint.pixels(footprint.occluded_window(pts, ground, cam, FRAME, MARGIN, NEAR_CLIP,
                                                                footprint.CONE_EDGES), W, H)
        assert 0 <= cols.min() - x <= 3 and 0 <= x + w - 1 - cols.max() <= 3, where
        assert 0 <= rows.min() - y <= 3 and 0 <= y + h - 1 - rows.max() <= 3, where
        px, py, pw, ph = footprint.pixels(footprint.window(pts, cam, FRAME), W, H)
        assert w * h <= pw * ph / 3.0, (where, (x, y, w, h), (px, py, pw, ph))


def test_clip_polytope_matches_the_pairwise_hull():
    """Cutting the cone's polytope along its edges, then the cut along its new edges, gives the hull the pairwise
    cut (every pair of points, ``clip_hull``) gives: the same support in every direction."""
    rng = np.random.default_rng(3)
    for _ in range(50):
        pts = footprint.spot_points(_random_spot(rng), math.cos(math.radians(rng.uniform(1.0, 180.0)) / 2))
        edges = footprint.CONE_EDGES
        for _cut in range(2):
            normal = rng.normal(size=3)
            offset = float(np.median(pts @ normal)) + rng.uniform(-1.0, 1.0)
            want = footprint.clip_hull(pts, normal, offset)
            pts, edges = footprint.clip_polytope(pts, edges, normal, offset)
            assert len(pts) > 0 and len(want) > 0
            scale = np.abs(want).max()
            for d in rng.normal(size=(20, 3)):
                assert math.isclose((pts @ d).max(), (want @ d).max(), rel_tol=1e-9, abs_tol=1e-9 * scale)


def _grid(n, hole=False, ell=False):
    """(corners, total area) of a flat n x n grid of unit quads in a tilted plane: one quad left out if ``hole``,
    a corner quarter if ``ell`` (an L shape)."""
    rot = np.array([[1.0, 0.0, 0.0], [0.0, math.cos(0.4), -math.sin(0.4)], [0.0, math.sin(0.4), math.cos(0.4)]])
    quads = [(i, j) for i in range(n) for j in range(n) if not (hole and (i, j) == (n // 2, n // 2))
             and not (ell and min(i, j) >= n // 2)]
    corners = {(i + a, j + b) for i, j in quads for a in (0, 1) for b in (0, 1)}
    pts = np.array([(x, y, 0.0) for x, y in sorted(corners)]) @ rot.T + (3.0, 5.0, 1.0)
    return pts, float(len(quads))


def test_flat_outline_of_a_floor_of_many_faces():
    """A subdivided floor's outline is its square (its area and corners); with a hole, an L shape, a bent
    floor or a missing area it is none."""
    pts, area = _grid(8)
    outline = footprint.flat_outline(pts, area)
    assert outline is not None and len(outline) == 4
    x, y = ((outline - outline.mean(axis=0)) @ np.linalg.svd(outline - outline.mean(axis=0))[2][:2].T).T
    assert math.isclose(0.5 * abs(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)), 64.0, rel_tol=1e-9)
    assert footprint.flat_outline(*_grid(8, hole=True)) is None
    assert footprint.flat_outline(*_grid(8, ell=True)) is None
    assert footprint.flat_outline(pts, area - 1.0) is None
    bent = pts.copy()
    bent[0] += (0.0, 0.0, 1e-3)
    assert footprint.flat_outline(bent, area) is None


def test_boxes_areas_rank_boxes_by_their_windows():
    """A box wholly in front covers at most the bounding box of its corners clipped to the picture: its window's
    share, exactly when its corners are in the picture; one crossing the camera's plane counts as the whole
    picture, one behind as none (the ranking of the meshes searched for occluders)."""
    rng = np.random.default_rng(9)
    cam = _look((0.0, -10.0, 2.0), (0.0, 5.0, 1.0))
    unit = np.array([[(0.0, 1.0)[(i >> k) & 1] for k in range(3)] for i in range(8)])
    boxes = np.array([footprint.box_points(unit * rng.uniform(0.1, 4.0, 3), _random_spot(rng)) for _ in range(40)])
    boxes = np.concatenate([boxes, unit[None] + (0.0, -10.5, 1.5), unit[None] + (0.0, -20.0, 0.0)])
    areas = footprint.boxes_areas(boxes, cam, FRAME)
    exact = 0
    for box, area in zip(boxes[:-2], areas):
        u0, u1, v0, v1 = footprint.window(box, cam, FRAME)
        assert (u1 - u0) * (v1 - v0) - 1e-9 <= area <= 1.0, (area, (u0, u1, v0, v1))
        if u0 > 0.0 and v0 > 0.0 and u1 < 1.0 and v1 < 1.0:
            assert math.isclose(area, (u1 - u0) * (v1 - v0), abs_tol=1e-9)
            exact += 1
    assert exact >= 5
    assert areas[-2] == 1.0 and areas[-1] == 0.0
