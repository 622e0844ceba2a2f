"""``python -m fog_addon render SCENE.blend`` renders the fog the file was saved with.

tests/scenes/cli_scene.py adds the fog through the operator with settings that
are all not the defaults (density, colour, scene scale, Selected Only with one
of two planes selected, one of two lights with its Fog Glow off), renders it
in that process as the panel's user would (Cycles, pixel centres, no denoiser)
and saves the .blend.  The command, given no fog flags, must render the same
picture; a flag overrides only its own setting.
"""
import json

import numpy as np
import pytest

from fog_scenes import render_harness as h
from fog_addon import imageio

pytestmark = pytest.mark.render   # every test here starts Blender (bpy) in a subprocess

SCRIPT = h.ROOT / "tests" / "scenes" / "cli_scene.py"
# Both processes render the same node trees with the same seed and sample count: measured bit-identical.
REL_TOL, ABS_TOL = 1e-5, 1e-7
DIFFERENT = 0.01   # mean relative difference (1000x the tolerance): a setting changes this picture


@pytest.fixture(scope="module")
def panel(tmp_path_factory):
    """(folder with panel.exr, override.exr, scene.blend; the build's JSON)."""
    d = tmp_path_factory.mktemp("cli_scene")
    p = h.run([SCRIPT, "build", d])
    res = json.loads(p.stdout.strip().splitlines()[-1])
    assert res["add"] == ["FINISHED"], res
    assert res["fogged"] == {"Ground": True, "Wall": False}, f"Selected Only in the panel's flow: {res['fogged']}"
    return d, res


def _cli(panel, out, *flags):
    d, res = panel
    p = h.run(["-m", "fog_addon", "render", d / "scene.blend", "--engine", "cycles",
               "--samples", res["settings"]["samples"], "--pixel-centre", *flags, "--out", d / out])
    return imageio.read_rgb(d / out), p.stdout


def _read(panel, name):
    return imageio.read_rgb(panel[0] / name)


def _assert_same(test, ref, what, stdout):
    assert test.shape == ref.shape, (what, test.shape, ref.shape)
    err = np.abs(test - ref)
    bad = err > REL_TOL * np.abs(ref) + ABS_TOL
    assert not bad.any(), (f"{what}: {int(bad.sum())} of {bad.size} values differ, max abs {err.max():.3g}, "
                           f"max rel {np.max(err / (np.abs(ref) + 1e-12)):.3g}\n--- command output ---\n{stdout}")


def _mean_rel(a, b):
    return float(np.mean(np.abs(a - b)) / np.mean(np.abs(b)))


def test_renders_the_files_fog(panel):
    img, out = _cli(panel, "cli.exr")
    _assert_same(img, _read(panel, "panel.exr"), "command without fog flags vs the panel's render", out)
    line = next(ln for ln in out.splitlines() if ln.startswith("fog: "))
    for setting in ("density 0.06 (file)", "colour (0.9, 0.7, 0.5) (file)", "scene scale 2 (file)",
                    "method auto (file)"):
        assert setting in line, f"{setting!r} not in {line!r}"


def test_density_flag_overrides_the_file(panel):
    density = panel[1]["settings"]["override_density"]
    img, out = _cli(panel, "cli_density.exr", "--density", density)
    override, base = _read(panel, "override.exr"), _read(panel, "panel.exr")
    assert _mean_rel(override, base) > DIFFERENT, "the override density does not change the picture"
    # Only the density changes: colour, scale, Selected Only and the light toggle still come from the file.
    _assert_same(img, override, f"--density {density} vs the panel's render at that density", out)


@pytest.mark.parametrize("flags", [("--color", "1,1,1"), ("--scene-scale", "1")])
def test_colour_and_scale_matter(panel, flags):
    """The command's old defaults (white, scale 1) give another picture here: the test above can tell."""
    img, out = _cli(panel, f"cli_{flags[0][2:]}.exr", *flags)
    assert _mean_rel(img, _read(panel, "panel.exr")) > DIFFERENT, (flags, out)


def test_method_and_light_toggles_from_the_file(panel):
    p = h.run([SCRIPT, "settings", panel[0] / "scene.blend"])
    res = json.loads(p.stdout.strip().splitlines()[-1])
    f = res["file"]
    assert f["lamp_use"] == {"Lamp On": True, "Lamp Off": False}, f
    assert f["selected_only"] is True and f["scene_scale"] == 2.0, f
    assert np.allclose(f["color"], panel[1]["settings"]["color"]), f
    assert res["cycles_file_osl"]["method"] == "osl" and res["cycles_file_osl"]["source"] == "file", res
    eevee = res["eevee_file_osl"]
    assert eevee["method"] == "nodes" and any("EEVEE" in n for n in eevee["notes"]), eevee
    assert res["cycles_flag_nodes"]["method"] == "nodes" and res["cycles_flag_nodes"]["source"] == "flag", res
    assert "needs --engine cycles" in res["eevee_flag_osl"].get("exit", ""), res["eevee_flag_osl"]
