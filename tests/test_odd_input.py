"""Odd input a new user gives (tests/scenes/odd_input.py, one Blender process): density 0 is no fog, values typed
into the panel beyond the sliders get the operator's message and keep the fog as built, and each useless setting
gets a note (a lamp at the camera, no lights, a Ground Level above the scene, an opaque fog, view layers the
Compositor method's composite does not show).  No NaN reaches a report."""
import json

import pytest

from fog_scenes import render_harness as h

pytestmark = pytest.mark.render


@pytest.fixture(scope="module")
def res():
    proc = h.run([h.ROOT / "tests" / "scenes" / "odd_input.py"], timeout=900)
    assert not h.log_errors(proc.stdout + proc.stderr)
    line = next(ln for ln in proc.stdout.splitlines() if ln.startswith("ODD_JSON "))
    return json.loads(line.split(" ", 1)[1])


def test_density_zero_is_no_fog(res):
    """The World (grey 0.08) reads as without the fog within 2 %, in both methods (it rendered black)."""
    for method, r in res["density_zero"].items():
        assert r["built"] == method
        assert r["sky_clear"] == pytest.approx(0.08, rel=0.01)
        assert r["sky"] == pytest.approx(1.0, abs=0.02), (method, r)
        assert r["picture"] == pytest.approx(1.0, abs=0.02), (method, r)


@pytest.mark.parametrize("key", ["density", "visibility", "height_falloff", "scene_scale"])
def test_panel_values_beyond_the_sliders_get_the_operators_message(res, key):
    r = res["panel"][key]
    assert r["operator"], "the value typed is one the operator refuses"
    assert r["message"] == r["operator"], "the panel says what the operator says"
    assert r["fog_kept"], "the fog keeps what it was built with"
    assert res["panel"]["before_add"][key] == r["operator"], "before Add Fog the panel says it too"
    assert res["panel"]["cleared"] is None, "a valid value again clears the message"


def test_typed_values_are_kept_not_clamped(res):
    p = res["panel"]
    assert p["density"]["kept"] == 1e4 and p["height_falloff"]["kept"] == -5.0 and p["scene_scale"]["kept"] == 0.0
    assert p["visibility"]["kept"] == pytest.approx(0.01, rel=1e-6)


@pytest.mark.parametrize("case, words", [
    ("lamp_at_camera", "from the camera"),
    ("no_lights", "the World is hidden"),
    ("ground_above", "Ground Level"),
    ("scale_1e6", "opaque"),
    ("density_100", "opaque"),
    ("two_layers_compositor", "view layers render"),
])
def test_each_useless_setting_gets_a_note(res, case, words):
    r = res["notes"][case]
    assert r["ok"] == ["FINISHED"]
    assert any(words in note for note in r["skipped"]), r["skipped"]


def test_auto_fogs_every_view_layer(res):
    """Two view layers and no compositor of the user's: Auto takes the node groups, which fog every layer."""
    r = res["notes"]["two_layers_auto"]
    assert r["method"] == "nodes" and "view layers" in r["reason"], r


def test_no_nan_in_reports(res):
    assert res["nan"] == []


def test_the_panels_notes_are_kept_until_the_scene_changes(res):
    """The panel draws the scene's notes on every redraw from a memo (they walk every object); a change of the scene
    (the depsgraph handler) computes them again."""
    r = res["notes"]["panel_notes"]
    assert r["memo"], "a second redraw reuses the notes"
    ground = [n for n in r["first"] if "Ground Level" in n]
    assert ground and not [n for n in r["moved"] if "Ground Level" in n], r
    assert r["back"] == r["first"], r
