"""The switch of the viewport's preview (``nodes/preview.py``): 1 while an artist works, 0 in every final render
and every saved file, 1 through a render ``forced`` (``render --viewport``).  The value is read from inside the
renders (a render_pre handler appended after the add-on's), and from the saved file opened again."""
import pytest

from fog_scenes import render_harness as h

pytestmark = pytest.mark.render

FLOW = r"""
import json, os
import bpy
import fog_addon
from fog_addon.nodes import preview
from fog_addon.ops import apply
from fog_addon.precompute.core.spec import FogSpec
bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
scene.render.engine = "CYCLES"; scene.cycles.samples = 1
scene.render.resolution_x, scene.render.resolution_y = 8, 6
cam = bpy.data.objects.new("Cam", bpy.data.cameras.new("Cam")); scene.collection.objects.link(cam); scene.camera = cam
lamp = bpy.data.objects.new("Lamp", bpy.data.lights.new("Lamp", "POINT")); scene.collection.objects.link(lamp)
lamp.location = (0, 5, 0)
fog_addon.register()
out = {"background": preview.value()}
apply.apply(scene, FogSpec(density=0.1))
out["built in background"] = preview.value()
preview._session = lambda: True          # as in an artist's session (Blender with a window)
preview.after_render()                    # (what opening a file does)
out["session"] = preview.value()
seen = []
bpy.app.handlers.render_pre.append(lambda *_: seen.append(preview.value()))
scene.render.filepath = os.path.join(os.getcwd(), "r.png")
bpy.ops.render.render(write_still=True)
out["in F12"], out["after F12"] = seen[-1], preview.value()
with preview.forced():
    bpy.ops.render.render(write_still=True)
    out["in forced"] = seen[-1]
out["after forced"] = preview.value()
path = os.path.join(os.getcwd(), "f.blend")
bpy.ops.wm.save_as_mainfile(filepath=path)
out["after save"] = preview.value()
bpy.ops.wm.open_mainfile(filepath=path, load_ui=False)
out["session after open"] = preview.value()   # (load_post shows it again in a session)
fog_addon.unregister()                         # as a farm opens it: without the add-on
bpy.ops.wm.open_mainfile(filepath=path, load_ui=False)
out["in the file"] = bpy.data.node_groups["AnalyticFog Params"].nodes["Viewport Preview"].outputs[0].default_value
print(json.dumps(out))
"""


def test_the_preview_is_off_in_final_renders_and_saved_files(tmp_path):
    out = h.bpy_flow(FLOW, tmp_path)
    assert out["background"] is None and out["built in background"] == 0.0, out   # nobody sees a background viewport
    assert out["session"] == 1.0, out
    assert out["in F12"] == 0.0 and out["after F12"] == 1.0, out
    assert out["in forced"] == 1.0 and out["after forced"] == 1.0, out
    assert out["after save"] == 1.0 and out["session after open"] == 1.0, out
    assert out["in the file"] == 0.0, out   # a farm renders no preview
