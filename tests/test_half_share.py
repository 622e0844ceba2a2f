"""The surface share's depth-aware upsampling (``comp_shafts._upsampled``), run by Blender's compositor on synthetic
images against the rule written out here in numpy.

Two surfaces meet at an odd column, so the coarse sample of the 2 x 2 block that straddles them lies on the near
one: the far surface's pixel in that block must take its far neighbour's sample, not its own.  With a step of
1 px (a picture too small to halve, ``comp_shafts.HALF_FROM``) every pixel keeps its own value; a step of 4 is a
picture of ``comp_shafts.QUARTER_FROM`` pixels or more.
"""
import json

import numpy as np
import pytest

from fog_scenes import render_harness as h

pytestmark = pytest.mark.render   # Blender's compositor, in a subprocess

W, H = 32, 16       # px: the picture
NEAR, FAR = 2.0, 20.0
EDGE_COLUMN = 13    # the first column of the far surface (odd: its block's sample lies on the near one)

_CODE = r"""
import json, sys
import bpy
import numpy as np
from fog_addon.nodes import comp_ops, comp_shafts
W, H, step = int(sys.argv[1]), int(sys.argv[2]), float(sys.argv[3])
data = json.loads(open(sys.argv[4]).read())
bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
scene.render.engine = "CYCLES"
scene.cycles.samples = 1
scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = W, H, 100
scene.render.image_settings.file_format = "OPEN_EXR"
scene.render.image_settings.color_depth = "32"
scene.view_settings.view_transform = "Standard"


def image(name, rows):
    a = np.asarray(rows, np.float32)
    img = bpy.data.images.new(name, a.shape[1], a.shape[0], alpha=True, float_buffer=True, is_data=True)
    img.colorspace_settings.name = "Non-Color"
    px = np.ones(a.shape[:2] + (4,), np.float32)
    px[..., :a.shape[2] if a.ndim == 3 else 3] = a if a.ndim == 3 else a[..., None]
    img.pixels.foreach_set(px.ravel())   # row 0 at the bottom, as the arrays are
    return img


tree = bpy.data.node_groups.new("Test", "CompositorNodeTree")
tree.interface.new_socket("Image", in_out="OUTPUT", socket_type="NodeSocketColor")
m = comp_ops.CompOps(tree, {})
reads = {}
for key in (k for k in data if k != "scaled"):
    node = tree.nodes.new("CompositorNodeImage")
    node.image = image(key, data[key])
    reads[key] = m.wrap(node.outputs["Image"], vector=True)
scalar = lambda v: m.dot(v, (1.0, 0.0, 0.0))
if "share" in data:   # the glows' lit shares at half resolution back at the picture's (_full_view)
    coarse = (lambda v: scalar(v)) if "scaled" not in data else (lambda v: scalar(comp_ops.scaled(m, v, 1.0 / step)))
    near, far = comp_shafts.full_view(m, [coarse(reads["share"]), coarse(reads["share_far"])],
                                    coarse(reads["half_length"]), scalar(reads["length"]), step)
    out = m.combine(near, far, 0.0)
else:
    out = comp_shafts.upsampled_group(m, reads["value"], scalar(reads["sample_length"]), scalar(reads["length"]), step)
rgba = tree.nodes.new("CompositorNodeSetAlpha")
m.feed(rgba.inputs["Image"], out)
tree.links.new(rgba.outputs[0], tree.nodes.new("NodeGroupOutput").inputs[0])
scene.compositing_node_group = tree
scene.render.filepath = sys.argv[5]
bpy.ops.render.render(write_still=True)
"""


def _upsampled(value, sample_length, length, step, edge):
    """The rule: a pixel's own sample where its distance matches in log within ``edge``, else the sum of its four
    neighbours' (``step`` px away) that match; its own always at a thousandth."""
    s = int(step)
    own_value = value[np.arange(H)[:, None] // s, np.arange(W)[None, :] // s]
    log, log_s = np.log(length), np.log(sample_length)
    own = np.abs(log_s - log) < edge
    others = np.zeros_like(own_value)
    for dx, dy in ((s, 0), (-s, 0), (0, s), (0, -s)):
        ys, xs = np.arange(H)[:, None] - dy, np.arange(W)[None, :] - dx
        inside = (ys >= 0) & (ys < H) & (xs >= 0) & (xs < W)
        yc, xc = np.clip(ys, 0, H - 1), np.clip(xs, 0, W - 1)
        match = inside & (np.abs(log_s[yc, xc] - log) < edge)
        others += np.where(match[..., None], own_value[yc, xc], 0.0)
    return own_value * (own + 1e-3)[..., None] + others * (1.0 - own)[..., None]


@pytest.mark.parametrize("step", [2, 4, 1])
def test_upsampling_keeps_each_surface_its_own_share(tmp_path, step):
    from fog_addon import imageio
    from fog_addon.nodes import comp_shafts
    rng = np.random.default_rng(7)
    cols = np.arange(W)
    length = np.broadcast_to(np.where(cols < EDGE_COLUMN, NEAR, FAR), (H, W)).astype(float)
    coarse = rng.uniform(0.2, 1.0, (H // step, W // step, 3))
    coarse_length = length[::step, ::step]   # a block's sample: its first pixel
    sample_length = coarse_length[np.arange(H)[:, None] // step, cols[None, :] // step]
    data = tmp_path / "data.json"
    data.write_text(json.dumps({"value": coarse.tolist(), "sample_length": sample_length.tolist(),
                                "length": length.tolist()}))
    out = tmp_path / "out.exr"
    h.run_bpy_code(_CODE, W, H, step, data, out, timeout=300)
    got = imageio.read_rgb(out)[::-1]   # the file's first row is the top
    want = _upsampled(coarse, sample_length, length, step, comp_shafts.UPSAMPLE_EDGE)
    if step == 2:   # the far surface's pixels in the straddling block take their far neighbour's sample
        assert np.allclose(want[:, EDGE_COLUMN], coarse[np.arange(H) // 2, (EDGE_COLUMN + 1) // 2]
                           + 1e-3 * coarse[np.arange(H) // 2, EDGE_COLUMN // 2])
    np.testing.assert_allclose(got, want, rtol=1e-5, atol=1e-6)


@pytest.mark.parametrize("step", [2, 4, 1])
def test_glow_shares_come_back_each_surface_its_own(tmp_path, step):
    """``comp_shafts.full_view``: the lit shares (S, S_far) of two surfaces, each constant over its surface at half
    resolution, come back at full resolution as the upsampling's rule divided by its weights (the interleaving's
    mean of a constant is that constant): their own surface's share, but for the straddling column's far pixels,
    whose own sample (on the near surface) counts a thousandth."""
    from fog_addon import imageio
    from fog_addon.nodes import comp_shafts
    cols = np.arange(W)
    length = np.broadcast_to(np.where(cols < EDGE_COLUMN, NEAR, FAR), (H, W)).astype(float)
    near_side = length == NEAR
    own = np.stack([np.where(near_side, 0.3, 0.8), np.where(near_side, 0.35, 0.85)], axis=-1)
    half_length = length[::step, ::step]   # a block's sample: its first pixel
    coarse = own[::step, ::step]
    sample_length = half_length[np.arange(H)[:, None] // step, cols[None, :] // step]
    packed = _upsampled(np.concatenate([coarse, np.ones(coarse.shape[:2] + (1,))], axis=-1), sample_length, length,
                        step, comp_shafts.UPSAMPLE_EDGE)
    want = packed[..., :2] / packed[..., 2:]
    assert np.abs(want - own).max() < 1e-3 * 0.5 + 1e-9   # (0.001 x 0.3 + 0.8) / 1.001 at the straddling column
    data = tmp_path / "data.json"
    data.write_text(json.dumps({"share": coarse[..., 0].tolist(), "share_far": coarse[..., 1].tolist(),
                                "half_length": half_length.tolist(), "length": length.tolist()}))
    out = tmp_path / "out.exr"
    h.run_bpy_code(_CODE, W, H, step, data, out, timeout=300)
    got = imageio.read_rgb(out)[::-1][..., :2]   # the file's first row is the top
    np.testing.assert_allclose(got, want, rtol=1e-5, atol=1e-6)


_SCALE_CODE = r"""
import json
import bpy
from fog_addon.nodes import comp_ops, comp_shafts
bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
tree = bpy.data.node_groups.new("Test", "CompositorNodeTree")
m = comp_ops.CompOps(tree, {})
coords = tree.nodes.new("CompositorNodeImageCoordinates")
pixel = m.wrap(coords.outputs["Pixel"], vector=True)
x, y = m.dot(pixel, (1.0, 0.0, 0.0)), m.dot(pixel, (0.0, 1.0, 0.0))
comp_shafts.halved(m, scene, pixel, pixel, x, y, m.wrap((0.0, 0.0, 0.0)), (x, y))
node = next(n for n in tree.nodes if n.label == "Surface Share Scale")
scene.compositing_node_group = tree   # in the depsgraph: its drivers are evaluated
out = []
for rx, ry, p in ((128, 72, 100), (256, 143, 100), (256, 144, 100), (640, 287, 100), (640, 360, 100),
                  (1920, 1080, 100), (1280, 720, 20), (1280, 720, 40)):
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = rx, ry, p
    scene.frame_set(1)
    out.append([rx, ry, p, node.outputs[0].default_value])
print("RESULT " + json.dumps(out))
"""


def test_share_scale_follows_the_render_size():
    """The shares' scale (``comp_shafts.halved``'s driver): 1 below HALF_FROM pixels on the picture's shorter side
    (its resolution times its percentage), 1/2 from there, 1/4 from QUARTER_FROM, exactly (the Scale nodes' sizes)."""
    from fog_addon.nodes import comp_shafts
    log = h.run_bpy_code(_SCALE_CODE, timeout=300).stdout
    rows = json.loads(next(ln for ln in log.splitlines() if ln.startswith("RESULT "))[7:])
    for rx, ry, p, factor in rows:
        side = min(rx, ry) * p // 100
        want = 0.25 if side >= comp_shafts.QUARTER_FROM else 0.5 if side >= comp_shafts.HALF_FROM else 1.0
        assert abs(factor - want) < 1e-6, (rx, ry, p, factor)


@pytest.mark.parametrize("width,height,step", [(30, 18, 4), (34, 17, 2), (31, 19, 4)])
def test_a_size_not_a_multiple_of_the_step_keeps_every_pixel(tmp_path, width, height, step):
    """Full-resolution shares scaled down (``comp_ops.scaled``, as ``comp_shafts.half_view`` does) and back
    (``full_view``) at a size the step does not divide: every pixel takes the share of a pixel at most ``step`` away
    in each direction (S holds each pixel's column, S_far its row); none is left at zero at the picture's edges."""
    from fog_addon import imageio
    rows, cols = np.mgrid[0:height, 0:width].astype(float)
    length = np.full((height, width), 5.0)
    data = tmp_path / "data.json"
    data.write_text(json.dumps({"share": (1.0 + cols).tolist(), "share_far": (1.0 + rows).tolist(),
                                "half_length": length.tolist(), "length": length.tolist(), "scaled": 1}))
    out = tmp_path / "out.exr"
    h.run_bpy_code(_CODE, width, height, step, data, out, timeout=300)
    got = imageio.read_rgb(out)[::-1]   # the file's first row is the top
    assert got.shape[:2] == (height, width)
    taken_col, taken_row = got[..., 0] - 1.0, got[..., 1] - 1.0
    assert got[..., :2].min() >= 1.0 - 1e-5   # no pixel without a share
    assert np.abs(taken_col - cols).max() <= step and np.abs(taken_row - rows).max() <= step
