"""EEVEE's direct light through fog on a glossy street lit by a near and a far lamp (issue 8).

EEVEE ignores light node trees, so each material's direct light is dimmed by
one average of the lights' e^(-beta D_sp) (``shading.shade_point``'s weight).
Against the Cycles path-traced reference (cast shadows and interreflection
off), as the other render tests.
"""
import pytest

from fog_scenes import render_harness as h

pytestmark = pytest.mark.render   # every test here starts Blender (bpy) in a subprocess

SCENE, DENSITY = "glossy_lamps", 0.08
SAMPLES = 4096   # the reference's own noise: see the README


def test_eevee_glossy_two_lamps(tmp_path, regen):
    ref = h.ensure_reference(SCENE, DENSITY, regen, samples=SAMPLES)
    out = h.render_test(SCENE, DENSITY, str(tmp_path / "eevee.exr"), engine="eevee")
    m = h.assert_close(out, ref, f"{SCENE}_{DENSITY}_eevee", rel_rmse=0.05, mean_ratio_tol=0.02)
    print(f"EEVEE relative RMSE {m['rel_rmse']:.4f}")


def test_cycles_glossy_two_lamps(tmp_path, regen):
    ref = h.ensure_reference(SCENE, DENSITY, regen, samples=SAMPLES)
    # 128 spp: the glossy street's own direct light (multiscatter GGX) is noisy at 16 spp (3.6 % there,
    # 2.1 % at 256 spp); the fog is noise-free at any count
    out = h.render_test(SCENE, DENSITY, str(tmp_path / "cycles.exr"), engine="cycles", samples=128)
    # mean 1.1 % low: the fog light reflected by the glossy street (Phong stand-in for GGX, view-independent
    # albedo) is too dark at grazing angles (a Schlick-at-view-angle albedo only moved it 3.6 -> 3.5 % at 16 spp)
    m = h.assert_close(out, ref, f"{SCENE}_{DENSITY}_cycles", rel_rmse=0.03, mean_ratio_tol=0.015)
    print(f"Cycles relative RMSE {m['rel_rmse']:.4f}")
