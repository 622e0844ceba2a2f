"""Dense fog end to end (issue 28): a lamp in fog of optical distance 4.5 rendered with Dense Fog on, against
Cycles' path-traced World volume with 64 volume bounces (``fog_scenes/dense.py``), by annulus means around the
lamp's image (the issue's annuli, 1.5 to 50 px at 0.1 deg a pixel; fireflies left out).

Goal: within 10 % in every annulus.  Measured (docs/measurements/2026-11-27-multiple-scattering.md), ours /
64 bounces: T 1.5 0.990-0.998, T 4.5 0.972-1.009, T 8 1.001-1.033 (Compositor; the Node Groups and EEVEE give
the same to 0.1 %).  The bound keeps a margin over that and the references' noise (T 8's inner ring: 5.9 %);
with Dense Fog off the render is the single-scattering reference's to 0.1 %.
"""
import json
import re

import numpy as np
import pytest

from fog_addon import compare, imageio
from fog_scenes import dense as dn
from fog_scenes import render_harness as h

pytestmark = pytest.mark.render

CASES, SEEDS = dn.GLOW_CASES, dn.GLOW_SEEDS
CASE = CASES[4.5]   # the issue's
BOUND = 0.07   # |ours / reference - 1| in every annulus (goal 0.10)


def _reference(volume_bounces, T=4.5):
    c = CASES[T]
    seeds = SEEDS[T] if volume_bounces else 2
    return dn.render_ms_reference(c["distance"], c["density"], c["anisotropy"], c["albedo"],
                                  volume_bounces=volume_bounces, samples=2048 if volume_bounces else 4096,
                                  seeds=seeds)


def _eevee_blend(tmp_path, distance):
    """The scene with the camera's clip end at 1 000 m: EEVEE renders NaN at its clip ratio of 1e8."""
    blend = tmp_path / "dense_eevee.blend"
    code = ("import bpy, sys; bpy.ops.wm.open_mainfile(filepath=sys.argv[-2]); "
            "bpy.context.scene.camera.data.clip_end = 1000.0; bpy.ops.wm.save_as_mainfile(filepath=sys.argv[-1])")
    h.run(["-c", code, str(dn.blend_path(distance)), str(blend)])
    return blend


@pytest.mark.parametrize("T,engine,method", [
    (4.5, "cycles", "compositor"),
    pytest.param(1.5, "cycles", "compositor", marks=pytest.mark.slow),
    pytest.param(8.0, "cycles", "compositor", marks=pytest.mark.slow),
    pytest.param(4.5, "cycles", "nodes", marks=pytest.mark.slow),
    pytest.param(4.5, "eevee", "compositor", marks=pytest.mark.slow),
])
def test_dense_fog_glow_against_64_bounces(tmp_path, T, engine, method):
    CASE = CASES[T]
    ref = imageio.read_rgb(_reference(64, T))
    blend = _eevee_blend(tmp_path, CASE["distance"]) if engine == "eevee" else dn.blend_path(CASE["distance"])
    log = []
    out = h.render_test("dense", CASE["density"], tmp_path / "ours.exr", engine=engine, method=method,
                        resolution=dn.RESOLUTION, blend=blend, log=log, multiple_scattering=None,   # the defaults
                        extra=("--anisotropy", repr(CASE["anisotropy"]), "--color",
                               ",".join([repr(CASE["albedo"])] * 3), "--explain"))
    assert not h.log_errors(log[0]), h.log_errors(log[0])
    assert "multiple scattering is off" not in log[0] and "Dense Fog left out" not in log[0], log[0][-3000:]
    assert "multiple scattering on (file)" in log[0], log[0][-3000:]   # (Dense Fog by the Quality, by default)
    ours = imageio.read_rgb(out)
    assert np.isfinite(ours).all()
    centre = dn.lamp_image_centre_from_blend(blend)
    ratio = np.array(dn.ring_means(ours, centre)) / np.array(dn.ring_means(ref, centre))
    print(f"T {T} {engine} {method}: ours / 64 bounces by annulus {np.round(ratio, 3)}")
    assert np.all(np.abs(ratio - 1.0) <= BOUND), (dn.ring_labels(), ratio)


def _predicted(log):
    """The predicted error ``--explain`` printed, a fraction."""
    found = re.search(r"predicted error ([0-9.]+)%", log)
    assert found, log[-3000:]
    return float(found.group(1)) / 100.0


def test_dense_fog_off_is_the_single_scattering(tmp_path):
    """The same render with Dense Fog off is single scattering (0 volume bounces); the note and the predicted
    error say what it leaves out, and the prediction is not optimistic: at least half the picture's measured
    relative RMSE against 64 volume bounces (issue 46), which it was 0.00 % before."""
    ref = imageio.read_rgb(_reference(0))
    blend = dn.blend_path(CASE["distance"])
    log = []
    out = h.render_test("dense", CASE["density"], tmp_path / "ours.exr", engine="cycles", method="compositor",
                        resolution=dn.RESOLUTION, blend=blend, log=log,
                        extra=("--anisotropy", repr(CASE["anisotropy"]), "--color",
                               ",".join([repr(CASE["albedo"])] * 3), "--multiple-scattering", "off", "--explain"))
    assert "multiple scattering is off" in log[0]
    ours = imageio.read_rgb(out)
    centre = dn.lamp_image_centre_from_blend(blend)
    ratio = np.array(dn.ring_means(ours, centre)) / np.array(dn.ring_means(ref, centre))
    assert np.all(np.abs(ratio - 1.0) <= 0.02), ratio
    measured = compare.metrics(ours, imageio.read_rgb(_reference(64)))["rel_rmse"]
    predicted = _predicted(log[0])
    print(f"Dense Fog off: predicted {predicted:.1%}, measured against 64 bounces {measured:.1%}")
    assert predicted >= 0.5 * measured, (predicted, measured)


THIN_FLOW = r"""
import json, sys
import bpy
sys.path.insert(0, ROOT)
import fog_addon
from demo_scenes import street_lamps
from fog_addon.ops import apply
from fog_addon.precompute.core.spec import FogSpec
bpy.ops.wm.read_factory_settings(use_empty=True)
fog_addon.register()
scene = bpy.context.scene
street_lamps.build(scene)
bpy.ops.mesh.primitive_cube_add(size=0.3, location=(0.0, 8.0, 2.0))   # a glowing object in view
glow = bpy.data.materials.new("Sign")
glow.use_nodes = True
bsdf = glow.node_tree.nodes["Principled BSDF"]
bsdf.inputs["Emission Color"].default_value = (1.0, 0.2, 0.6, 1.0)
bsdf.inputs["Emission Strength"].default_value = 20.0
bpy.context.object.data.materials.append(glow)
out = {}
def read_tables():   # the Dense Fog tables a node of the fog reads (any tree: materials, World, compositor)
    trees = [ng for ng in bpy.data.node_groups] + [m.node_tree for m in bpy.data.materials if m.node_tree]
    return sorted({n.image.name for t in trees for n in t.nodes
                   if getattr(n, "image", None) is not None and n.image.name.startswith("AnalyticFog Multiple")})
for density in (1e-7, 0.05):
    notes = apply.apply(scene, FogSpec(density=density, method="compositor"))
    choice = apply.stored_choice()
    out[str(density)] = {"thin": sorted(choice["thin"]), "lights": sorted(choice["lights"]),
                         "tables": read_tables(), "error": choice["error"], "target": choice["target"],
                         "emitters": choice["dense"]["emitters"]}
print("THIN " + json.dumps(out))
"""


def test_thin_fog_pays_nothing_and_dense_fog_models_the_rest():
    """With the defaults (Dense Fog by the Quality) the street's lamps in fog far too thin to scatter twice
    are left without Dense Fog, and so is a glowing object's glow: no node reads a table of it (no cost), the
    prediction within the target; at its usual density every lamp and the glowing object get it."""
    proc = h.run_bpy_code(THIN_FLOW.replace("ROOT", repr(str(h.ROOT))))
    assert not h.log_errors(proc.stdout + proc.stderr), h.log_errors(proc.stdout + proc.stderr)
    res = json.loads(next(ln for ln in proc.stdout.splitlines() if ln.startswith("THIN ")).split(" ", 1)[1])
    thin, usual = res["1e-07"], res["0.05"]
    assert thin["thin"] == thin["lights"] and len(thin["lights"]) == 3 and thin["tables"] == [], thin
    assert thin["error"] <= thin["target"] and not thin["emitters"], thin
    assert usual["thin"] == [] and len(usual["tables"]) >= 1 and usual["emitters"], usual
