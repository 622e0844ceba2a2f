"""The sun's shafts in a fog layer end to end (issue 29, "its shadows in the fog ... come from the light-shaft
machinery"): the city of ``fog_scenes/daylight.py`` under a low sun (12 degrees, 10 W/m^2, ahead and to the right,
every surface casting shadows: case ``hard_g0.7_inside_low``), rendered with the analytic fog layer and its shafts
against Cycles' path-traced single scattering in a mesh box of fog (volume bounces 0), shadows in it.

Goal (the issue's daylight accuracy): <= 3 % relative RMSE in Cycles, <= 6 % in EEVEE.  Without the shafts the same
render is further off (``test_without_shafts_the_street_is_too_bright``: the test can fail).  Figures:
docs/measurements/2026-11-27-sun-shafts.md.
"""
import numpy as np
import pytest

from fog_addon import imageio
from fog_addon.compare import metrics
from fog_scenes import daylight as dl
from fog_scenes import render_harness as h

pytestmark = pytest.mark.render

CASE = "hard_g0.7_inside_low"
BOUND = {"cycles": 0.03, "eevee": 0.06}
SAMPLES = 64
REFERENCE_SAMPLES = 4096   # per seed, 2 seeds: the mean's noise 1.3 % (1024: 2.6 %, most of the bound)


def _render(tmp_path, engine, shafts="on", case=CASE):
    case = dl.as_case(case)
    f = dl.layer(case)
    blend = tmp_path / f"{dl.case_name(case)}.blend"
    dl.build_scene(str(blend), case, with_fog=False)
    log = []
    out = h.render_test("daylight", f["beta0"], tmp_path / f"ours_{shafts}.exr", engine=engine, method="compositor",
                        resolution=dl.RESOLUTION, blend=str(blend), log=log, cast_shadows=True,
                        samples=SAMPLES if engine == "cycles" else None,
                        extra=dl.fog_flags(case) + ("--shafts", shafts))
    assert not h.log_errors(log[0]), h.log_errors(log[0])
    return out, log[0]


# {case: reference seeds}: the falloff's reference takes 4 (its noise 1.2 %; with 2 it was 1.7 % and the case read
# 3.18 %, most of the rest the sky's occlusion by the buildings, which the fog does not model: the measurement page)
CASES = {CASE: 2, "falloff_g0.7_inside_low": 4, "hard_g0.7_above_low": 2}


@pytest.mark.parametrize("case", [CASE, pytest.param("falloff_g0.7_inside_low", marks=pytest.mark.slow),
                                  pytest.param("hard_g0.7_above_low", marks=pytest.mark.slow)])
def test_sun_shafts_against_cycles(tmp_path, case):
    out, log = _render(tmp_path, "cycles", case=case)
    assert "its shafts in the fog come from a map" in log, log
    ours = imageio.read_rgb(out)
    assert np.isfinite(ours).all()
    ref = dl.render_reference(case, samples=REFERENCE_SAMPLES, seeds=CASES[case])
    m = h.assert_close(out, ref, name=f"sun_shafts_{case}", rel_rmse=BOUND["cycles"])
    print(f"\n{case} cycles: relative RMSE {m['rel_rmse']:.4f}")


@pytest.mark.slow
def test_sun_shafts_in_eevee(tmp_path):
    """EEVEE with the Compositor: within its goal, and the shafts take its picture closer to the reference than the
    same render without them."""
    ref = imageio.read_rgb(dl.render_reference(CASE, samples=REFERENCE_SAMPLES, seeds=2))
    errors = {}
    for shafts in ("on", "off"):
        out, log = _render(tmp_path, "eevee", shafts)
        ours = imageio.read_rgb(out)
        assert np.isfinite(ours).all()
        errors[shafts] = metrics(ours, ref)["rel_rmse"]
    print(f"\n{CASE} eevee: relative RMSE shafts on {errors['on']:.4f}, off {errors['off']:.4f}")
    assert errors["on"] <= BOUND["eevee"] and errors["on"] < errors["off"], errors


@pytest.mark.slow
def test_without_shafts_the_street_is_too_bright(tmp_path):
    """Shafts off: the fog in the buildings' shadows glows as if lit, beyond the bound the shafts meet."""
    out, log = _render(tmp_path, "cycles", shafts="off")
    assert "Light Shafts are off" in log, log
    ref = dl.render_reference(CASE, samples=REFERENCE_SAMPLES, seeds=2)
    m = metrics(imageio.read_rgb(out), imageio.read_rgb(ref))
    print(f"\n{CASE} cycles, shafts off: relative RMSE {m['rel_rmse']:.4f}")
    assert m["rel_rmse"] > BOUND["cycles"], m
