"""The World's light through the fog (``shading.shade_background``): extinguished by default, as Cycles'
World volume extinguishes it, kept when the artist asks (``apply_fog(world_light=True)``, the panel's
World Light, ``render --world-light on``)."""
import json

import pytest

from fog_scenes import render_harness as h

pytestmark = pytest.mark.render   # every test here starts Blender (bpy) in a subprocess


@pytest.mark.parametrize("cases", [("cycles_nodes", "blender_eevee_nodes"), pytest.param(
    ("cycles_osl",), marks=pytest.mark.slow(reason="the OSL method's 1 024 samples; the World's term is shared"))])
def test_world_light_is_extinguished_unless_kept(tmp_path, cases):
    """A white plane under a white World, no lamps (tests/scenes/world_light_probe.py): radiance 1 without
    fog; fogged, exactly 0 with World Light off and e^{-beta D} with it on, in Cycles (nodes, OSL) and EEVEE.
    Measured: Cycles 1.0 / 0.0 / 0.6598 against e^{-beta D} 0.6598; EEVEE 0.990 / 0.0 / 0.653."""
    proc = h.run([h.ROOT / "tests" / "scenes" / "world_light_probe.py", tmp_path, *cases], timeout=600)
    line = next(ln for ln in proc.stdout.splitlines() if ln.startswith("WORLD_LIGHT_JSON "))
    res = json.loads(line.split(" ", 1)[1])
    print(res)
    for key in cases:
        lit = res[f"{key}_no_fog"]
        assert abs(lit - 1.0) < 0.02, (key, res)
        assert res[f"{key}_world_light_off"] == 0.0, (key, res)
        assert abs(res[f"{key}_world_light_on"] / (lit * res["transmittance"]) - 1.0) < 0.01, (key, res)
