"""The viewport's preview of the Compositor's fog (``nodes/preview.py``, ``ops/plan.preview_models``).

* ``render --viewport`` (what the rendered viewport shows) is the Node Groups method's picture where the preview
  holds every light (the spheres: three lamps in its budget), and it differs from the render without the preview
  (the glows are there);
* a final render is bit for bit the render of the same scene built without a preview (the preview's closures sit
  behind a Mix Shader of factor 0: Cycles' SVM jumps over them);
* a scene with more lights than the preview's budget samples the other point lights (the boulevard's 45 lamps
  against path tracing) and names the spot and area lights it leaves out;
* the preview against path tracing where shadows cut the fog (its shafts).
"""
import re

import numpy as np
import pytest

from fog_addon import compare, imageio
from fog_scenes import render_harness as h

pytestmark = pytest.mark.render

FLAGS = ["--density", "0.15", "--resolution", "48x27", "--pixel-centre", "--samples", "4",
         "--no-interreflection", "--no-cast-shadows"]


# the street lamps' preview against its Node Groups render, both 256 spp: 3.0 % (mean ratio 1.0006; 0.26 with the
# sampled lamps' Dense Fog left out, mutation preview_sampled_no_dense)
THREE_LAMPS_NOISE = 0.045
ENGINES = ["cycles", "eevee"]   # EEVEE: its materials share the uniform block with the lights they dim


def _render(blend, out, engine, *flags):
    r = h.run(["-m", "fog_addon", "render", blend, "--engine", engine, *FLAGS, *flags, "--out", out], check=False)
    assert r.returncode == 0, (r.stdout + r.stderr)[-2000:]
    return imageio.read_rgb(out).astype(np.float64), r.stdout


@pytest.mark.parametrize("engine", ["cycles", pytest.param("eevee", marks=pytest.mark.slow(
    reason="EEVEE's preview is built and rendered in the default tier by test_final_renders_are_those_without_the_"
           "preview and test_eevee_preview_says_it_has_no_shafts"))])
def test_viewport_shows_the_node_groups_fog(tmp_path, engine):
    """Two lamps (the budget's two): the preview models both on every sample, the Node Groups' picture."""
    blend = h.scene_blend("glossy_lamps", tmp_path)
    view, said = _render(blend, tmp_path / "view.exr", engine, "--method", "compositor", "--viewport")
    nodes, _ = _render(blend, tmp_path / "nodes.exr", engine, "--method", "nodes")
    final, _ = _render(blend, tmp_path / "final.exr", engine, "--method", "compositor")
    bare, _ = _render(blend, tmp_path / "bare.exr", engine, "--method", "compositor", "--viewport", "--density",
                      "1e-9")
    assert np.isfinite(view).all()
    assert compare.metrics(view, nodes)["rel_rmse"] < 1e-4, compare.metrics(view, nodes)
    assert compare.metrics(view, final)["rel_rmse"] < 0.01   # the compositor's own fog: the same models per pixel
    assert compare.metrics(view, bare)["rel_rmse"] > 0.1      # the fog's light is there


def test_viewport_samples_three_lamps_without_bias(tmp_path):
    """Three lamps, more than the budget's two: Cycles' preview samples all three, one a sample by its tile's guess
    (``preview_sampled``); over 256 samples its picture is the Node Groups' within the draws' noise."""
    blend = h.scene_blend("street_lamps", tmp_path)
    flags = ["--samples", "256"]
    view, said = _render(blend, tmp_path / "view.exr", "cycles", "--method", "compositor", "--viewport", *flags)
    nodes, _ = _render(blend, tmp_path / "nodes.exr", "cycles", "--method", "nodes", *flags)
    assert "preview samples 3 of the 3 lights" in said, said[-2000:]
    m = compare.metrics(view, nodes)
    assert m["rel_rmse"] < THREE_LAMPS_NOISE and abs(m["mean_ratio"] - 1.0) < 0.01, m


FLOW = r"""
import json, os, sys
import numpy as np
import bpy
import fog_addon
from fog_addon import measure, methods
from fog_addon.methods import compositor
from fog_addon.ops import apply
from fog_addon.precompute.core.spec import FogSpec
bpy.ops.wm.open_mainfile(filepath=BLEND)
scene = bpy.context.scene
scene.render.engine = ENGINE
measure.set_samples(scene, 4)
scene.render.resolution_x, scene.render.resolution_y = SIZE
measure.set_pixel_centre_filter(scene)
fog_addon.register()
spec = SPEC
def previewed():
    return bool(bpy.data.node_groups[GROUP].nodes.get("Viewport Preview"))
apply.apply(scene, spec)
with_preview = previewed()
measure.render_to_file(scene, os.path.join(os.getcwd(), "a.exr"))
WITHOUT   # the same scene built without a preview
apply.remove_fog(scene)
apply.apply(scene, spec)
without = previewed()
measure.render_to_file(scene, os.path.join(os.getcwd(), "b.exr"))
print(json.dumps({"with": with_preview, "without": without}))
"""


def _final_against_unpreviewed(tmp_path, engine, blend, spec, without, group="AnalyticFog Surface", size=(48, 27)):
    """Render ``blend`` built by ``spec`` (a FogSpec expression) with its preview and built without it (``without``:
    the line that keeps the preview out); both final renders, bit for bit the same."""
    code = FLOW
    for key, value in (("BLEND", repr(str(blend))), ("ENGINE", repr({"cycles": "CYCLES", "eevee": "BLENDER_EEVEE"}[engine])),
                       ("SIZE", repr(size)), ("SPEC", spec), ("WITHOUT", without), ("GROUP", repr(group))):
        code = code.replace(key, value)
    out = h.bpy_flow(code, tmp_path)
    assert out == {"with": True, "without": False}, out
    a, b = (imageio.read_rgb(tmp_path / f"{k}.exr") for k in ("a", "b"))
    assert np.array_equal(a, b), float(np.abs(a - b).max())


@pytest.mark.parametrize("engine", [pytest.param("cycles", marks=pytest.mark.slow(
    reason="Cycles' final render against the unpreviewed one: test_daylight_final_renders_are_those_without_the_"
           "preview in the default tier")), "eevee"])
def test_final_renders_are_those_without_the_preview(tmp_path, engine):
    _final_against_unpreviewed(tmp_path, engine, h.scene_blend("spheres", tmp_path),
                               'FogSpec(density=0.15, method="compositor")',
                               'methods.get("compositor").preview_budget = lambda *a: None')


# The preview against Cycles' path tracing with cast shadows (fog_scenes/shafts.py: issue 27's scenes and their
# references), 128 x 72, 16 spp, the shaft tests' lamp mask.  The issue's goals: 15 % on scenes with shadows, 10 % on
# a street.  Measured (2026-11-30, docs/measurements/2026-11-29-viewport-preview.md): window room 6.3 % (180 %
# without the preview's shafts), colonnade 1.35 % (19 %), street lamps 7.7 % (its three lamps sampled one a sample,
# without shafts: noise at 16 spp; 4.5 % at 64, 3.1 % at 256; 4.2 % when two were modelled with their shafts); the
# bounds add a margin.  The softbox colonnade (an area light's shafts, 2026-12-01): 3.09 % (14.9 % without them).
PREVIEW_BOUND = {"window_room": 0.09, "colonnade": 0.025, "street_lamps": 0.09, "softbox_colonnade": 0.04}
PREVIEW_GOAL = {"window_room": 0.15, "colonnade": 0.15, "street_lamps": 0.10, "softbox_colonnade": 0.15}


@pytest.mark.parametrize("scene,density", [("window_room", 0.1),
                                           pytest.param("colonnade", 0.08, marks=pytest.mark.slow),
                                           pytest.param("softbox_colonnade", 0.08, marks=pytest.mark.slow),
                                           pytest.param("street_lamps", 0.08, marks=pytest.mark.slow)])
def test_viewport_against_path_tracing(tmp_path, scene, density):
    from fog_scenes import shafts as fs   # noqa: PLC0415 (the shaft scenes' references)
    ref = fs.ensure_shaft_reference(scene, density)
    log = []
    out = h.render_test(scene, density, tmp_path / f"{scene}.exr", engine="cycles", method="compositor", samples=16,
                        resolution=fs.SHAFT_RESOLUTION, cast_shadows=True, log=log, extra=["--shafts", "on",
                                                                                            "--viewport"])
    assert not h.log_errors(log[0]), h.log_errors(log[0])   # (out of SVM stack space: a material black)
    m = h.assert_close(out, ref, name=f"viewport_{scene}", rel_rmse=PREVIEW_BOUND[scene],
                       mask=fs.lamp_pixel_mask(scene, fs.SHAFT_RESOLUTION))
    print(f"{scene}: relative RMSE {m['rel_rmse']:.4f} (bound {PREVIEW_BOUND[scene]}, goal {PREVIEW_GOAL[scene]})")
    assert PREVIEW_BOUND[scene] <= PREVIEW_GOAL[scene]


def test_eevee_preview_says_it_has_no_shafts(tmp_path):
    """EEVEE's preview has no shafts (its uniform block would hold the shares' constants): the notes name the lights."""
    blend = h.scene_blend("street_lamps", tmp_path)
    r = h.run(["-m", "fog_addon", "render", blend, "--engine", "eevee", "--density", "0.08", "--resolution", "32x18",
               "--samples", "1", "--method", "compositor", "--shafts", "on", "--viewport",
               "--out", tmp_path / "e.exr"], check=False)
    assert r.returncode == 0, (r.stdout + r.stderr)[-2000:]
    assert re.search(r"preview shows no light shafts of Lamp \d, Lamp \d in EEVEE", r.stdout), r.stdout[-2000:]


# The boulevard (45 lamps, no shadows; the render tests' reference, 64 x 36): the preview samples all 45, one a
# sample, each pixel by its tile's guess of the lamps' glows (nodes/preview_sampled.py).  Measured (2026-11-30):
# 3.0 % at 256 spp, 6.8 % at 64 (two lamps modelled and 43 drawn by the whole picture's importance: 6.0 %, 11.2 %;
# 35.8 % before the sampling); the tiles mirrored top to bottom (mutation preview_tiles_flipped) 4.8 % at 256.  The
# issue's goal: 10 % on a street of 25 lamps, at the viewport's samples (Cycles' default: 1024).
BOULEVARD_SAMPLES = 256
BOULEVARD_BOUND = 0.04


@pytest.mark.slow
def test_viewport_samples_the_other_lamps_of_a_boulevard(tmp_path):
    ref = h.ensure_reference("boulevard", 0.015)
    log = []
    out = h.render_test("boulevard", 0.015, tmp_path / "boulevard.exr", engine="cycles", method="compositor",
                        samples=BOULEVARD_SAMPLES, log=log, extra=["--viewport"])
    assert not h.log_errors(log[0]), h.log_errors(log[0])
    assert "preview samples 45 of the 45 lights" in log[0], log[0][-3000:]
    m = h.assert_close(out, ref, name="viewport_boulevard", rel_rmse=BOULEVARD_BOUND, mean_ratio_tol=0.04)
    print(f"boulevard: relative RMSE {m['rel_rmse']:.4f}, mean ratio {m['mean_ratio']:.4f}")


@pytest.mark.slow(reason="25 s cold; the default tier names what the preview leaves out in "
                         "test_preview_names_what_it_leaves_out_of_a_layer_and_glowing_objects")
def test_preview_names_the_spots_it_leaves_out(tmp_path):
    """The concert stage's three spots: the preview models two, the third is not sampled (a point's glow is not a
    spot's) and the notes name it."""
    blend = h.scene_blend("concert_stage", tmp_path)
    r = h.run(["-m", "fog_addon", "render", blend, "--engine", "cycles", "--density", "0.04", "--resolution",
               "32x18", "--samples", "1", "--method", "compositor", "--viewport", "--out", tmp_path / "c.exr"],
              check=False)
    assert r.returncode == 0, (r.stdout + r.stderr)[-2000:]
    assert "preview of the fog leaves out 1 of the 3 lights" in r.stdout, r.stdout[-2000:]
    share = re.search(r"preview of the fog leaves out 1 of the 3 lights .*, up to ([0-9]+)% of a pixel's fog "
                      r"\(predicted", r.stdout)
    assert share and int(share.group(1)) > 0, r.stdout[-2000:]   # (its share, from the preview's prediction)


NOTES_FLOW = r"""
import json
import bpy
import fog_addon
from fog_addon.ops import apply
from fog_addon.precompute.core.spec import FogSpec
bpy.ops.wm.open_mainfile(filepath=BLEND)
scene = bpy.context.scene
scene.render.engine = "CYCLES"
mat = bpy.data.materials.new("Neon")
nt = mat.node_tree
nt.nodes.clear()
emit, out = nt.nodes.new("ShaderNodeEmission"), nt.nodes.new("ShaderNodeOutputMaterial")
emit.inputs["Strength"].default_value = 20.0
nt.links.new(emit.outputs[0], out.inputs["Surface"])
bpy.ops.mesh.primitive_cube_add(size=0.3, location=(0.0, 4.0, 0.5))
bpy.context.active_object.name = "Neon Sign"
bpy.context.active_object.data.materials.append(mat)
fog_addon.register()
notes = apply.apply(scene, FogSpec(density=0.15, method="compositor", fog_top=3.0))
print(json.dumps([why for _, why in notes]))
"""


def test_preview_names_what_it_leaves_out_of_a_layer_and_glowing_objects(tmp_path):
    """The preview shows glowing objects' glows from points along each, without their shadows (the compositor's
    follow their shapes), and its lamps glow above a layer's top: the notes say both."""
    blend = h.scene_blend("spheres", tmp_path)
    notes = h.bpy_flow(NOTES_FLOW.replace("BLEND", repr(str(blend))), tmp_path)
    assert any("preview shows the glows of the glowing objects (Neon Sign) from points along each" in n
               for n in notes), notes
    assert any("preview takes the lamps' glows through the fog layer" in n for n in notes), notes


SAMPLED_FLOW = r"""
import json, os, sys, time
import numpy as np
import bpy
import fog_addon
from fog_addon.nodes import preview_sampled
from fog_addon.ops import apply
from fog_addon.precompute.core.spec import FogSpec
bpy.ops.wm.open_mainfile(filepath=BLEND)
scene = bpy.context.scene
fog_addon.register()
apply.apply(scene, FogSpec(density=0.015, method="compositor", shafts=False))   # (no shadow maps to bake)
img = bpy.data.images[preview_sampled.TABLE]
def rows():
    px = np.empty(len(img.pixels), np.float32); img.pixels.foreach_get(px)
    return px.reshape(img.size[1], img.size[0], 4)
before = rows()
lamp = next(o for o in scene.objects if o.type == "LIGHT" and any(
    np.allclose(before[0, j, :3], tuple(o.matrix_world.translation), atol=1e-4) for j in range(img.size[0])))
lamp.location.x += 1.0
lamp.data.energy *= 2.0
bpy.context.view_layer.update()
t = time.perf_counter()
apply.refresh_lights(scene, this_frame=True)   # what the depsgraph handler calls
took = time.perf_counter() - t
after = rows()
moved = [j for j in range(img.size[0]) if np.allclose(after[0, j, :3], tuple(lamp.matrix_world.translation), atol=1e-4)]
bpy.ops.wm.save_as_mainfile(filepath=os.path.join(os.getcwd(), "saved.blend"))
packed = bpy.data.images[preview_sampled.TABLE].packed_file is not None
apply.remove_fog(scene)
print(json.dumps({"moved": len(moved), "changed": bool(not np.array_equal(before, after)), "seconds": took,
                  "packed": packed, "removed": preview_sampled.TABLE not in bpy.data.images,
                  "groups_left": [g.name for g in bpy.data.node_groups if "Preview" in g.name]}))
"""


def test_sampled_lights_follow_the_scene(tmp_path):
    """A sampled lamp moved and brightened reaches the table at the handlers' refresh (the boulevard's 43 sampled
    lamps); the saved file keeps the table; removing the fog removes it and the preview's groups."""
    blend = h.scene_blend("boulevard", tmp_path)
    out = h.bpy_flow(SAMPLED_FLOW.replace("BLEND", repr(str(blend))), tmp_path)
    assert out["moved"] == 1 and out["changed"], out
    assert out["packed"] and out["removed"] and out["groups_left"] == [], out
    print(f"the refresh took {out['seconds']:.3f} s")


# A fog layer's sun and sky in the preview (the compositor adds them at render time): the city of
# fog_scenes/daylight.py (case hard_g0_inside, 160 x 90, Cycles 16 spp) against its path-traced reference.  Measured
# (2026-11-29, docs/measurements/2026-11-29-viewport-preview.md): Cycles 1.55 % (222 % before: the sky undimmed,
# no sun's glow), the node groups' own figure; EEVEE 4.6 % (212 % before), its final render 4.3 %.
DAY_BOUND = {"cycles": 0.03, "eevee": 0.06}   # test_daylight_render.py's goals for the final renders


@pytest.mark.parametrize("engine", ["cycles", pytest.param("eevee", marks=pytest.mark.slow)])
def test_viewport_shows_the_daylight(tmp_path, engine):
    from fog_scenes import daylight as dl
    case = dl.as_case("hard_g0_inside")
    blend = tmp_path / "city.blend"
    dl.build_scene(str(blend), case, with_fog=False)
    log = []
    out = h.render_test("daylight", dl.layer(case)["beta0"], tmp_path / "view.exr", engine=engine,
                        method="compositor", resolution=dl.RESOLUTION, blend=str(blend), log=log,
                        samples=16 if engine == "cycles" else None, extra=dl.fog_flags(case) + ("--viewport",))
    assert not h.log_errors(log[0]), h.log_errors(log[0])
    m = h.assert_close(out, dl.render_reference(case, samples=1024, seeds=2), name=f"daylight_viewport_{engine}",
                       rel_rmse=DAY_BOUND[engine])
    assert abs(m["mean_ratio"] - 1.0) < DAY_BOUND[engine], m


@pytest.mark.parametrize("engine", ["cycles", pytest.param("eevee", marks=pytest.mark.slow)])
def test_daylight_final_renders_are_those_without_the_preview(tmp_path, engine):
    """The daylight's preview takes the surfaces' and the World's factors through ``preview.blend``: at a Viewport
    Preview of 0 Cycles folds it away when it compiles, EEVEE computes x + 0 x (...): the final render is bit for bit
    the one built without a preview."""
    from fog_scenes import daylight as dl
    case = dl.as_case("hard_g0_inside")
    blend = tmp_path / "city.blend"
    dl.build_scene(str(blend), case, with_fog=False)
    f = dl.layer(case)
    _final_against_unpreviewed(tmp_path, engine, blend,
                               f'FogSpec(density={f["beta0"]!r}, method="compositor", fog_top={f["h0"]!r})',
                               "compositor._preview = lambda *a, **k: (None, {})", group="AnalyticFog World",
                               size=(64, 36))


GLOWING_BOUND = 0.08   # measured 5.4 % (the preview at 128 spp, the reference at 1024: their noise), mean ratio 0.994


def test_viewport_glows_a_glowing_object(tmp_path):
    """A glowing sphere beside a lamp, nothing else (tests/scenes/glowing_preview.py): the viewport's preview of the
    Compositor's fog (the sphere a point source of intensity L pi R^2 at its centre, sampled with the lights:
    ``methods.compositor.sampled_points``) against Cycles' path-traced single scattering, the sphere's own pixels
    left out.  Without it the preview had the lamp's glow alone."""
    scene = h.ROOT / "tests" / "scenes" / "glowing_preview.py"
    ref, out = tmp_path / "reference.exr", tmp_path / "preview.exr"
    h.run([scene, "reference", ref, 1024])
    h.run([scene, "preview", out, 128])
    b = imageio.read_rgb(ref)
    rows, cols = b.shape[:2]
    yy, xx = np.mgrid[0:rows, 0:cols]
    off_sphere = np.hypot(xx + 0.5 - cols / 2, yy + 0.5 - rows / 2) > 4
    m = h.assert_close(out, ref, name="viewport_glowing_sphere", rel_rmse=GLOWING_BOUND, mean_ratio_tol=0.03,
                       mask=off_sphere)
    print(f"glowing sphere: relative RMSE {m['rel_rmse']:.4f}, mean ratio {m['mean_ratio']:.4f}")
