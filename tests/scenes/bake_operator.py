"""The bake operator without a window (scripts, ``-b``), with a cache of its own (argv[1]); prints BAKE_JSON.

The spheres demo with its point light and Dense Fog on: ``apply.missing_tables`` lists the point light's table
before, ``fog.bake_tables`` bakes it in line and syncs, the list is empty after, and the choice has Dense Fog;
``fog.add('INVOKE_DEFAULT')`` without a window runs as ``execute``.
"""
import json
import os
import pathlib
import sys

os.environ["ANALYTIC_FOG_CACHE"] = sys.argv[-1]
ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import bpy  # noqa: E402

import fog_addon  # noqa: E402
from demo_scenes import spheres  # noqa: E402
from fog_addon import props  # noqa: E402
from fog_addon.nodes import groups  # noqa: E402
from fog_addon.ops import apply  # noqa: E402
from fog_addon.precompute.model import bakers  # noqa: E402

bpy.ops.wm.read_factory_settings(use_empty=True)
fog_addon.register()
scene = bpy.context.scene
spheres.build(scene)
scene.render.engine = "CYCLES"
out = {"add": sorted(bpy.ops.fog.add("INVOKE_DEFAULT", density=0.05))}
fog = scene.analytic_fog
with props.quiet():
    fog.anisotropy = 0.35   # a g no other test bakes Dense Fog for
    fog.use_multiple_scattering = True
spec = apply.spec_of(scene)
out["before"] = [bakers.label(t) for t, _ in apply.missing_tables(scene, spec)]
out["bake"] = sorted(bpy.ops.fog.bake_tables(level="rechoose"))
out["after"] = [bakers.label(t) for t, _ in apply.missing_tables(scene, spec)]
choice = apply.stored_choice()
built = json.loads(bpy.data.node_groups[groups.SURFACE][apply.SPEC_KEY])
out["built"] = {"anisotropy": built["anisotropy"], "multiple_scattering": built["multiple_scattering"]}
out["steps"] = {name: step for name, (step, _) in choice["lights"].items()}
print("BAKE_JSON " + json.dumps(out))
