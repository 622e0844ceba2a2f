"""EEVEE's clip range (``caveats.clip_note``): beyond clip end / clip start = 1e7 EEVEE's depth fails (a black World;
a 1 mm to 200 km camera over a valley drew no ground plane, and the Compositor method's fog took those pixels for
sky), so the fog says so, with the Clip Start that would do."""
from types import SimpleNamespace

import numpy as np
import pytest

from fog_addon import caveats


def _scene(engine, start, end):
    cam = SimpleNamespace(type="CAMERA", name="Camera", data=SimpleNamespace(clip_start=start, clip_end=end))
    return SimpleNamespace(render=SimpleNamespace(engine=engine), camera=cam)


def test_a_wide_clip_range_in_eevee_is_said():
    note = caveats.clip_note(_scene("BLENDER_EEVEE", 0.001, 200000.0), "compositor")
    assert note and "raise Clip Start to 0.02 or more" in note and "ground plane" in note and "sky's" in note
    assert "NaN" not in note
    nodes = caveats.clip_note(_scene("BLENDER_EEVEE", 0.001, 200000.0), "nodes")
    assert "ground plane" in nodes and "sky's" not in nodes


@pytest.mark.parametrize("engine,start,end", [("BLENDER_EEVEE", 0.01, 1e5), ("BLENDER_EEVEE", 1.0, 2e5),
                                              ("BLENDER_EEVEE", float(np.float32(0.02)), 2e5),   # Clip Start as stored
                                              ("CYCLES", 0.001, 2e5)])
def test_a_sane_range_or_cycles_says_nothing(engine, start, end):
    assert caveats.clip_note(_scene(engine, start, end), "compositor") is None
