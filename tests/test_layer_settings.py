"""The fog layer's settings (issue 29): Fog Top, Height Falloff, Ground Level in the properties, the command
line and the presets.  Nothing here renders: the parser and the presets are checked in this process, the
properties in one Blender (bpy) process without a window (``_FLOW``)."""
import json
import math
import subprocess
import types

import pytest

from fog_addon import cli
from fog_addon.precompute.core import presets
from fog_addon.precompute.core.spec import FogSpec
from fog_scenes import render_harness as h

KOSCHMIEDER = math.log(50.0)   # ln(1 / 0.02): contrast threshold 2 %, independent of presets.KOSCHMIEDER


def _render_args(*flags):
    """``render`` parsed as the command line does it, with the preset resolved (``cli._resolve_density``)."""
    args = cli.build_parser().parse_args(["render", "scene.blend", "--engine", "cycles", *flags, "--out", "o.png"])
    cli._resolve_density(args, False, layers=True)
    return args


# --- presets: each layered preset inside the ranges its sources give (presets.py docstring) -------------------

# (visibility m, top m, falloff m, g, albedo) ranges typed from the sources, not from presets.py:
RANGES = {
    # radiation fog (Gultepe et al. 2007): tens of metres to ~200 m deep, visibility 100-500 m; droplets g 0.8-0.9
    "valley_fog": dict(visibility=(100.0, 500.0), top=(10.0, 200.0), falloff=(0.0, 50.0), g=(0.8, 0.9),
                       albedo=(0.95, 1.0)),
    # convective boundary layer 1-2 km (Stull 1988), visibility 10-20 km, aerosol scale height 1.2 km (Dobashi
    # et al. 2002 A.1; Bruneton & Neyret 2008), continental aerosol g 0.6-0.76, albedo 0.9 (Bruneton & Neyret)
    "summer_haze": dict(visibility=(10000.0, 20000.0), top=(1000.0, 2000.0), falloff=(1140.0, 1260.0),
                        g=(0.6, 0.76), albedo=(0.85, 0.95)),
    # marine layer 100-400 m (Koracin et al. 2014), visibility about 1 km, g about 0.8
    "sea_mist": dict(visibility=(700.0, 1500.0), top=(100.0, 400.0), falloff=(0.0, 100.0), g=(0.75, 0.85),
                     albedo=(0.95, 1.0)),
    # a clear day: visibility 20-50 km ("very clear", the WMO's visibility code), aerosol from the ground with
    # H_M = 1.2 km, Mie g 0.76, albedo 0.9 (Bruneton & Neyret 2008 section 2.1)
    "clear_day": dict(visibility=(20000.0, 50000.0), top=(0.0, 0.0), falloff=(1140.0, 1260.0), g=(0.7, 0.8),
                      albedo=(0.85, 0.95)),
}
AIR = {"valley_fog": 0.0, "summer_haze": 1.0, "sea_mist": 0.0, "clear_day": 1.0}   # 1: a day's clear air


@pytest.mark.parametrize("name", sorted(RANGES))
def test_layered_preset_within_its_sources(name):
    layer = presets.LAYERED[name]
    r = RANGES[name]
    checks = {"visibility": KOSCHMIEDER / layer["density"], "top": layer["fog_top"],
              "falloff": layer["height_falloff"], "g": layer["anisotropy"]}
    checks.update({f"albedo {i}": a for i, a in enumerate(layer["albedo"])})
    for what, value in checks.items():
        lo, hi = r[what.split()[0]]
        assert lo <= value <= hi, (name, what, value, (lo, hi))
    assert len(layer["albedo"]) == 3
    assert layer["air"] == AIR[name]
    spec = FogSpec(density=layer["density"], anisotropy=layer["anisotropy"], albedo=layer["albedo"],
                   fog_top=layer["fog_top"], height_falloff=layer["height_falloff"], air=layer["air"]).validated()
    assert spec.layered
    assert (spec.air_per_unit() is None) == (AIR[name] == 0.0)


def test_layered_presets_are_listed_apart_from_the_visibility_classes():
    assert set(presets.LAYERED) == set(RANGES)
    assert not set(presets.LAYERED) & set(presets.PRESETS)   # the Add Fog operator's density presets stay four
    assert set(cli._presets()) == set(presets.PRESETS) | set(RANGES)


# --- Air: the clear air's density, validated, stored and scaled ------------------------------------------------

# Bruneton & Neyret 2008 section 2.1: sea-level Rayleigh scattering at 680, 550, 440 nm (1/m), scale height (m)
BRUNETON_RAYLEIGH = (5.8e-6, 13.5e-6, 33.1e-6)
BRUNETON_RAYLEIGH_HEIGHT = 8000.0


@pytest.mark.parametrize("air,message", [
    (math.nan, "must be finite"), (math.inf, "must be finite"), (-0.5, "must be >= 0"),
    (100.5, "at most 100 times sea-level air"), ("thick", "must be a number"),
])
def test_bad_air_is_refused_with_a_message(air, message):
    with pytest.raises(ValueError, match=message) as e:
        FogSpec(fog_top=100.0, air=air).validated()
    assert "air" in str(e.value)


@pytest.mark.parametrize("air", [0, 0.0, 2.5, 100.0])
def test_air_in_range_is_accepted(air):
    spec = FogSpec(fog_top=100.0, air=air).validated()
    assert spec.air == float(air) and isinstance(spec.air, float)


def test_air_defaults_to_no_air():
    assert FogSpec().validated().air == 0.0
    assert FogSpec(fog_top=50.0).validated().air_per_unit() is None


def test_air_per_unit_is_none_without_a_top_or_without_air():
    assert FogSpec(air=1.0).validated().air_per_unit() is None                 # fog fills all space
    assert FogSpec(fog_top=0.0, height_falloff=1200.0, air=0.0).validated().air_per_unit() is None


@pytest.mark.parametrize("air,scene_scale", [(1.0, 1.0), (2.5, 1.0), (1.0, 100.0), (0.3, 0.01)])
def test_air_per_unit_scales_the_standard_atmosphere(air, scene_scale):
    spec = FogSpec(fog_top=100.0, air=air, scene_scale=scene_scale).validated()
    rgb, height = spec.air_per_unit()
    assert len(rgb) == 3
    for got, beta in zip(rgb, BRUNETON_RAYLEIGH):
        assert got == pytest.approx(beta * air * scene_scale, rel=1e-12)   # 1/(Blender unit)
    assert height == pytest.approx(BRUNETON_RAYLEIGH_HEIGHT / scene_scale, rel=1e-12)   # Blender units


@pytest.mark.parametrize("fields", [dict(fog_top=80.0, height_falloff=5.5, air=2.5, scene_scale=3.0),
                                    dict(fog_top=0.0, height_falloff=1200.0, air=1.0),
                                    dict(fog_top=None, air=0.75)])
def test_air_round_trips_through_settings_and_json(fields):
    spec = FogSpec(**fields).validated()
    settings = types.SimpleNamespace(**spec.settings_values())   # the properties, as from_settings reads them
    assert settings.air_density == fields["air"]
    assert FogSpec.from_settings(settings) == spec
    assert json.loads(spec.to_json())["air"] == fields["air"]
    assert FogSpec.from_json(spec.to_json()) == spec


def test_files_from_before_air_read_as_no_air():
    spec = FogSpec(fog_top=80.0, height_falloff=5.0, air=3.0).validated()
    values = spec.settings_values()
    del values["air_density"]                                       # a file saved before the property
    assert FogSpec.from_settings(types.SimpleNamespace(**values)).air == 0.0
    data = json.loads(spec.to_json())
    del data["air"]                                                 # node groups built before the field
    assert FogSpec.from_json(json.dumps(data)).air == 0.0


# --- the command line: flags parsed, presets resolved, bad values refused --------------------------------------

def test_flags_parse_to_the_layer():
    args = _render_args("--fog-top", "120", "--height-falloff", "15", "--ground-level", "-2.5")
    assert (args.fog_top, args.height_falloff, args.ground_level, args.no_fog_top) == (120.0, 15.0, -2.5, False)
    args = _render_args("--no-fog-top")
    assert args.no_fog_top and args.fog_top is None
    args = _render_args()
    assert (args.fog_top, args.height_falloff, args.ground_level) == (None, None, None)   # the file's settings
    assert args.air is None
    assert _render_args("--air", "2.5").air == 2.5 and _render_args("--air", "0").air == 0.0


def test_render_help_lists_air():
    r = subprocess.run([h.PYTHON, "-m", "fog_addon", "render", "--help"], capture_output=True, text=True,
                       timeout=60, cwd=h.ROOT)
    assert r.returncode == 0 and "--air X" in r.stdout and "sea-level air" in r.stdout


def test_layered_preset_sets_what_its_flags_leave_out():
    args = _render_args("--preset", "summer_haze")
    assert args.density == pytest.approx(KOSCHMIEDER / 15000.0, rel=1e-9)
    assert (args.fog_top, args.height_falloff, args.anisotropy, args.color) == (1500.0, 1200.0, 0.7, (0.9,) * 3)
    args = _render_args("--preset", "valley_fog", "--fog-top", "40", "--height-falloff", "0", "--anisotropy",
                        "0.5", "--color", "0.5,0.6,0.7")
    assert (args.fog_top, args.height_falloff, args.anisotropy, args.color) == (40.0, 0.0, 0.5, (0.5, 0.6, 0.7))
    args = _render_args("--preset", "sea_mist", "--no-fog-top")
    assert args.fog_top is None and args.no_fog_top
    args = _render_args("--preset", "fog")   # a visibility class leaves the layer to the file
    assert (args.fog_top, args.height_falloff, args.color, args.air) == (None, None, None, None)


def test_layered_preset_sets_the_air_its_flag_leaves_out():
    assert _render_args("--preset", "summer_haze").air == 1.0
    assert _render_args("--preset", "valley_fog").air == 0.0
    args = _render_args("--preset", "clear_day")
    assert (args.fog_top, args.height_falloff, args.anisotropy, args.air) == (0.0, 1200.0, 0.76, 1.0)
    assert args.density == pytest.approx(KOSCHMIEDER / 40000.0, rel=1e-9)
    assert _render_args("--preset", "clear_day", "--air", "0.5").air == 0.5


@pytest.mark.parametrize("flags,message", [
    (["--fog-top", "-1"], "fog top must be >= 0"),
    (["--fog-top", "nan"], "fog top must be finite"),
    (["--fog-top", "inf"], "fog top must be finite"),
    (["--fog-top", "high"], "fog top must be a number"),
    (["--height-falloff", "-3"], "height falloff must be >= 0"),
    (["--height-falloff", "inf"], "height falloff must be finite"),
    (["--ground-level", "nan"], "ground level must be finite"),
    (["--air", "-1"], "air must be >= 0"),
    (["--air", "nan"], "air must be finite"),
    (["--air", "101"], "air must be at most 100"),
    (["--air", "lots"], "air must be a number"),
    (["--fog-top", "50", "--no-fog-top"], "not allowed with argument"),
])
def test_bad_layer_flags_exit_2(capsys, flags, message):
    with pytest.raises(SystemExit) as e:
        cli.main(["render", "scene.blend", "--engine", "cycles", *flags, "--out", "o.png"])
    assert e.value.code == 2
    assert message in capsys.readouterr().err


def test_reference_refuses_a_layered_preset(capsys, tmp_path):
    """The path-traced reference fills all space with fog: a preset with a top would be a wrong reference."""
    code = cli.main(["reference", str(tmp_path / "s.blend"), "--preset", "valley_fog", "--out",
                     str(tmp_path / "o.exr")])
    assert code == 2 and "fog layer with a top" in capsys.readouterr().err


# --- the properties in Blender: round trip, the render command's spec, the presets' operators ------------------

_FLOW = r"""
import argparse, dataclasses, json, sys
import bpy
import fog_addon
from fog_addon import cli, render
from fog_addon.ops.operators import FOG_OT_preset_add
from fog_addon.precompute.core import presets
from fog_addon.precompute.core.spec import FogSpec

bpy.ops.wm.read_factory_settings(use_empty=True)
fog_addon.register()
scene = bpy.context.scene
s = scene.analytic_fog
assert not s.enabled   # no fog: setting a property schedules nothing
R = {}

rna = s.bl_rna.properties
R["props"] = {k: dict(type=rna[k].type, default=rna[k].default, subtype=rna[k].subtype,
                      unit=getattr(rna[k], "unit", None), min=getattr(rna[k], "soft_min", None),
                      hard_min=getattr(rna[k], "hard_min", None))
              for k in ("use_fog_top", "fog_top", "height_falloff", "ground_level", "air_density")}
R["air_range"] = [rna["air_density"].hard_max, rna["air_density"].soft_max, rna["air_density"].name]

def store(spec):
    for key, value in spec.settings_values().items():
        setattr(s, key, value)

def fields(spec):
    return dataclasses.asdict(spec)

R["round_trip"] = []
for fields_in in (dict(fog_top=80.0, height_falloff=5.5, ground_level=-3.5, density=0.0123, air=2.5),
                  dict(fog_top=0.0, height_falloff=0.0, ground_level=12.25),
                  dict(fog_top=None, height_falloff=7.0, ground_level=1.0, air=0.5)):
    spec = FogSpec(**fields_in).validated()
    store(spec)
    R["round_trip"].append([fields(spec), fields(FogSpec.from_settings(s)), s.use_fog_top])

def case(*flags):
    args = cli.build_parser().parse_args(["render", "scene.blend", "--engine", "cycles", *flags, "--out", "o.png"])
    cli._resolve_density(args, False, layers=True)
    args.engine_id = "CYCLES"
    spec, _, shown, notes = render.fog_settings(scene, args)
    return dict(spec=fields(spec), shown={k: list(v) for k, v in shown.items() if k in
                                          ("fog top", "height falloff", "ground level", "density", "air")},
                notes=[n for _, n in notes], line=render.describe(shown))

store(FogSpec(fog_top=80.0, height_falloff=5.0, ground_level=1.5).validated())   # the file: a layer
R["cases"] = {"file": case(), "top": case("--fog-top", "40"), "no_top": case("--no-fog-top"),
              "falloff_ground": case("--height-falloff", "20", "--ground-level", "-3"),
              "haze": case("--preset", "summer_haze"), "air": case("--air", "2.5"),
              "clear_day": case("--preset", "clear_day")}
store(FogSpec().validated())                                                      # the file: unbounded
R["cases"]["unbounded"] = case()
R["cases"]["unbounded_falloff"] = case("--height-falloff", "7")
R["cases"]["unbounded_air"] = case("--air", "1")

R["builtin"] = {}
for name in presets.LAYERED:
    store(FogSpec().validated())
    assert bpy.ops.fog.preset_builtin(name=name) == {"FINISHED"}
    R["builtin"][name] = dict(use_fog_top=s.use_fog_top, fog_top=s.fog_top, height_falloff=s.height_falloff,
                              density=s.density, anisotropy=s.anisotropy, color=list(s.color), air=s.air_density)
s.use_fog_top, s.fog_top, s.height_falloff, s.air_density = True, 77.0, 3.0, 1.5
bpy.ops.fog.preset_builtin(name="haze")
R["after_visibility_preset"] = [s.use_fog_top, s.fog_top, s.height_falloff, s.density, s.air_density]

R["preset_values"] = list(FOG_OT_preset_add.preset_values)
s.use_fog_top, s.fog_top, s.height_falloff, s.air_density = True, 250.0, 12.0, 2.5
R["preset_add"] = sorted(bpy.ops.fog.preset_add(name="Layer Test"))
path = bpy.utils.preset_find("Layer_Test", "analytic_fog")
s.use_fog_top, s.fog_top, s.height_falloff, s.air_density = False, 9.0, 0.0, 0.0
bpy.ops.script.execute_preset(filepath=path, menu_idname="FOG_MT_presets")
R["preset_restored"] = [s.use_fog_top, s.fog_top, s.height_falloff, s.air_density]
print(json.dumps(R))
"""


@pytest.fixture(scope="module")
def flow(tmp_path_factory):
    return h.bpy_flow(_FLOW, tmp_path_factory.mktemp("layer"), timeout=300)


@pytest.mark.render
def test_properties_are_declared_as_documented(flow):
    p = flow["props"]
    assert p["use_fog_top"]["type"] == "BOOLEAN" and p["use_fog_top"]["default"] is False
    assert p["fog_top"]["default"] == 100.0 and p["fog_top"]["min"] == 0.0
    assert p["height_falloff"]["default"] == 0.0 and p["height_falloff"]["min"] == 0.0
    assert p["ground_level"]["default"] == 0.0
    for k in ("fog_top", "height_falloff", "ground_level"):
        assert (p[k]["type"], p[k]["subtype"], p[k]["unit"]) == ("FLOAT", "DISTANCE", "LENGTH"), (k, p[k])
    assert (p["air_density"]["type"], p["air_density"]["default"], p["air_density"]["min"]) == ("FLOAT", 0.0, 0.0)
    # the sliders' range only: a value typed beyond it reaches the spec's validation and its message
    # (tests/test_odd_input.py), it is not clamped in silence
    assert all(p[k]["hard_min"] < -1e30 for k in ("fog_top", "height_falloff", "air_density")), p
    assert flow["air_range"][1:] == [4.0, "Air"] and flow["air_range"][0] > 1e30


@pytest.mark.render
def test_spec_round_trips_through_the_properties(flow):
    for stored, read, use_fog_top in flow["round_trip"]:
        assert use_fog_top == (stored["fog_top"] is not None)
        for key, value in stored.items():
            if isinstance(value, float):
                assert read[key] == pytest.approx(value, rel=1e-6), (key, stored, read)
            else:
                assert read[key] == value, (key, stored, read)


@pytest.mark.render
def test_render_flags_feed_the_spec(flow):
    c = flow["cases"]
    layer = {name: tuple(case["spec"][k] for k in ("fog_top", "height_falloff", "ground_level"))
             for name, case in c.items()}
    assert layer["file"] == (80, 5, 1.5) and c["file"]["shown"]["fog top"] == [80.0, "file"]
    assert "fog top 80 (file), height falloff 5 (file), ground level 1.5 (file)" in c["file"]["line"]
    assert layer["top"] == (40, 5, 1.5) and c["top"]["shown"]["fog top"] == [40.0, "flag"]   # the rest the file's
    assert layer["falloff_ground"] == (80, 20, -3)
    assert c["falloff_ground"]["shown"]["ground level"] == [-3.0, "flag"]
    assert layer["haze"] == (1500, 1200, 1.5)
    assert c["haze"]["spec"]["density"] == pytest.approx(KOSCHMIEDER / 15000.0, rel=1e-9)
    assert layer["unbounded"][0] is None and c["unbounded"]["shown"]["fog top"] == ["unbounded", "file"]
    assert not c["unbounded"]["notes"] and not c["file"]["notes"]
    assert any("--fog-top" in n for n in c["unbounded_falloff"]["notes"]), c["unbounded_falloff"]
    assert any("--fog-top" in n for n in c["unbounded_air"]["notes"]), c["unbounded_air"]
    assert c["file"]["spec"]["air"] == 0.0 and c["file"]["shown"]["air"] == [0.0, "file"]
    assert c["air"]["spec"]["air"] == 2.5 and c["air"]["shown"]["air"] == [2.5, "flag"]
    assert c["haze"]["spec"]["air"] == 1.0 and c["haze"]["shown"]["air"] == [1.0, "flag"]
    assert tuple(c["clear_day"]["spec"][k] for k in ("fog_top", "height_falloff", "air")) == (0.0, 1200.0, 1.0)


@pytest.mark.render
def test_no_fog_top_clears_the_files_top(flow):
    c = flow["cases"]["no_top"]
    assert c["spec"]["fog_top"] is None and c["shown"]["fog top"] == ["unbounded", "flag"]
    assert c["spec"]["height_falloff"] == 5 and c["spec"]["ground_level"] == 1.5   # the rest stays the file's


@pytest.mark.render
def test_builtin_presets_set_the_layer_or_keep_it(flow):
    for name, got in flow["builtin"].items():
        layer = presets.LAYERED[name]
        assert got["use_fog_top"] is True, name
        for key in ("fog_top", "height_falloff", "density", "anisotropy", "air"):
            assert got[key] == pytest.approx(layer[key], rel=1e-6), (name, key, got)
        assert got["color"] == pytest.approx(list(layer["albedo"]), rel=1e-6), name
    assert flow["builtin"]["clear_day"]["air"] == 1.0 and flow["builtin"]["summer_haze"]["air"] == 1.0
    use, top, falloff, density, air = flow["after_visibility_preset"]   # a visibility class keeps the layer
    assert (use, top, falloff, air) == (True, 77.0, 3.0, 1.5)
    assert density == pytest.approx(KOSCHMIEDER / 8000.0, rel=1e-6)


@pytest.mark.render
def test_user_presets_save_the_layer(flow):
    assert {"fog.use_fog_top", "fog.fog_top", "fog.height_falloff", "fog.air_density"} <= set(flow["preset_values"])
    assert flow["preset_add"] == ["FINISHED"]
    assert flow["preset_restored"] == [True, 250.0, 12.0, 2.5]
