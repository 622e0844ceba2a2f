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

_CODE = r'''
import sys, json, math, bpy
import numpy as np
sys.path.insert(0, sys.argv[1])
from fog_scenes import glowing_sphere as gs
from fog_addon import view
from fog_addon.ops import left_out
from fog_addon.precompute.core.spec import FogSpec
from fog_addon.precompute.model import predict
scene = bpy.context.scene
for o in list(scene.objects):
    bpy.data.objects.remove(o)
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
