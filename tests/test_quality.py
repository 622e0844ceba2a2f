"""The Quality's error predictor holds on real renders (issue 8 §2).

Each case renders one scene twice in Cycles (tests/scenes/quality_probe.py):
with the models the Quality chose and with every light fully modelled
(Exact), the lights lighting only the fog, and compares the two pictures
(the fog's light alone) pixel by pixel where the exact
fog is at least 1e-3 of its peak.  The measured error (the largest relative
difference) must not exceed the predicted one (``predict.py``, computed from
ray casts of a 64x36 grid, not from a render; the render has 128x72
pixels), and over the cases the prediction may be at most 10x too
pessimistic in the median.  The pessimism of each case is printed.
"""
import json
import statistics
import subprocess
import sys

import numpy as np
import pytest

from fog_scenes import render_harness as h
from conftest import ROOT
from fog_addon import imageio
from fog_addon.precompute.core import spec as spec_
from fog_addon.precompute.model import predict

pytestmark = pytest.mark.render   # every test here starts Blender (bpy) in a subprocess

SCRIPT = ROOT / "tests" / "scenes" / "quality_probe.py"
CASES = [("street_lamps", "draft"), ("boulevard", "final"), ("random:0", "draft"), ("random:1", "draft"),
         ("random:2", "draft"), ("random:4", "final"), ("randomspot:3", "draft"), ("randomspot:5", "final"),
         ("concert_stage", "final"), ("daylit:2", "draft"), ("daylit:5", "final")]
# The two biggest are rendered with the Compositor method: the same models once per pixel (pixel centres here,
# so the same points), where the node groups' two renders took 476 s (randomspot:3, 39 spots) and 152 s
# (boulevard, 45 lamps) in a full-suite run at 225f330, and gave the same predicted and measured errors.
COMPOSITOR_CASES = {"boulevard", "randomspot:3", "concert_stage"}
# concert_stage at Final takes no step: its three spots' glows keep every term and take 4-point rims
# (spot.RIM_LADDER), so its measured error is theirs alone (predicted 1.6e-3 with predict.RIM_SAFETY, measured
# 7.8e-4 when the case was added).


def _run(tmp_path, scene, quality):
    out = tmp_path / scene.replace(":", "_")
    method = "compositor" if scene in COMPOSITOR_CASES else "nodes"
    r = subprocess.run([sys.executable, str(SCRIPT), str(out), scene, quality, method], capture_output=True,
                       text=True, timeout=900)
    assert r.returncode == 0, r.stderr[-3000:]
    errors = h.log_errors(r.stdout + r.stderr)
    assert not errors, errors[:5]
    info = json.loads(r.stdout.strip().splitlines()[-1])
    auto = imageio.read_rgb(out / "auto.exr").astype(np.float64)
    exact = imageio.read_rgb(out / "exact.exr").astype(np.float64)
    judged = exact >= predict.FLOOR * exact.max()
    rel = np.abs(auto - exact)[judged] / exact[judged]
    info["measured"] = float(rel.max()) if rel.size else 0.0
    return info


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    """results(scene, quality): the case's probe, run once per module whichever test asks first."""
    cache = {}

    def get(scene, quality):
        if (scene, quality) not in cache:
            cache[(scene, quality)] = _run(tmp_path_factory.mktemp("quality"), scene, quality)
        return cache[(scene, quality)]
    return get


# The default tier: a demo scene at Draft, the boulevard at Final (Compositor method) and one random scene; the
# other random scenes, the random spots, the concert stage and the daylit ones (10-210 s each) run in the slow tier
# (the daylight's share of each sample's fog: tests/test_predict.py in the numpy tier).
FAST_CASES = {("street_lamps", "draft"), ("boulevard", "final"), ("random:2", "draft")}
SLOW = pytest.mark.slow(reason="the default tier checks the prediction on FAST_CASES")


@pytest.mark.parametrize("scene,quality", [c if c in FAST_CASES else pytest.param(*c, marks=SLOW) for c in CASES],
                         ids=[f"{s}-{q}" for s, q in CASES])
def test_measured_error_within_prediction(results, scene, quality):
    info = results(scene, quality)
    target = spec_.target_error(quality)
    print(f"{scene} {quality}: {info['lights']} lights, steps {sorted(info['steps'].values())}, "
          f"rims {sorted(info['rims'].values())}, predicted {info['predicted']:.4f}, measured {info['measured']:.4f}")
    # the ladder's choice within the target; what the settings leave out (the shadows, shafts being off here, and
    # Dense Fog in the spots' scenes) and Dense Fog's surplus near surfaces are counted on top
    assert info["predicted"] - info["left_out"] <= target + 1e-12
    # (the shadows a scene without shafts lacks and Dense Fog's surplus over the scene's surfaces are in both renders,
    # auto and exact: not in what they measure, so the ladder alone bounds it)
    assert info["measured"] <= (info["predicted"] - info["left_out"]) * (1 + 1e-3) + 2e-5, info["explain"]


@pytest.mark.slow(reason="the median over every case in CASES: it renders the slow tier's cases too (130 s)")
def test_prediction_not_too_pessimistic(results):
    """Median over the cases that dropped something: predicted / measured <= 10 (renders the cases the
    other test has not, so it holds on its own)."""
    infos = [results(scene, quality) for scene, quality in CASES]
    # the ladder's own part: what the settings leave out (the shadows, shafts being off) and Dense Fog's surplus over
    # the scene's surfaces are the same in both renders, auto and exact, so not in what they measure
    ratios = [(i["predicted"] - i["left_out"]) / i["measured"] for i in infos
              if i["predicted"] - i["left_out"] > 0 and i["measured"] > 0]
    assert len(ratios) >= 3, f"only {len(ratios)} cases dropped anything: the median would prove little"
    assert statistics.median(ratios) <= 10.0, ratios
