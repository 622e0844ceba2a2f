"""The Compositor method's windows (``precompute/model/footprint.py``, ``nodes/comp_fog.py``) change no pixel:
tests/scenes/compositor_windows.py renders spots at hard cases (the camera inside a cone, a squashed cone
aimed sideways, a 10-degree hard-edged cone, a 170-degree cone animated across the picture, a cone beside the
ground's edge whose beam the ground hides in part) with and without windows, at frames 1 and 5, after a spot
moved and the depsgraph handler's refresh ran, and at frame 5 after it moved again and the frame-change
handler ran.

Measured (one render thread, so both renders sum in the same order; with threads the same comparison
drifted up to 2.5e-6 of the peak, rel RMSE 1.8e-6, from run to run): the pictures agree within 2.1e-7 of the
peak in landscape and 2.5e-6 in portrait (6.5e-9 and 6.4e-7 at 3d21982, before the spot beside the ground's
edge).  With the handler's window update switched off (``comp_fog.set_windows`` a no-op) the moved spot's case
fails: 63 pixels off, up to 0.4 % of the peak; with the frame-change handler's (``apply.grow_windows`` a no-op)
the moved-again case: 12 pixels, up to 0.22 %; with the occluder's window dropping what lies beyond the
ground's plane (``footprint.occluded_window`` returning the near part's window) every case: up to 4.8e-4 of
the peak.

CI's machine gave rel RMSE 1.87e-6 in portrait at frame 1 (max 7.6e-5 of a pixel's value, under 1e-5 of the
peak), the level threads gave here; this machine gives 2.4e-8 (4.0e-8 with Cycles' SSE4.2 kernel), and the
windows keep their pixels when their corners move by up to 1e-9 relative (200 trials).  The cause was not
found here; the bound on the RMSE is TOLERANCE, as on the peak, and every mutation above exceeds it 20-fold."""
import json

import numpy as np
import pytest

from fog_scenes import render_harness as h
from fog_addon import imageio

pytestmark = pytest.mark.render   # every test here starts Blender (bpy) in a subprocess

TOLERANCE = 1e-5   # of the picture's peak: float rounding (the cropped floats pass through colour sockets)


@pytest.fixture(scope="module", params=["landscape", pytest.param("portrait", marks=pytest.mark.slow(
    reason="the default tier renders the landscape case; portrait (another 30 s) in the slow tier"))])
def res(request, tmp_path_factory):
    """The scene's renders; "portrait": odd sizes at 150 %, the sensor fitted vertically, the lens shifted."""
    out = tmp_path_factory.mktemp("windows")
    extra = ["portrait"] if request.param == "portrait" else []
    proc = h.run([h.ROOT / "tests" / "scenes" / "compositor_windows.py", out, *extra], timeout=600)
    assert not h.log_errors(proc.stdout + proc.stderr)
    line = next(ln for ln in proc.stdout.splitlines() if ln.startswith("WINDOWS_JSON "))
    return json.loads(line.split(" ", 1)[1])


@pytest.mark.parametrize("case", ["frame 1", "frame 5", "moved", "moved, frame 5"])
def test_windows_change_no_pixel(res, case):
    name = "windows_" + case.replace(" ", "_").replace(",", "")
    h.assert_close(res["windows"][case], res["whole"][case], name, rel_rmse=TOLERANCE)
    a, b = imageio.read_rgb(res["windows"][case]), imageio.read_rgb(res["whole"][case])
    worst = float(np.abs(a - b).max() / b.max())
    assert worst <= TOLERANCE, (case, worst)


def test_windows_crop(res):
    """The windows are smaller than the picture where they can be: the narrow spot's, the surfaces' (the
    sky above the ground), but not the spot holding the camera; the ground cuts the spots aimed at it."""
    shares = res["shares"]
    assert shares["L000"] == 1.0
    assert shares["L002"] < 0.25 and shares["surfaces"] < 0.8
    print({k: round(v, 4) for k, v in shares.items() if isinstance(v, float)})
    assert shares["L002"] <= 0.5 * shares["L002 plain"] and shares["L004"] < shares["L004 plain"]


def test_grown_windows_are_computed_again_before_saving(res):
    """Windows grown by single frames are marked (saving the file computes them over the range again,
    ``handlers.on_save_pre``); the refresh it runs clears the mark.  (In the portrait picture the moved
    spot stays within its window: nothing grows, nothing is marked.)"""
    shares = res["shares"]
    assert shares["grown"] == shares["grown, frame 5"] == (not res["portrait"])
    assert not shares["saved"]


def test_occluders_are_only_what_ends_every_ray(res):
    """The ground is an occluder as built, and not when it is left out of renders (itself or its collection),
    lets light through, or when the picture holds an unfogged object or a holdout, or with depth of field."""
    cases = res["shares"]["occluders"]
    assert cases.pop("as built") and cases.pop("undone"), cases
    assert not any(cases.values()), cases
