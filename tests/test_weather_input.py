"""What ``weather`` reads (issue 43, "weather reads what it is given"; ``weather.read_image``, ``read_depth``).

Blender 5.0 writes a multilayer EXR as a multi-part file, one part per pass ("ViewLayer.Combined" with channels
"ViewLayer.Combined.R, G, B, A", "ViewLayer.Depth" with "ViewLayer.Depth.Z", ...).  ``--depth`` read its channel 0
(Combined's red) as metres, and an 8-bit PNG was read as linear light (or as depth of 0-1 m), silently.  Here the
picture and the depth are found by name, whatever their order; what names do not settle is refused naming the
channels found; integer images are decoded from sRGB (as IMAGE, with a note) or refused (as DEPTH).

The files are written with ``imageio.write_layers``, which ``test_blenders_own_multilayer_exr`` checks against a
file Blender 5.0 renders (same parts, channel names and order), and on which it measures the issue's figure.
"""
import io
import json
import math
import subprocess
import sys

import numpy as np
import pytest

from fog_addon import imageio, weather

H, W = 24, 32
VISIBILITY = 20.0   # m: beta 0.196, T 1.6-2.4 over the scene's 8-12 m


def scene():
    """A fog-free picture (H, W, 4) with a bright window on a dim wall, and its depth (8-12 m, sky at the top)."""
    rng = np.random.default_rng(43)
    rgba = np.ones((H, W, 4), np.float32)
    rgba[..., :3] = 0.05 + 0.1 * rng.random((H, W, 3))
    rgba[10:14, 6:10, :3] = 20.0
    z = np.tile(np.linspace(8.0, 12.0, W, dtype=np.float32), (H, 1))
    z[:4] = 1e10
    rgba[:4, :, :3] = 0.5
    return rgba, z


def blender_layers(rgba, z, layer="ViewLayer"):
    """The parts Blender 5.0 writes for a view layer with the Combined and Z passes, in its order."""
    return {f"{layer}.Combined": (rgba, "RGBA"), f"{layer}.Depth": (z, "Z")}


def decoys(z):
    """Blender passes that are not depth although named ...Z: Mist (0-1), Position, Normal."""
    xyz = np.dstack([z, z, z])
    return {"ViewLayer.Mist": (np.clip(z / 100.0, 0, 1), "Z"), "ViewLayer.Position": (xyz, "XYZ"),
            "ViewLayer.Normal": (xyz / 20.0, "XYZ")}


def fog(image, depth, **kw):
    """``weather.run`` on two files (or one), returning (picture, what it said)."""
    out, said = image.parent / "out.exr", io.StringIO()
    pic = weather.run(image, depth, out, VISIBILITY, stream=said, **kw)
    return pic, said.getvalue()


def write_single(tmp_path, rgba, z):
    """The picture as a plain RGB EXR and the depth on its own as a single-channel EXR."""
    imageio.write_exr(tmp_path / "rgb.exr", rgba[..., :3])
    imageio.write_exr(tmp_path / "z.exr", z[..., None])
    return tmp_path / "rgb.exr", tmp_path / "z.exr"


def max_rel(a, b):
    return float(np.max(np.abs(a - b) / np.maximum(np.abs(b), 1e-6)))


def test_multilayer_depth_gives_the_single_channel_picture(tmp_path):
    """The issue's measure: the multilayer EXR as IMAGE and as DEPTH gives the picture the plain RGB EXR and the
    Z pass on its own give, within 1 % (it is the same data: measured 0).  The parts are written with decoys
    first (Mist, Position, Normal: "...Z" channels that are not depth), so position decides nothing."""
    rgba, z = scene()
    rgb_path, z_path = write_single(tmp_path, rgba, z)
    imageio.write_layers(tmp_path / "ml.exr", {**decoys(z), **blender_layers(rgba, z)})
    want, _ = fog(rgb_path, z_path, depth_kind="z")   # (a lone channel is taken as distance unless told)
    got, said = fog(tmp_path / "ml.exr", tmp_path / "ml.exr")
    assert max_rel(got, want) < 0.01
    assert "image: ViewLayer.Combined (R, G, B)" in said and "depth: ViewLayer.Depth.Z" in said


def test_single_part_layers_and_a_plain_z_channel(tmp_path):
    """The same names in one part (how other programs write multilayer EXR), and a plain R, G, B, A, Z EXR:
    the picture is R, G, B and the depth Z; a single-channel EXR is the depth whatever its channel's name, but
    Blender's Mist pass alone (0-1, not metres) is refused."""
    rgba, z = scene()
    o = imageio.oiio()
    names = ("ViewLayer.Mist.Z", "ViewLayer.Combined.R", "ViewLayer.Combined.G", "ViewLayer.Combined.B",
             "ViewLayer.Combined.A", "ViewLayer.Depth.Z")
    for path, chans, data in ((tmp_path / "one.exr", names, np.dstack([z / 100.0, rgba, z])),
                              (tmp_path / "rgbaz.exr", ("R", "G", "B", "A", "Z"), np.dstack([rgba, z]))):
        spec = o.ImageSpec(W, H, len(chans), "float")
        spec.channelnames = chans
        imageio._write(path, spec, np.ascontiguousarray(data, np.float32))
        np.testing.assert_array_equal(weather.read_image(path), rgba[..., :3])
        np.testing.assert_array_equal(weather.read_depth(path), z)
    imageio.write_exr(tmp_path / "y.exr", z[..., None])
    np.testing.assert_array_equal(weather.read_depth(tmp_path / "y.exr"), z)
    imageio.write_layers(tmp_path / "mist.exr", {"ViewLayer.Mist": (z / 100.0, "Z")})
    with pytest.raises(weather.WeatherError, match="Mist pass"):
        weather.read_depth(tmp_path / "mist.exr")


def test_the_compositors_picture_is_taken_and_said(tmp_path):
    """Blender with its compositor on writes "Composite.Combined" before the view layer's passes: that is the
    picture (said, with the flag for the render's own); --image-pass takes the other."""
    rgba, z = scene()
    comp = rgba.copy()
    comp[..., :3] *= 2.0
    imageio.write_layers(tmp_path / "c.exr", {"Composite.Combined": (comp, "RGBA"), **blender_layers(rgba, z)})
    said = []
    np.testing.assert_array_equal(weather.read_image(tmp_path / "c.exr", note=said.append), comp[..., :3])
    assert "Composite.Combined" in said[0] and "--image-pass ViewLayer.Combined" in said[0]
    np.testing.assert_array_equal(weather.read_image(tmp_path / "c.exr", "ViewLayer.Combined"), rgba[..., :3])


def test_ambiguous_files_are_refused_naming_their_channels(tmp_path):
    """Two view layers: two pictures and two depths, each refused naming them, then chosen by --image-pass and
    --depth-pass.  A file with no depth channel (R, G, B; or only Mist and Position) and one with no picture
    are refused naming what they hold."""
    rgba, z = scene()
    two = tmp_path / "two.exr"
    imageio.write_layers(two, {**blender_layers(rgba, z), **blender_layers(rgba * 3.0, z + 1.0, "Second")})
    with pytest.raises(weather.WeatherError, match="several pictures") as e:
        weather.read_image(two)
    assert "ViewLayer.Combined" in str(e.value) and "Second.Combined" in str(e.value)
    with pytest.raises(weather.WeatherError, match="several depth channels") as e:
        weather.read_depth(two)
    assert "ViewLayer.Depth.Z, Second.Depth.Z" in str(e.value) and "--depth-pass" in str(e.value)
    np.testing.assert_array_equal(weather.read_image(two, "Second.Combined"), rgba[..., :3] * 3.0)
    np.testing.assert_array_equal(weather.read_depth(two, "Second.Depth"), z + 1.0)
    np.testing.assert_array_equal(weather.read_depth(two, "Second.Depth.Z"), z + 1.0)
    with pytest.raises(weather.WeatherError, match="no pass 'Third.Combined'"):
        weather.read_image(two, "Third.Combined")

    imageio.write_exr(tmp_path / "rgb.exr", rgba[..., :3])
    with pytest.raises(weather.WeatherError, match=r"no depth channel .* channels: R, G, B\."):
        weather.read_depth(tmp_path / "rgb.exr")
    imageio.write_layers(tmp_path / "mist.exr", {"ViewLayer.Combined": (rgba, "RGBA"), **decoys(z)})
    with pytest.raises(weather.WeatherError, match="no depth channel") as e:
        weather.read_depth(tmp_path / "mist.exr")
    assert "ViewLayer.Mist (Z)" in str(e.value) and "ViewLayer.Position (X, Y, Z)" in str(e.value)
    imageio.write_layers(tmp_path / "nopic.exr", {"ViewLayer.Depth": (z, "Z"), **decoys(z)})
    with pytest.raises(weather.WeatherError, match="no picture to fog") as e:
        weather.read_image(tmp_path / "nopic.exr")
    assert "ViewLayer.Depth (Z)" in str(e.value)


@pytest.mark.parametrize("bits", [8, 16])
def test_an_integer_picture_is_decoded_from_srgb(tmp_path, bits):
    """An 8- or 16-bit PNG holds sRGB-encoded levels: IMAGE decodes them to linear light (0.5 -> 0.214) and
    says so; the same levels as a float EXR are taken as they are."""
    levels = np.linspace(0.0, 1.0, H * W * 3, dtype=np.float32).reshape(H, W, 3)
    imageio.write_png(tmp_path / "p.png", levels, bits=bits)
    said = []
    got = weather.read_image(tmp_path / "p.png", note=said.append)
    stored = np.round(levels * (2 ** bits - 1)) / (2 ** bits - 1)
    np.testing.assert_allclose(got, imageio.srgb_to_linear(stored), rtol=1e-5, atol=1e-7)
    assert float(imageio.srgb_to_linear(0.5)) == pytest.approx(0.21404, abs=1e-5)
    assert f"{bits}-bit" in said[0] and "converted from sRGB to linear" in said[0]


def test_an_integer_depth_is_refused(tmp_path):
    """A PNG holds grey levels, not metres: as DEPTH it is refused (grey or RGB, 8 or 16 bits), saying why and
    what to give instead, before any fog is computed."""
    _, z = scene()
    imageio.write_png(tmp_path / "g16.png", np.clip(z / 12.0, 0, 1)[..., None], bits=16)
    imageio.write_png(tmp_path / "rgb8.png", np.dstack([np.clip(z / 12.0, 0, 1)] * 3))
    for name, bits in (("g16.png", "16-bit"), ("rgb8.png", "8-bit")):
        with pytest.raises(weather.WeatherError, match=f"integer image \\({bits}") as e:
            weather.read_depth(tmp_path / name)
        assert "not metres" in str(e.value) and "float EXR" in str(e.value)


def test_command_line_says_what_it_read(tmp_path):
    """``python -m fog_addon weather``: a PNG picture with a multilayer depth runs and says both; a PNG depth
    exits 2 with the reason; two view layers exit 2 naming the choices."""
    rgba, z = scene()
    imageio.write_png(tmp_path / "p.png", np.clip(rgba[..., :3], 0, 1))
    imageio.write_layers(tmp_path / "ml.exr", blender_layers(rgba, z))
    imageio.write_layers(tmp_path / "two.exr", {**blender_layers(rgba, z), **blender_layers(rgba, z, "Second")})
    base = [sys.executable, "-m", "fog_addon", "weather", "--visibility", "20", "--out", str(tmp_path / "o.exr")]
    ok = subprocess.run(base + [str(tmp_path / "p.png"), "--depth", str(tmp_path / "ml.exr")], capture_output=True,
                        text=True)
    assert ok.returncode == 0, ok.stderr
    assert "converted from sRGB to linear" in ok.stderr and "depth: ViewLayer.Depth.Z" in ok.stderr
    bad = subprocess.run(base + [str(tmp_path / "ml.exr"), "--depth", str(tmp_path / "p.png")], capture_output=True,
                         text=True)
    assert bad.returncode == 2 and "not metres" in bad.stderr
    two = subprocess.run(base + [str(tmp_path / "two.exr"), "--depth", str(tmp_path / "ml.exr")],
                         capture_output=True, text=True)
    assert two.returncode == 2 and "Second.Combined" in two.stderr and "--image-pass" in two.stderr


# -- Blender's own file --------------------------------------------------------------------------------------------

RENDER = r'''
import sys, bpy
bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
scene.render.engine = 'CYCLES'
scene.cycles.samples = 2
scene.cycles.use_denoising = False
scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 32, 24, 100
cam = bpy.data.objects.new("cam", bpy.data.cameras.new("cam"))
scene.collection.objects.link(cam)
scene.camera = cam
cam.location, cam.rotation_euler = (0.0, -10.0, 0.0), (1.5708, 0.0, 0.0)
bpy.ops.mesh.primitive_uv_sphere_add(radius=2.0, location=(0.0, 0.0, 0.0))
lamp = bpy.data.objects.new("lamp", bpy.data.lights.new("lamp", 'POINT'))
lamp.data.energy = 1000.0
lamp.location = (3.0, -5.0, 3.0)
scene.collection.objects.link(lamp)
for vl in scene.view_layers:
    vl.use_pass_combined = True
    vl.use_pass_z = True
im = scene.render.image_settings
im.media_type = 'MULTI_LAYER_IMAGE'
im.file_format = 'OPEN_EXR_MULTILAYER'
im.color_depth = '32'
scene.render.filepath = sys.argv[1]
scene.render.use_file_extension = False
bpy.ops.render.render(write_still=True)
'''


def structure(path):
    return [(c.name, c.subimage, c.index, c.format) for c in imageio.channels(path)]


@pytest.mark.render
def test_blenders_own_multilayer_exr(tmp_path):
    """A 32x24 Cycles render (a sphere 8 m away, 2 samples) saved by Blender 5.0 as a multilayer EXR: its parts
    and channels are those ``write_layers`` writes for ``blender_layers``; fogging it (as IMAGE and DEPTH) gives
    the picture its Combined and its Z written on their own give, within 1 % (measured 0).  Read the old way (the
    depth from channel 0, Combined's red) the sphere's pixels were far off (measured: printed)."""
    raw = tmp_path / "blender.exr"
    proc = subprocess.run([sys.executable, "-c", RENDER, str(raw)], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0 and raw.is_file(), proc.stderr[-2000:]
    parts = imageio.read_layers(raw)   # (this process has not rendered)
    rgba, z = parts["ViewLayer.Combined"], parts["ViewLayer.Depth"][..., 0]
    imageio.write_layers(tmp_path / "ours.exr", blender_layers(rgba, z))
    assert structure(raw) == structure(tmp_path / "ours.exr")
    rgb_path, z_path = write_single(tmp_path, rgba, z)
    want, _ = fog(rgb_path, z_path, depth_kind="z")
    got, said = fog(raw, raw)
    assert max_rel(got, want) < 0.01, said
    sphere = z < 1e6
    assert sphere.sum() > 50
    old = weather.add_weather(rgba[..., :3], rgba[..., 0], VISIBILITY)
    off = np.abs(old - want)[sphere].sum() / want[sphere].sum()
    print(json.dumps({"multilayer vs single-channel, max rel": max_rel(got, want),
                      "channel-0 depth, sphere's light off by": round(float(off), 3)}))
    assert off > 0.3


def test_blenders_depth_pass_is_turned_into_ray_distance(tmp_path):
    """Blender's Depth pass is depth along the view axis; the fog needs distance along each pixel's ray.  Against
    an independent geometry (a plane facing the camera at z 10 m: distance = z / cos of the ray's angle to the
    axis, the angle from the pixel's offset and the field of view), and the run says it converted."""
    h, w, fov = 18, 32, 50.0
    z = np.full((h, w), 10.0)
    half = math.tan(math.radians(fov) / 2.0)
    x = (np.arange(w) + 0.5) / w * 2.0 - 1.0
    y = ((np.arange(h) + 0.5) - h / 2.0) / (w / 2.0)
    cos = 1.0 / np.sqrt(1.0 + (half * x[None, :]) ** 2 + (half * y[:, None]) ** 2)
    np.testing.assert_allclose(weather.ray_distance(z, fov), 10.0 / cos, rtol=1e-12)
    assert weather.ray_distance(np.full((2, 2), 1e10), fov).max() == 1e10, "the sky stays the sky"
    rgba = np.ones((h, w, 4), np.float32)
    imageio.write_layers(tmp_path / "ml.exr", blender_layers(rgba, z.astype(np.float32)))
    _, said = fog(tmp_path / "ml.exr", tmp_path / "ml.exr", fov_deg=fov)
    assert "turned into distance" in said
    _, said = fog(tmp_path / "ml.exr", tmp_path / "ml.exr", fov_deg=fov, depth_kind="distance")
    assert "turned into distance" not in said
