"""The predictor's denominator holds the sources the ladder does not step (``left_out.with_other``): a glowing
object's glow and fog light, where the method glows it (the Compositor), as a point source of its emission's
radiance L times its mean projected area (a quarter of its surface: Cauchy).

Blender: the glowing sphere of ``fog_scenes/glowing_sphere.py`` (radius R, radiance L, white Emission): its
intensity is exactly L pi R^2 in every direction (a Lambertian sphere), so the sampled fog must be a point lamp's of
that intensity at the sphere's centre (``predict.light_fog``), within the UV sphere's area (its facets: under 2 %);
with the Node Groups (no glow of glowing objects) it is not in the denominator.  The daylight's part:
tests/test_predict.py (numpy, against quadrature) and the slow ``daylit`` cases of tests/test_quality.py.
"""
import json

import pytest

from fog_scenes import render_harness as h

pytestmark = pytest.mark.render

# the glowing sphere's scene, emptied and built again (``sys.argv[1]``: the repository)
_SPHERE = r'''
import sys, json, math, bpy
import numpy as np
sys.path.insert(0, sys.argv[1])
from fog_scenes import glowing_sphere as gs
from fog_addon import view
from fog_addon.nodes import graph
from fog_addon.ops import left_out
from fog_addon.precompute.core.spec import FogSpec
from fog_addon.precompute.model import predict
scene = bpy.context.scene
for o in list(scene.objects):
    bpy.data.objects.remove(o)
'''

_CODE = _SPHERE + r'''
gs.build(scene, resolution=(32, 32))
spec = FogSpec(density=0.1)
seen = view.view_samples(scene, [], grid=(32, 32))
got = left_out.with_other(scene, spec, seen, "compositor").other
none = left_out.with_other(scene, spec, seen, "nodes").other
at = seen._replace(lights=np.zeros((len(seen.distance), 1, 3)))
glow, scatter = predict.light_fog(at, np.full((1, 3), gs.RADIANCE * math.pi * gs.RADIUS_M ** 2), 0.1, 0.0)
want = (glow + scatter).sum(axis=1)
print("SOURCES " + json.dumps({"ratio": [float(np.min(got / want)), float(np.max(got / want))],
                               "none": none is None}))
'''


def test_a_glowing_objects_fog_is_in_the_compositors_denominator():
    proc = h.run_bpy_code(_CODE, h.ROOT)
    got = json.loads(next(ln for ln in proc.stdout.splitlines() if ln.startswith("SOURCES "))[8:])
    print(got)
    assert got["none"], "the Node Groups glow no glowing object: nothing of it in their denominator"
    assert 0.99 < got["ratio"][0] <= got["ratio"][1] < 1.0, got   # (a UV sphere's facets: a little less area)


_TEXTURED = _SPHERE + r'''
gs.build(scene, resolution=(16, 16))
mat = next(m for m in bpy.data.materials if m.node_tree and any(n.bl_idname == "ShaderNodeEmission"
                                                                  for n in m.node_tree.nodes))
nt = mat.node_tree
em = next(n for n in nt.nodes if n.bl_idname == "ShaderNodeEmission")
tex = nt.nodes.new("ShaderNodeTexImage")
nt.links.new(tex.outputs["Color"], em.inputs["Color"])
out = {}
# a float image of 512 x 512, its left half (2, 0, 0) and its right half (0, 0, 1): mean (1, 0, 0.5)
img = bpy.data.images.new("Halves", 512, 512, float_buffer=True)
px = np.zeros((512, 512, 4), np.float32); px[..., 3] = 1.0
px[:, :256, 0] = 2.0; px[:, 256:, 2] = 1.0
img.pixels.foreach_set(px.ravel())
tex.image = img
out["float"] = graph.emitted_radiance(mat)
seen = view.view_samples(scene, [], grid=(16, 16))
out["other"] = left_out.with_other(scene, FogSpec(density=0.1), seen, "compositor").other is not None
# an 8-bit sRGB image of 8 x 8, stored 0.5 and 1.0 in halves (grey)
img8 = bpy.data.images.new("Bytes", 8, 8, float_buffer=False)
px = np.ones((8, 8, 4), np.float32); px[:, :4, :3] = 0.5
img8.pixels.foreach_set(px.ravel())
tex.image = img8
out["bytes"] = graph.emitted_radiance(mat)
out["stored"] = float(np.array(img8.pixels[:4])[0])
# a procedural texture: not a plain value
noise = nt.nodes.new("ShaderNodeTexNoise")
nt.links.new(noise.outputs["Color"], em.inputs["Color"])
out["noise"] = graph.emitted_radiance(mat)
out["strength"] = em.inputs["Strength"].default_value
print("TEXTURED " + json.dumps(out))
'''


def test_a_textured_emission_shines_with_its_images_mean():
    """An Image Texture's colour counts as the image's mean (``graph.image_mean``): a float image of two halves,
    (2, 0, 0) and (0, 0, 1), 512 a side, gives (1, 0, 0.5) x the strength; an 8-bit sRGB image of
    halves stored 0.5 and 1.0 gives the mean of their linear values (the sRGB curve written out here); the glowing
    object is then in the Compositor's denominator.  A procedural texture stays unread (None: judged without it)."""
    proc = h.run_bpy_code(_TEXTURED, h.ROOT)
    got = json.loads(next(ln for ln in proc.stdout.splitlines() if ln.startswith("TEXTURED "))[9:])
    s = got["strength"]
    assert got["float"] == pytest.approx([s * 1.0, 0.0, s * 0.5], rel=1e-5, abs=1e-6), got
    stored = got["stored"]   # the byte nearest 0.5 (128 / 255)
    linear = ((stored + 0.055) / 1.055) ** 2.4
    assert got["bytes"] == pytest.approx([s * (linear + 1.0) / 2.0] * 3, rel=1e-4), got
    assert got["other"], "the textured sphere's fog is in the Compositor's denominator"
    assert got["noise"] is None, got
