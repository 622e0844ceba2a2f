"""The predictor sees past glass where the method shades the fog there (``view._first_opaque``,
``left_out.sees_past_glass``): the shop window of tests/scenes/shop_window.py (a Principled glass pane in a
window, a lamp in the shop behind it).

* Each view sample through the pane reaches the first opaque surface behind it: its distance is the one Blender's
  own ``Scene.ray_cast`` gives with the pane hidden (to 1e-4 m), and without ``past_glass`` the pane's own, as
  ``Scene.ray_cast`` gives with the pane there;
* the methods that shade the fog past glass in Cycles see past it (the Node Groups, the Compositor), OSL and every
  method in EEVEE not (``capabilities``' "glass" row: they show the fog in front of the pane only);
* a glass shader left in the pane's material but not connected to its output is no glass: samples stop at the
  pane, whose albedo is the connected (red) Principled BSDF's;
* the shop lamp's predicted fog at the pane's samples takes the shop's segment behind the pane (more than the
  street's segment alone), so the Quality judges the lamp by the glow the render shows through the pane.
"""
import json

import pytest

from fog_scenes import render_harness as h

pytestmark = pytest.mark.render

_CODE = r'''
import sys, json, math, bpy
import numpy as np
sys.path.insert(0, sys.argv[1]); sys.path.insert(0, sys.argv[1] + "/tests/scenes")
import shop_window as sw
from mathutils import Vector
from fog_addon import view
from fog_addon.ops import left_out
from fog_addon.precompute.model import predict
scene, cam = sw.build()
bpy.context.view_layer.update()
lights = [o for o in scene.objects if o.type == "LIGHT"]
grid = (48, 27)
past = view.view_samples(scene, lights, grid=grid, past_glass=True)
first = view.view_samples(scene, lights, grid=grid, past_glass=False)
def blender_hit(o, d):
    hit, loc, _n, _i, ob, _m = scene.ray_cast(bpy.context.evaluated_depsgraph_get(), Vector(o), Vector(d))
    return (ob.name if hit else None), ((loc - Vector(o)).length if hit else math.inf)
def hits(samples):
    return [blender_hit(o, d) for o, d in zip(samples.camera, samples.direction)]
def err(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(np.max(np.where(np.isfinite(a), np.abs(a - b), 0.0), initial=0.0))
first_hits, past_hits = hits(first), hits(past)
pane_first = np.array([n == "Pane" for n, _ in first_hits])
pane_past = np.array([n == "Pane" for n, _ in past_hits])
first_err = err([t for _, t in first_hits], first.distance)
elsewhere_err = err(np.where(pane_past, np.inf, [t for _, t in past_hits]), past.distance)
scene.objects["Pane"].hide_viewport = True
bpy.context.view_layer.update()
behind = np.array([blender_hit(o, d)[1] for o, d in zip(past.camera, past.direction)])
scene.objects["Pane"].hide_viewport = False
bpy.context.view_layer.update()
past_err = err(behind[pane_past], past.distance[pane_past])
power = view.light_intensities(lights)
shop = int(np.argmax([o.location.y for o in lights]))
g_past = float(np.median(sum(predict.light_fog(past, power, sw.BETA, 0.0))[pane_past, shop]))
g_first = float(np.median(sum(predict.light_fog(first, power, sw.BETA, 0.0))[pane_first, shop]))
same_elsewhere = elsewhere_err < 1e-4
# the pane's glass left in its tree, a red opaque Principled BSDF connected to the output instead: an opaque pane
tree = scene.objects["Pane"].active_material.node_tree
surface = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial").inputs["Surface"]
red = tree.nodes.new("ShaderNodeBsdfPrincipled")
red.inputs["Base Color"].default_value = (1.0, 0.0, 0.0, 1.0)
tree.links.new(red.outputs[0], surface)
loose = view.view_samples(scene, lights, grid=grid, past_glass=True)
loose_err = err(first.distance, loose.distance)
loose_albedo = np.asarray(loose.rho_d)[pane_first].mean(axis=0).tolist()
sees = {}
for engine in ("CYCLES", "BLENDER_EEVEE"):
    scene.render.engine = engine
    sees[engine] = {m: left_out.sees_past_glass(scene, m) for m in ("nodes", "osl", "compositor")}
print("GLASS " + json.dumps({"pane": int(pane_first.sum()), "first_err": float(first_err), "past_err": past_err,
                             "same_elsewhere": same_elsewhere, "gain": g_past / g_first, "loose_err": loose_err,
                             "loose_albedo": loose_albedo,
                             "sees": sees}))
'''


def test_the_predictor_sees_past_glass():
    proc = h.run_bpy_code(_CODE, h.ROOT)
    got = json.loads(next(ln for ln in proc.stdout.splitlines() if ln.startswith("GLASS "))[6:])
    print(got)
    assert got["pane"] > 50, "the pane fills part of the view"
    assert got["first_err"] < 1e-4 and got["past_err"] < 1e-4, got
    assert got["same_elsewhere"], "samples that meet no glass are as before"
    assert got["gain"] > 1.5, "the shop lamp's fog past the pane counts"
    assert got["loose_err"] < 1e-4, "a glass shader not connected to the output is no glass: samples stop at the pane"
    r, g, b = got["loose_albedo"]
    assert r > 0.5 and g < 0.05 and b < 0.05, ("the pane's albedo is the connected red BSDF's", got["loose_albedo"])
    assert got["sees"] == {"CYCLES": {"nodes": True, "osl": False, "compositor": True},
                           "BLENDER_EEVEE": {"nodes": False, "osl": False, "compositor": False}}, got["sees"]
