"""The Compositor method's set-up (tests/scenes/compositor_method.py, one process, no render): the driven
image plane against Blender's own ``Camera.view_frame``, splicing into a user's compositor and taking it
out again, switching methods, refusals that change nothing, and drivers that carry the panel's density and
colour and an animated lamp into the compositor.  Its pictures are proved in test_render.py (against
Cycles' path-traced volume) and test_many_lights.py (1 to 256 lights against the numpy twin)."""
import json

import pytest

from fog_scenes import render_harness as h

pytestmark = pytest.mark.render   # every test here starts Blender (bpy) in a subprocess

FOG_AOVS = ["Fog Coverage", "Fog Position", "Fog Normal", "Fog Base Color", "Fog Metallic", "Fog Roughness",
            "Fog Specular IOR Level", "Fog Transmission Weight"]


@pytest.fixture(scope="module")
def res():
    proc = h.run([h.ROOT / "tests" / "scenes" / "compositor_method.py"], timeout=600)
    assert not h.log_errors(proc.stdout + proc.stderr)
    line = next(ln for ln in proc.stdout.splitlines() if ln.startswith("COMPOSITOR_JSON "))
    return json.loads(line.split(" ", 1)[1])


def test_driven_image_plane_matches_view_frame(res):
    """Auto, Horizontal and Vertical sensor fits, landscape and portrait, shifted: the driven corner and
    edge vectors (unit distance, so about 0.5-1 long) within float32 rounding of Blender's."""
    assert len(res["frames"]) == 5
    for case, err in res["frames"].items():
        assert err < 1e-6, (case, err)


def test_spliced_into_a_users_compositor_and_taken_out(res):
    s = res["splice"]
    assert [n for n in s["notes"] if "light shafts are not modelled" not in n[1]   # (the spheres: a caveat)
            and "multiple scattering is off" not in n[1]] == []                    # (apply_fog's single scattering)
    assert s["fog_nodes"] == ["CompositorNodeGroup"] and s["group"] == "AnalyticFog Compositor Fog"
    assert s["feeds"] == ["Glare", "Viewer"], "both of the Image's users read the fogged picture"
    assert s["rl_feeds"] == ["AnalyticFog Compositor 0 Fog"]
    assert s["aovs_fed"] == sorted(FOG_AOVS + ["Image"])
    assert s["denoising"] is True, "the render holds no fog light: Cycles' denoiser stays on"
    assert s["state"] == {"tree": "My Compositor", "fog": True, "engine": "CYCLES",
                          "links": '[["Render Layers", "Glare", "Image"], ["Render Layers", "Viewer", "Image"]]'}
    assert s["restored"] == {"links": True, "nodes": True, "fog": True, "aovs": True}, s["after"]


def test_switching_methods(res):
    s = res["switch"]
    assert s["nodes_light_groups"] >= 1
    c = s["compositor"]
    assert c["own_tree"] == "AnalyticFog Compositor" and c["aovs"] == FOG_AOVS
    assert c["material_light_groups"] == 0, "with the Compositor method the materials hold no light's fog"
    b = s["back"]
    assert b["tree"] is None and b["aovs"] == [] and not b["fog_group"]
    assert b["material_light_groups"] == s["nodes_light_groups"]


def test_switching_engines(res):
    """EEVEE reads the Depth pass instead of the position AOV (comp_fog.EEVEE_AOVS), and its materials keep the
    lights' shared dimming of direct light (EEVEE has no light node trees); switching back undoes both."""
    cycles, eevee, back = res["engines"]["states"]
    assert cycles["inputs_fed"] == sorted(FOG_AOVS + ["Image"]) and not cycles["depth_pass"]
    assert cycles["aovs"] == sorted(FOG_AOVS) and cycles["material_light_groups"] == 0
    assert cycles["preview_light_groups"] >= 1   # the viewport's preview holds the lamp (nodes/preview.py)
    eevee_aovs = [name if name != "Fog Position" else "Fog Depth" for name in FOG_AOVS]
    assert eevee["engine"] == "BLENDER_EEVEE" and eevee["depth_pass"]
    assert eevee["inputs_fed"] == sorted(eevee_aovs + ["Image", "Depth"]) and eevee["aovs"] == sorted(eevee_aovs)
    assert eevee["material_light_groups"] >= 1, "EEVEE's materials dim the lights' direct light"
    assert back == cycles
    assert res["engines"]["removed"] == {"depth_pass": False, "fog": []}


def test_eevee_dimming_holds_what_fits_brightest_first(res):
    """methods.compositor.dimming_lights on 200 lamps in EEVEE: as many as the budget holds at step off (no fog light in
    the materials), the brightest at the camera (power over squared distance); none in Cycles."""
    d = res["dimming"]
    assert 100 < d["kept"] < 200 and d["fits"] and not d["one_more_fits"], d
    assert d["models"] == ["airlight off"] and d["brightest"], d
    assert d["cycles"] == 0


def test_eevee_preview_takes_the_room_the_dimming_leaves(res):
    """The viewport's preview in EEVEE (Compositor.preview_budget): with 200 lamps the dimming lights fill the
    uniform block and the preview holds no light; with 20 it holds its own budget's two lights."""
    p = res["preview"]
    assert p["crowded_off"] and not p["crowded_glow"], p
    assert p["few_two_full"] and p["few_two_glows"] and not p["few_three_full"] and not p["few_three_glows"], p


def test_eevee_viewport_compositor_is_said(res):
    """EEVEE's viewport compositor, on in a 3D view, would add the fog over the preview: the notes say so."""
    assert any("viewport compositor is on" in why for _, why in res["viewport_compositor"]), res["viewport_compositor"]
    assert not any("viewport compositor" in why for _, why in res["viewport_compositor_off"])


@pytest.mark.parametrize("case,words", [("workbench", "needs Cycles or EEVEE"), ("backscatter", "is below -0.8"),
                                        ("panoramic", "perspective camera")])
def test_refused_changing_nothing(res, case, words):
    assert res["refused"][case] is not None and words in res["refused"][case]
    assert res["refused"][case + " changed"] == []


def test_density_colour_and_lamp_reach_the_compositor_by_drivers(res):
    d = res["driven"]
    assert d["beta"] == pytest.approx(0.05, rel=1e-6)
    assert d["albedo"] == pytest.approx([0.5, 0.6, 0.7], rel=1e-6)
    assert d["light_x"] == pytest.approx(d["lamp_x"], abs=1e-6) and abs(d["lamp_x"]) > 1.0
    assert d["intensity"] == pytest.approx(d["want_intensity"], rel=1e-6)


def test_each_node_built_once(res):
    """CompOps (the compositor's node builder) and NodeOps (the materials') build an operation on the same
    inputs once: Blender's compositor evaluates every node it is given over every pixel, and Cycles' own
    merging of duplicates is quadratic in a material's nodes.  A spot's two glows share all but one rim
    (spot.airlight_pair: three, not four)."""
    s = res["shared"]
    assert s["same"] and s["different"] and s["same_in_shader"]
    assert s["math"] == ["ADD", "EXPONENT", "EXPONENT", "MULTIPLY", "MULTIPLY", "SQRT"], s["math"]
    assert s["pair_rims"] == 3
