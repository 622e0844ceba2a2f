"""The fog's drivers pass their values through unchanged (``drivers._new_driver``).

Blender 5.0's ``driver_add`` gives a driver's F-Curve two keyframes, (0, 0) and (1, 1), through which its result is
mapped, and their evaluation snaps values within 1e-4 of a key: a haze's density of 9.78e-5 /m (a visibility of
40 km) reached the Compositor method's fog group as 0, and 0.99995 as 1.  Checked in a Blender process: a value
driven through ``drivers.drive_expression`` and a location through ``drivers.drive_location``, in the scene's
compositor group (which the depsgraph evaluates), against the values they read.
"""
import json
import os
import subprocess

import pytest

from fog_scenes import render_harness as h

pytestmark = pytest.mark.render   # starts Blender (bpy) in a subprocess

_CODE = r"""
import json
import bpy
from fog_addon.nodes import drivers
bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
src = bpy.data.node_groups.new("Source", "ShaderNodeTree")
value = src.nodes.new("ShaderNodeValue")
value.name = "V"
ob = bpy.data.objects.new("Target", None)
scene.collection.objects.link(ob)
tree = bpy.data.node_groups.new("Driven", "CompositorNodeTree")
driven = tree.nodes.new("ShaderNodeValue")
drivers.drive_expression(driven.outputs[0], "b", [("b", src, 'nodes["V"].outputs[0].default_value')])
loc = tree.nodes.new("ShaderNodeCombineXYZ")
drivers.drive_location(loc, ob)
scene.compositing_node_group = tree
out = []
for v in (9.78e-5, 5e-5, 0.99995, 0.3, 1.0e-7, 250.0):
    value.outputs[0].default_value = v
    ob.location = (v, -v, 2.0 * v)
    scene.frame_set(scene.frame_current + 1)
    out.append([v, driven.outputs[0].default_value, [loc.inputs[i].default_value for i in range(3)]])
print("RESULT " + json.dumps(out))
"""


def test_driven_values_pass_through(tmp_path):
    env = dict(os.environ, TMPDIR=str(tmp_path))
    r = subprocess.run([h.PYTHON, "-c", _CODE], capture_output=True, text=True, timeout=300, cwd=h.ROOT, env=env)
    line = next((l for l in r.stdout.splitlines() if l.startswith("RESULT ")), None)
    assert line, r.stdout[-2000:] + r.stderr[-2000:]
    for v, got, (x, y, z) in json.loads(line[7:]):
        assert got == pytest.approx(v, rel=1e-6), (v, got)
        assert (x, y, z) == pytest.approx((v, -v, 2.0 * v), rel=1e-6), (v, x, y, z)
