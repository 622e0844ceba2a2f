"""fog.add twice is the same as once; after the user edits a fogged material it re-syncs only the fog's copies of the BSDF; bad density changes nothing; fog.remove (after a save and reopen) restores every node tree, custom property and Cycles setting the fog touched exactly, keeping the user's edits and the user's own nodes named like the fog's."""
import json
import subprocess
import sys

import pytest

from conftest import ROOT

pytestmark = pytest.mark.render   # every test here starts Blender (bpy) in a subprocess


def test_add_twice_remove_restores(tmp_path):
    r = subprocess.run([sys.executable, str(ROOT / "tests" / "scenes" / "add_remove.py")],
                       capture_output=True, text=True, timeout=600, cwd=tmp_path)
    assert r.returncode == 0, r.stderr[-3000:]
    res = json.loads(r.stdout.strip().splitlines()[-1])
    assert res["fog_changed_something"], res
    assert res["overrides_on"], f"the scene must trigger both setting overrides: {res}"
    assert {"materials/Diffuse", "materials/Glossy", "worlds/Scene World", "lights/Lamp"} <= set(res["tagged_after_add"]), res
    assert res["tagged_after_remove"] == [], f"fog.remove left tagged nodes in {res['tagged_after_remove']}"
    assert res["user_nodes_kept"], "a user's node named 'AnalyticFog Mine' was taken for the fog's"
    assert res["changed_by_reopen"] == [], f"saving and reopening changed {res['changed_by_reopen']}"
    assert res["changed_by_second_add"] == [], f"a second fog.add changed {res['changed_by_second_add']}"
    assert res["changed_by_add_after_edit"] == [], f"fog.add after a user edit changed {res['changed_by_add_after_edit']}"
    assert res["fog_follows_edit"], f"fog.add after a user edit did not re-sync the fog's copies: {res}"
    assert res["edit_kept_by_add"] and res["edit_kept_by_remove"], res
    assert res["nan_cancelled"], res
    assert res["not_restored"] == [], f"fog.remove did not restore {res['not_restored']}"
