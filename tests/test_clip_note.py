"""EEVEE's clip range (``caveats.clip_note``): beyond clip end / clip start = 1e7 EEVEE's depth fails (a black World,
and with the Compositor method NaN on far ground: a 1 mm to 200 km camera over a valley), so the fog says so."""
from types import SimpleNamespace

import pytest

from fog_addon import caveats


def _scene(engine, start, end):
    cam = SimpleNamespace(type="CAMERA", name="Camera", data=SimpleNamespace(clip_start=start, clip_end=end))
    return SimpleNamespace(render=SimpleNamespace(engine=engine), camera=cam)


def test_a_wide_clip_range_in_eevee_is_said():
    note = caveats.clip_note(_scene("BLENDER_EEVEE", 0.001, 200000.0), "compositor")
    assert note and "Clip Start" in note and "NaN" in note
    assert "NaN" not in caveats.clip_note(_scene("BLENDER_EEVEE", 0.001, 200000.0), "nodes")


@pytest.mark.parametrize("engine,start,end", [("BLENDER_EEVEE", 0.01, 1e5), ("BLENDER_EEVEE", 1.0, 2e5),
                                              ("CYCLES", 0.001, 2e5)])
def test_a_sane_range_or_cycles_says_nothing(engine, start, end):
    assert caveats.clip_note(_scene(engine, start, end), "compositor") is None
