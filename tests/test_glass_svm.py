"""Glass past which the fog's tails glow (``glass_tails.place_tails``) within Cycles' SVM stack (Node Groups).

The See Through shader's tails, the straight one through the pane and the mirrored one, are an Emission closure
each (``glass_tails.build_tail_bundle``).  As one closure of their sum SVM compiled both tails' kernels side by side
(``closures.closure_sum`` says why): one spot light at Quality Exact took the Glass BSDF material to 255 floats,
out of SVM stack space, and the pane rendered black.  As two closures: 178 (2 spots 208, 3 spots 229; the other
materials 179, 192, 196), docs/measurements/2026-11-29-shader-budgets.md.
"""
import json

import pytest

from fog_scenes import render_harness as h
from fog_scenes.cycles_debug_log import peaks

pytestmark = pytest.mark.render   # starts Blender (bpy) in a subprocess

SCENE = h.ROOT / "tests" / "scenes" / "glass_svm.py"


def test_glass_with_a_spot_renders_clean(tmp_path):
    """tests/scenes/glass_svm.py, one spot (16 x 12 px, 1 sample, about 4 s): no error in the log (no "out of SVM
    stack space"), the Glass BSDF pane and the Principled Transmission 1 pane not black."""
    proc = h.run([SCENE, tmp_path / "glass_svm.exr", 1, 0], timeout=600, check=False)
    text = proc.stdout + proc.stderr
    assert proc.returncode == 0, text[-3000:]
    stack = {k: v for k, v in peaks(text.split("RENDER_START", 1)[-1]).items() if k in ("Glass", "Trans")}
    line = next(ln for ln in text.splitlines() if ln.startswith("GLASS_SVM "))
    objects = json.loads(line.split(" ", 1)[1])["objects"]
    print("SVM stack peaks", stack, "objects", objects)
    assert not h.log_errors(text), (h.log_errors(text), stack)
    for pane in ("Glass", "Trans"):
        o = objects[pane]
        # through the pane: the ground the spot lights and the cone's glow (a pixel or two may see dark sky)
        assert o["n"] >= 4 and o["max"] > 1e-4 and o["black"] <= o["n"] // 3, (pane, o, stack)
