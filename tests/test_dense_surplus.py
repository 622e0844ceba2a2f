"""Dense Fog beside surfaces: its multiply scattered field is that of fog without surfaces (``multiple.py``), and
where a hood, a wall or the ground stops part of a light's power before it scatters each light's field is scaled
by the share the surfaces leave (``escape.field_scales``; ``precompute/physics/point/escape.py``, whose numpy
checks are ``tests/test_escape.py``).  What the scale may still miss is in the predicted error, and a note says it.

* Blender's ray casts: a lamp between a floor and a ceiling, its escape fraction against its closed form
  1 - (E_2(beta h) + E_2(beta c)) / 2 (E_2: the exponential integral), its field's scale below 1 and above f.
* Slow: the hooded lamp and the open street with the defaults (Dense Fog on) against Cycles with 32 volume bounces
  and every object in the fog's way (``tests/references/*_ms32.exr``: 2048 and 1024 spp, one seed), by 4x4 block
  means with the reference's fireflies clipped (its per-pixel noise is larger than the error): within BOUND, and
  the predicted error at least half the measured.  Measured: docs/measurements/2026-11-30-dense-walls.md.
"""
import json
import re

import pytest
from scipy import special

from fog_addon import imageio
from fog_scenes import render_harness as h
from fog_scenes import dense_surfaces as ds
from fog_scenes import shafts as fs

pytestmark = pytest.mark.render

_CODE = r'''
import sys, json, bpy
sys.path.insert(0, sys.argv[1])
from fog_addon import escape
import demo_scenes
scene = bpy.context.scene
demo_scenes.clear_scene(scene)
m = demo_scenes.material("Grey", (0.5, 0.5, 0.5))
demo_scenes.add_box(scene, "Floor", (0.0, 0.0, -0.5), (500.0, 500.0, 0.5), m)
if float(sys.argv[3]) > 0:
    demo_scenes.add_box(scene, "Ceiling", (0.0, 0.0, 3.0 + float(sys.argv[3]) + 0.5), (500.0, 500.0, 0.5), m)
demo_scenes.add_point_light(scene, "Lamp", (0.0, 0.0, 3.0), 100.0)
demo_scenes.add_camera(scene, (0.0, -10.0, 1.5), (0.0, 0.0, 2.0))
class Spec:
    beta_per_unit = float(sys.argv[2])
    anisotropy = 0.0
    grey_albedo = 1.0
lights = [o for o in scene.objects if o.type == "LIGHT"]
print("ESCAPE " + json.dumps({"f": escape.escape_fractions(scene, Spec, lights)["Lamp"],
                              "k": escape.field_scales(scene, Spec, lights)["Lamp"]}))
'''


def test_escape_fraction_and_scale_of_a_lamp_between_planes():
    beta, ceiling = 0.08, 1.0
    proc = h.run_bpy_code(_CODE, h.ROOT, beta, ceiling)
    got = json.loads(next(ln for ln in proc.stdout.splitlines() if ln.startswith("ESCAPE "))[7:])
    want = 1.0 - 0.5 * special.expn(2, beta * 3.0) - 0.5 * special.expn(2, beta * ceiling)
    print(f"beta {beta}, ceiling {ceiling} m above: f {got['f']:.4f}, closed form {want:.4f}, scale {got['k']:.2f}")
    assert abs(got["f"] - want) < 0.01, (got, want)
    assert want < got["k"] < 1.0, got   # (the fog the camera sees lies beside the lamp, fed by the light going sideways)


# (scene, density, reference, its samples, bound on the block means' relative RMSE): ``--regen-references`` renders
# them again (``shafts.render_ms_reference``)
MS_CASES = [("hooded_lamp", 0.08, "hooded_lamp_0.08_ms32.exr", 2048, 0.10),
            ("street_lamps", 0.08, "street_lamps_0.08_shadows_ms32.exr", 1024, 0.08)]


@pytest.mark.slow
@pytest.mark.parametrize("scene,density,reference,samples,bound", MS_CASES, ids=[c[0] for c in MS_CASES])
def test_dense_fog_beside_surfaces_against_path_tracing(tmp_path, regen, scene, density, reference, samples, bound):
    if regen or not (h.REFERENCES / reference).is_file():
        fs.render_ms_reference(scene, density, h.REFERENCES / reference, samples)
    ref, _ = ds.clip_fireflies(imageio.read_rgb(h.REFERENCES / reference))
    log = []
    out = h.render_test(scene, density, tmp_path / f"{scene}.exr", engine="cycles", method="compositor", samples=16,
                        resolution=fs.SHAFT_RESOLUTION, cast_shadows=True, log=log,
                        extra=["--shafts", "on", "--explain"], multiple_scattering=None)
    mask = fs.lamp_pixel_mask(scene, fs.SHAFT_RESOLUTION)
    ours = imageio.read_rgb(out)
    measured = ds.rel_rmse(ds.block_means(ours, mask), ds.block_means(ref, mask))
    predicted = float(re.search(r"predicted error ([0-9.]+)%", log[0]).group(1)) / 100.0
    assert "Dense Fog near surfaces" in log[0], log[0][-2000:]
    print(f"{scene}: 4x4 blocks {measured:.3f} against 32 bounces (per pixel {ds.rel_rmse(ours, ref, mask):.3f}), "
          f"predicted {predicted:.3f}")
    assert measured <= bound, (measured, bound)
    assert predicted >= 0.5 * measured, (predicted, measured)
