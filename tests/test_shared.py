"""One shared copy of each fog node group, table image and OSL text: after add/remove/add, and after
appending a fogged object from another fogged file once ``dedupe.merge_duplicates`` has run."""
import json
import subprocess
import sys

import pytest

from conftest import ROOT
from fog_addon.nodes import groups, osl
from fog_addon.precompute.model import rungs

pytestmark = pytest.mark.render   # every test here starts Blender (bpy) in a subprocess

SCENES = ROOT / "tests" / "scenes"
A_DENSITY = 0.05           # shared_append.py: scene A's fog; B's is 0.3
SURFACE = groups.SURFACE


def _run(script, *args):
    r = subprocess.run([sys.executable, str(SCENES / script), *map(str, args)],
                       capture_output=True, text=True, timeout=900)
    assert r.returncode == 0, r.stderr[-3000:]
    return json.loads(r.stdout.strip().splitlines()[-1])


def _one_copy_each(state, expect, where):
    names = sorted(n for names in state["fog"].values() for n in names) if "fog" in state else state["names"]
    assert names == expect, f"{where}: fog data {names}, expected {expect}"
    assert state["max_count"] <= 1 and state["suffixed"] == [], f"{where}: copies {state['suffixed']}"
    assert state["suffixed_refs"] == [], f"{where}: still used: {state['suffixed_refs']}"


@pytest.mark.slow   # (9 s; appending fogged files keeps one copy in the default tier: test_append_from_fogged_file)
def test_add_remove_add_keeps_one_copy(tmp_path):
    res = _run("shared_add_remove.py", tmp_path)
    assert len(res["steps"]) > 10
    for step in res["steps"]:
        _one_copy_each(step, step["expect"], step["step"])


SLOW = pytest.mark.slow(reason="the default tier appends once (with renders); the other ways in the slow tier")


@pytest.mark.parametrize("mode, method, render", [
    ("append", "nodes", True),        # bpy.ops.wm.append, merged, pulled lamp removed, tiny Cycles renders
    pytest.param("append_keep", "nodes", False, marks=SLOW),  # the same, pulled lamp kept in A
    pytest.param("load", "nodes", False, marks=SLOW),  # bpy.data.libraries.load(link=False): the sphere and B's World
    pytest.param("load", "osl", False, marks=SLOW),    # OSL method: B's shader text comes along too
])
def test_append_from_fogged_file(tmp_path, mode, method, render):
    res = _run("shared_append.py", tmp_path, mode, method, *(["render"] if render else []))
    expect = res["expect"]
    _one_copy_each(res["a"], expect, "scene A")

    # What the append brings: B's copies of the fog under suffixed names, and B's lamp by the drivers.
    arrived = res["arrived"]
    models = rungs.choose(method)
    assert {f"{SURFACE}.001", "AnalyticFog Params.001", f"{groups.light_group_name(models)}.001"} <= set(
        arrived["suffixed"]), arrived
    assert arrived["appended_material_groups"] == [f"{SURFACE}.001"], arrived
    assert arrived["light_params"]["LampB"] == ["AnalyticFog Params.001"], arrived
    assert "LampB" in arrived["objects"], "B's lamp is expected to come along as a driver target"
    if mode == "load":
        assert "LampB" not in arrived["scene_objects"] and arrived["object_users"]["LampB"] == 0, arrived
        assert {"AnalyticFog World.001", f"{groups.background_group_name(models)}.001"} <= set(
            arrived["suffixed"]), arrived
    else:
        assert "LampB" in arrived["scene_objects"], "wm.append instantiates the driver-pulled lamp in A"
    if method == "osl":
        assert f"{osl.text_name(rungs.AIRLIGHT_QUADRATURE)}.001" in arrived["suffixed"], arrived

    # merge_duplicates folds every copy onto A's and reports the lamp (and B's camera) pulled in.
    assert sorted(res["merged"]) == arrived["suffixed"], res["merged"]
    assert res["pulled"] == (["CameraB", "LampB"] if mode == "load" else ["LampB"]), res["pulled"]
    assert res["merge_again"] == [[], []], res["merge_again"]
    merged = res["after_merge"]
    _one_copy_each(merged, expect, "after merge_duplicates")
    assert merged["appended_material_groups"] == [SURFACE], merged
    keep_lamp = mode == "append_keep"
    assert ("LampB" in merged["scene_objects"]) == keep_lamp and ("LampB" in merged["objects"]) == keep_lamp, merged
    assert "CameraB" not in merged["objects"], merged

    # apply_fog on A afterwards: still one copy each, the appended material on A's fog and A's lights.
    for key in ("after_apply", "after_remove_add"):
        st = res[key]
        _one_copy_each(st, res["expect_after_apply"], key)   # a kept lamp B joins A's light bundles
        assert st["appended_material_groups"] == [SURFACE], (key, st)
        assert abs(st["beta"] - A_DENSITY) < 1e-7, (key, st["beta"])
        assert st["surface_drivers"] == (["LampA", "LampB"] if keep_lamp else ["LampA"]), (key, st)
        assert all(v == ["AnalyticFog Params"] for v in st["light_params"].values()), (key, st)

    if render:
        r = res["render"]   # max |difference| / max pixel against the appended material re-wrapped natively in A
        assert r["merged"] < 1e-4, r
        assert r["before_merge"] > 0.02, r   # B's fog (beta 0.3, LampB) on the sphere before the merge
