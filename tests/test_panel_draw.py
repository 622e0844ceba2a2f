"""The panel's draw code, recorded row by row (``tools/panel_picture.Recorder``, the picture in the README): every
setting is drawn, the method's line appears once, and the count of fully modelled lights counts lights."""
import json

import pytest

from fog_scenes import render_harness as h

pytestmark = pytest.mark.render   # starts Blender (bpy) in a subprocess

_CODE = r"""
import json
from tools import panel_picture
rows = panel_picture.record()
print("ROWS " + json.dumps([[kind, "   ".join(parts)] for kind, parts, _ in rows]))
"""


@pytest.fixture(scope="module")
def rows():
    proc = h.run_bpy_code(_CODE)
    assert not h.log_errors(proc.stdout + proc.stderr)
    line = next(ln for ln in proc.stdout.splitlines() if ln.startswith("ROWS "))
    return [text for _, text in json.loads(line.split(" ", 1)[1])]


@pytest.mark.parametrize("setting", ["Visibility", "Density", "Color", "Anisotropy", "Scene Scale", "Fog Top",
                                     "Height Falloff", "Ground Level", "Air", "Method", "Selected Only",
                                     "World Light", "Light Shafts", "Dense Fog", "Fog Passes", "Quality"])
def test_every_setting_is_drawn(rows, setting):
    assert any(r.startswith(setting) for r in rows), rows


def test_the_method_is_said_once_and_lights_are_counted(rows):
    assert sum(r.startswith("Method Auto:") for r in rows) == 1, rows
    assert "1 light(s) fully modelled" in rows and "1 light(s) light the fog" in rows, rows


def test_what_the_picture_lacks_is_listed_first_with_its_share():
    """With Dense Fog and Light Shafts off the panel's Quality box lists what the picture lacks, each with its
    predicted share, the largest first and above the lights (issue 46)."""
    proc = h.run_bpy_code(_CODE.replace("panel_picture.record()", "panel_picture.record(use_multiple_scattering=False, "
                                                                  "use_shafts=False)"))
    assert not h.log_errors(proc.stdout + proc.stderr)
    line = next(ln for ln in proc.stdout.splitlines() if ln.startswith("ROWS "))
    rows = [text for _, text in json.loads(line.split(" ", 1)[1])]
    lacks = [k for k, r in enumerate(rows) if "in the predicted error" in r]
    assert lacks and any("multiple scattering left out" in rows[k] for k in lacks), rows
    shares = [float(r.split("up to ")[1].split("%")[0]) for r in (rows[k] for k in lacks)]
    assert shares == sorted(shares, reverse=True) and shares[0] > 1.0, rows
    quality = next(k for k, r in enumerate(rows) if r.startswith("Quality ") and "predicted error" in r)
    assert quality < lacks[0] < next(k for k, r in enumerate(rows) if "fully modelled" in r), rows
