"""Open a saved state of the panel's property test (property_repro.py --save-before-render), change settings,
render 16 x 12 px at 1 sample in Cycles with its debug log on, and print each shader's peak SVM stack use.

    TMPDIR=/tmp/h3 .venv/bin/python benchmarks/shader_budgets/svm_variants.py FILE.blend [passes=0] [top=0]
        [spots=0] [points=0] [dense=1] [method=NODES]
"""
import json
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import bpy  # noqa: E402

import fog_addon  # noqa: E402
from fog_addon import measure  # noqa: E402
from fog_addon.ops import apply  # noqa: E402
from fog_scenes import cycles_debug_log  # noqa: E402

path, changes = sys.argv[1], dict(a.split("=", 1) for a in sys.argv[2:])
fog_addon.register()
bpy.ops.wm.open_mainfile(filepath=path, load_ui=False)
scene = bpy.context.scene
s = scene.analytic_fog
for kind, attr in (("spots", "SPOT"), ("points", "POINT")):
    if changes.get(kind) == "0":
        for o in [o for o in scene.collection.objects if o.type == "LIGHT" and o.data.type == attr]:
            scene.collection.objects.unlink(o)
if "passes" in changes:
    s.use_passes = changes["passes"] == "1"
if "top" in changes:
    s.use_fog_top = changes["top"] == "1"
if "dense" in changes:
    s.use_multiple_scattering = changes["dense"] == "1"
if "method" in changes:
    s.method = changes["method"]
if "quality" in changes:
    s.quality = changes["quality"]
if changes:
    bpy.ops.fog.add()
choice = apply.stored_choice() or {}
print("STATE " + json.dumps({"method": choice.get("method"), "passes": s.use_passes, "top": s.use_fog_top,
                             "dense": s.use_multiple_scattering, "g": s.anisotropy,
                             "lights": sorted((o.data.type, choice.get("lights", {}).get(o.name, [None])[0])
                                              for o in scene.objects if o.type == "LIGHT")}), flush=True)
measure.set_resolution(scene, 16, 12)
scene.cycles.samples = 1
scene.render.use_compositing = False
print("debug", cycles_debug_log.enable(), flush=True)
print("RENDER_START", flush=True)
measure.render_to_file(scene, pathlib.Path(bpy.app.tempdir) / "variant.exr")
