"""Long operations show progress: stages in order, every material counted, a line per stage on the CLI."""
import io
import json
import subprocess
import sys

import pytest

from conftest import ROOT
from fog_addon.ops import progress

_SCENE = r"""
import json, sys
sys.path.insert(0, sys.argv[1])
import bpy
from fog_addon.ops import apply
from demo_scenes import add_camera, add_point_light, add_sphere, material
bpy.ops.wm.read_factory_settings(use_empty=True)
s = bpy.context.scene
add_camera(s, (0, -8, 2), (0, 0, 0))
add_point_light(s, "L", (0, 0, 3), 100.0)
for k in range(30):
    add_sphere(s, f"S{k}", (k % 6, k // 6, 0), 0.3, material(f"M{k}", (0.5, 0.5, 0.5)), segments=8, rings=4)
calls = []
apply.apply_fog(s, 0.05, progress=lambda *a: calls.append(a))
removed = []
apply.remove_fog(s, progress=lambda *a: removed.append(a))
print(json.dumps({"add": calls, "remove": removed}))
"""


@pytest.mark.render
def test_apply_and_remove_report_every_stage_and_material():
    r = subprocess.run([sys.executable, "-c", _SCENE, str(ROOT)], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-3000:]
    res = json.loads(r.stdout.strip().splitlines()[-1])
    for calls, stages in ((res["add"], ["appended fog", "lights and tables", "materials", "world"]),
                          (res["remove"], ["materials", "world", "lights"])):
        assert list(dict.fromkeys(c[0] for c in calls)) == stages
        mats = [c for c in calls if c[0] == "materials"]
        assert [c[1] for c in mats] == list(range(mats[0][2] + 1)) and mats[0][2] >= 30
        fractions = [progress.overall(*c) for c in calls]
        assert fractions == sorted(fractions) and 0.0 <= fractions[0] and fractions[-1] <= 1.0


def test_console_prints_a_line_per_stage_and_tenths():
    out = io.StringIO()
    report = progress.ConsoleProgress(out)
    report("lights and tables", 0, 1)
    for k in range(1001):
        report("materials", k, 1000)
    lines = out.getvalue().splitlines()
    assert lines[0].startswith("progress: lights and tables 0/1")
    assert [ln.split()[-3] for ln in lines[1:]] == [f"{k}/1000" for k in range(0, 1001, 100)]
