"""Method Auto (``fog_addon/methods/auto.py``), the default: per scene, the node groups or the compositor, by
predicted cost and by what the scene needs; the choice and its reason shown (tests/scenes/auto_method.py, one
process, no render).  Its cost goals are a benchmark (benchmarks/overhead.py --methods cycles_auto), not a test."""
import json

import pytest

from fog_scenes import render_harness as h

pytestmark = pytest.mark.render   # starts Blender (bpy) in a subprocess


@pytest.fixture(scope="module")
def res():
    proc = h.run([h.ROOT / "tests" / "scenes" / "auto_method.py"], timeout=600)
    line = next(ln for ln in proc.stdout.splitlines() if ln.startswith("AUTO_JSON "))
    return json.loads(line.split(" ", 1)[1])


def test_cost_picks_the_compositor_in_cycles(res):
    """Cycles' node groups cost about 4x the fog-free render with one lamp and ~30x with 16; the compositor
    1.3-1.5x: Auto takes the compositor, and says the predicted figures."""
    for case in ("cycles_1", "cycles_25"):
        name, reason = res[case]
        assert name == "compositor" and "predicted" in reason, (case, res[case])


def test_light_shafts_pick_the_compositor(res):
    """Objects in a lamp's glow (the spheres): only the compositor casts their shadows into the fog, so Auto
    takes it whatever the cost, glass in view too (a Glass BSDF, which in Cycles both methods shade past: the reason
    names no caveat for it)."""
    for case in ("cycles_1_shafts", "cycles_1_glass_shafts"):
        name, reason = res[case]
        assert name == "compositor" and "light shafts" in reason, (case, res[case])
    assert "Window Glass" not in res["cycles_1_glass_shafts"][1]


def test_few_samples_keep_the_node_groups(res):
    """The compositor's cost is per pixel and frame, the render's per sample: at 1 sample the node groups win,
    unless Dense Fog has a spot light to glow (where its multiply scattered light matters), which only the
    compositor does."""
    assert res["cycles_1_one_sample"][0] == "nodes", res["cycles_1_one_sample"]
    name, reason = res["cycles_1_one_sample_dense_spot"]
    assert name == "compositor" and "spot" in reason, res["cycles_1_one_sample_dense_spot"]
    # in fog so thin that its multiply scattered light is far below the Quality's target, Dense Fog leaves the spot
    # out (the Quality's ``left_out.dense_fog``), so it asks nothing of the method
    assert res["cycles_1_one_sample_thin_spot"][0] == "nodes", res["cycles_1_one_sample_thin_spot"]


def test_what_only_the_node_groups_have(res):
    # fog passes: both methods serve them, so they do not move the choice
    assert res["cycles_1_passes"][0] == res["cycles_1_shafts"][0] == "compositor", res["cycles_1_passes"]
    assert res["cycles_1_passes_no_shafts"][0] == res["cycles_1"][0], res["cycles_1_passes_no_shafts"]
    # a panoramic camera: the compositor serves it in Cycles (the choice as with a perspective one), not in EEVEE
    assert res["cycles_1_panoramic"] == res["cycles_1_shafts"], res["cycles_1_panoramic"]
    assert res["eevee_1_panoramic"][0] == "nodes" and "perspective" in res["eevee_1_panoramic"][1]
    assert res["cycles_1_g_below_tables"][0] == "osl", res["cycles_1_g_below_tables"]


def test_see_through_materials(res):
    """Glass in Cycles (a Glass BSDF, a frosted Principled glass): both methods shade what lies past it (the compositor through its materials'
    tails), so Auto chooses by cost and names no caveat.  A transparent material (alpha 0.5): the compositor's one
    surface point per pixel is wrong there; the node groups while they cost little (1 lamp), else the compositor
    with the caveat said."""
    for case in ("cycles_1_glass", "cycles_25_glass"):
        name, reason = res[case]
        assert name == "compositor" and "Window Glass" not in reason and "predicted" in reason, res[case]
    name, reason = res["cycles_1_frosted"]   # frosted Principled glass: served alike (``caveats.served_glass``)
    assert name == res["cycles_1_glass"][0] and "Frosted Glass" not in reason, res["cycles_1_frosted"]
    name, reason = res["cycles_1_curtain"]
    assert name == "nodes" and "Net Curtain" in reason, res["cycles_1_curtain"]
    name, reason = res["cycles_25_curtain"]
    assert name == "compositor" and "Net Curtain" in reason and "approximate" in reason, res["cycles_25_curtain"]


def test_eevee(res):
    """EEVEE's uniform block can't hold 64 lamps' node groups: the compositor; one lamp costs EEVEE's node
    groups little (1.03x measured): they keep it."""
    assert res["eevee_64"][0] == "compositor" and "uniform block" in res["eevee_64"][1], res["eevee_64"]
    assert res["eevee_1"][0] == "nodes", res["eevee_1"]


def test_explicit_method_has_no_reason(res):
    assert res["cycles_1_explicit_nodes"] == ["nodes", None]


def test_operator_reports_and_stores_the_choice(res):
    assert res["add"] == ["FINISHED"] and res["spec_method"] == "AUTO"
    assert res["built"] == res["stored"]["method"] == "compositor" and res["stored"]["method_reason"]
    assert any(line.strip().startswith("Method Auto: Compositor (") for line in res["explain"]), res["explain"]
    # the spheres shadow the lamps' glows: the shafts' nodes a ray are said, and that the prediction leaves them out
    assert any(line.strip().startswith("Light shafts of") and "not in the prediction" in line
               for line in res["explain"]), res["explain"]


def test_refused_change_is_shown_and_changes_nothing(res):
    """Anisotropy -0.9 with Method Compositor (beyond its tables): refused; the fog keeps its groups, the panel
    shows why.  A lamp moved while refused: the handlers rebuild with the settings the fog was built with and
    keep saying why (they built the refused settings: with Fog Passes, once refused too, the World's preview
    bundle had no pass sockets, a KeyError that left half-built groups and no word).  Served again, the message
    clears."""
    r = res["refused"]
    assert r["error"] and "anisotropy -0.9 is below -0.8" in r["error"] and r["built"] == "compositor" and r["g"] == 0.0, r
    m = res["refused_then_moved"]
    assert m["raised"] is None and m["built"] == "compositor" and not m["building"], m
    assert m["error"] == r["error"] and m["g"] == 0.0, m
    # a fault of the add-on's in a handler's rebuild is said, not raised, and the next rebuild clears it
    f = res["fault"]
    assert f["raised"] is None and "could not follow the scene (ZeroDivisionError" in f["error"], f
    assert f["after"] is None and f["built"] == "compositor", f


def test_compositor_serves_fog_passes(res):
    """Fog Passes with Method Compositor: a File Output node of the fog's writes the fog group's Fog Light and Fog
    Transmittance (the view layer holds the materials' transmittance, not the fog light); Auto then chooses by
    cost among the methods that serve them, and says so."""
    c = res["compositor_passes"]
    assert c["error"] is None and c["built"] == "compositor", c
    assert c["outputs"] == [["/tmp/", "ViewLayer Fog Passes_####", ["Fog Light", "Fog Transmittance"]]], c
    assert c["aovs"] == ["Fog Transmittance"], c
    a = res["auto_with_passes"]
    assert a["error"] is None and a["built"] in ("nodes", "compositor") and "Method Auto" in a["line"], a


def test_what_is_not_modelled_is_said(res):
    """A lamp with the spheres under it has shadows in the fog, a lamp over a bare ground has none in sight
    (the ground's shadow lies under it) unless the camera is below the ground.  With the compositor's shafts
    nothing is said of them; the node groups, or Light Shafts off, say that the objects cast no shadow into
    the fog; a lamp's Radius is said not to soften the shafts.  Glass in view is said.  The operator stores
    the notes for the panel (and reports them, as ``render`` prints them)."""
    assert set(res["shadows_spheres"]) == {"L000"} and res["shadows_spheres"]["L000"] >= 3, res["shadows_spheres"]
    assert res["shadows_ground_only"] == {}, res["shadows_ground_only"]
    assert res["shadows_ground_from_below"] == {"L000": 1}, res["shadows_ground_from_below"]
    assert res["glass_add"] == ["FINISHED"]
    text = " | ".join(res["caveats"])
    assert "light shafts" not in text and "Window Glass" in text, res["caveats"]
    said = "light shafts are not modelled (this method has none: Method Compositor (or Auto) casts them"
    assert any(said in n for n in res["caveats_nodes"])
    assert any("light shafts are not modelled (Light Shafts is off)" in n for n in res["caveats_off"])
    assert any("are sharp" in n and "L000" in n for n in res["caveats_soft"]), res["caveats_soft"]
