"""Headless renders of the demo scenes with the analytic fog against cached Cycles path-traced references.

References: tests/references/<scene>_<density>.exr (tests/render_harness.py;
regenerate with --regen-references).  Cast shadows and surface-to-surface
light are off in both renders (the model has neither); pixel-centre sampling.
A failing comparison writes tests/_failures/<case>_diff.png.

Bounds (issue: relative RMSE <= 3 % Cycles, <= 5 % EEVEE at optical thickness
up to 2), at the default densities (street lamps beta = 0.08, T = 1.6 to the
farthest lamp; spheres beta = 0.15, T = 1.05) and in thinner fog.  Measured
(README): Cycles 0.5-1.0 %, EEVEE 0.6-2.2 %.
"""
import pytest

import render_harness as h

THICK = [("street_lamps", 0.08), ("spheres", 0.15)]
THIN = [("street_lamps", 0.03), ("spheres", 0.05)]


def _case(tmp_path, regen, scene, density, engine, method="nodes"):
    ref = h.ensure_reference(scene, density, regen)
    out = h.render_test(scene, density, str(tmp_path / f"{scene}_{engine}_{method}.exr"), engine=engine,
                        method=method)
    return out, ref


@pytest.mark.parametrize("scene,density", THICK)
def test_cycles_nodes(tmp_path, regen, scene, density):
    out, ref = _case(tmp_path, regen, scene, density, "cycles")
    h.assert_close(out, ref, f"{scene}_{density}_cycles", rel_rmse=0.03, mean_ratio_tol=0.01)


@pytest.mark.parametrize("scene,density", THIN)
def test_cycles_nodes_thin(tmp_path, regen, scene, density):
    out, ref = _case(tmp_path, regen, scene, density, "cycles")
    h.assert_close(out, ref, f"{scene}_{density}_cycles", rel_rmse=0.03, mean_ratio_tol=0.01)


@pytest.mark.parametrize("scene,density", THICK)
def test_cycles_osl(tmp_path, regen, scene, density):
    out, ref = _case(tmp_path, regen, scene, density, "cycles", "osl")
    h.assert_close(out, ref, f"{scene}_{density}_cycles_osl", rel_rmse=0.03, mean_ratio_tol=0.01)


@pytest.mark.parametrize("scene,density", THICK + THIN)
def test_eevee_nodes(tmp_path, regen, scene, density):
    out, ref = _case(tmp_path, regen, scene, density, "eevee")
    h.assert_close(out, ref, f"{scene}_{density}_eevee", rel_rmse=0.05, mean_ratio_tol=0.02)
