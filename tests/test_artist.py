"""The artist's controls without a window: settings, Blender presets, method switch, light
changes through the depsgraph handler, selected-only, bad input (tests/scenes/artist_flow.py)."""
import json
import math
import os
import subprocess
import sys

import pytest

from conftest import ROOT

pytestmark = pytest.mark.render   # every test here starts Blender (bpy) in a subprocess

KOSCHMIEDER = -math.log(0.02)   # independent of fog_addon.precompute.core.presets


@pytest.fixture(scope="module")
def flow(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("artist")
    env = dict(os.environ, BLENDER_USER_RESOURCES=str(tmp / "user"), HOME=str(tmp / "home"))
    r = subprocess.run([sys.executable, str(ROOT / "tests" / "scenes" / "artist_flow.py")],
                       capture_output=True, text=True, timeout=600, cwd=tmp, env=env)
    assert r.returncode == 0, r.stderr[-3000:]
    return json.loads(r.stdout.strip().splitlines()[-1])


def test_visibility_density_scale_colour_reach_the_groups(flow):
    assert flow["density_from_visibility_1km"] == pytest.approx(KOSCHMIEDER / 1000.0, rel=1e-6)
    assert flow["beta_after_visibility"] == pytest.approx(KOSCHMIEDER / 1000.0, rel=1e-6)
    assert flow["beta_after_scale_10"] == pytest.approx(10 * KOSCHMIEDER / 1000.0, rel=1e-6)
    assert flow["albedo_in_groups"][:3] == pytest.approx([0.5, 0.7, 0.9], abs=1e-6)


def test_presets(flow):
    assert flow["haze_density"] == pytest.approx(KOSCHMIEDER / 8000.0, rel=1e-6)   # haze class 5-10 km
    assert flow["haze_beta_in_groups"] == pytest.approx(flow["haze_density"])
    assert flow["preset_add"] == "FINISHED" and flow["preset_file"]
    density, colour = flow["preset_restored"]
    assert density == pytest.approx(0.0123, rel=1e-6) and colour == pytest.approx([0.9, 0.8, 0.7], abs=1e-6)
    assert flow["preset_beta_in_groups"] == pytest.approx(0.0123, rel=1e-6)
    assert flow["preset_removed"]


def test_method_switch_keeps_materials(flow):
    assert flow["osl_script_nodes"] == 2 and flow["osl_switch_on"] is True
    assert flow["node_groups_left_after_switch"] == ["AnalyticFog Light [airlight quadrature, scatter table, "
                                                     "direct exact]"]   # the table rung's group is gone
    assert flow["osl_switch_restored"] is False
    assert flow["materials_kept_by_method_switch"]


def test_haze_preset_sets_its_anisotropy(flow):
    assert flow["haze_anisotropy"] == pytest.approx([0.7, 0.7], abs=1e-6)


def test_anisotropy_switch(flow):
    """Issue 9: the panel's Anisotropy rebuilds the lights' groups with g's models and tables."""
    at = flow["names_at_g085"]
    assert "AnalyticFog Airlight N (g +0.850)" in at and "AnalyticFog Surface M (g +0.850)" in at, at
    assert any(n.startswith("AnalyticFog Light [airlight table (g +0.850)") for n in at), at
    assert "AnalyticFog Airlight N" not in at   # the isotropic table is not kept beside it
    assert flow["names_after_refused_g"] == at   # -0.9 needs OSL: refused, nothing changed
    back = flow["names_back_at_g0"]
    assert "AnalyticFog Airlight N" in back and not any("(g +0.850)" in n for n in back), back
    assert flow["materials_kept_by_anisotropy"]


def test_lights_followed_without_touching_materials(flow):
    assert flow["lights_start"] == ["Lamp"]
    assert flow["lights_after_add"] == ["Extra", "Lamp"]
    assert flow["lights_after_hide"] == ["Lamp"]
    assert flow["lights_after_area"] == ["Extra", "Lamp"]   # an area light glows too
    assert flow["lights_after_sun"] == ["Lamp"]             # a sun light is left out (a note says so)
    assert flow["lights_after_toggle_off"] == ["Lamp"]
    assert flow["lights_after_toggle_on"] == ["Extra", "Lamp"]
    assert flow["lights_after_delete"] == ["Lamp"]
    assert flow["materials_kept_by_light_changes"]


def test_bad_input_refused_with_a_message_and_nothing_changed(flow):
    for d, (status, msg) in flow["bad_density"].items():
        assert status == "CANCELLED" and "density" in msg, (d, msg)
    assert flow["no_camera"][0] == "CANCELLED" and "no camera" in flow["no_camera"][1]
    assert flow["ortho_camera"][0] == "CANCELLED" and "orthographic" in flow["ortho_camera"][1]
    assert flow["unchanged_by_bad_input"]


def test_light_notes(flow):
    notes = flow["light_notes"]
    assert "zero power" in notes["Dark"] and "swallows the sun" in notes["Sunny"] and "non-uniform" in notes["Squashed"]
    assert flow["lights_taking_part"] == ["Lamp", "Squashed"]


def test_selected_only(flow):
    assert flow["fogged_selected"] == flow["selected_materials"] == ["Diffuse"]


def test_invisible_fog_is_reported(flow):
    assert flow["invisible_note"] and not flow["visible_note_at_scale_1000"]


def test_panels_draw(flow):
    assert set(flow["panel_props"]) >= {"visibility", "density", "color", "scene_scale", "method", "selected_only",
                                        "use", "quality"}
    labels = [p for p in flow["panel_props"] if p.startswith("label: ")]
    full = [p for p in labels if p.startswith("label: Full models: ")]
    assert any("airlight table (2e-04)" in p for p in full), full           # the models the preference chooses
    assert any("airlight quadrature (1e-06)" in p for p in full), full      # ... drawn again with OSL preferred
    assert any(p.startswith("label: Quality 0.01: predicted error") for p in labels), labels   # the choice (Final)
