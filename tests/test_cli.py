"""The command line refuses what it can't do with a clear message and a non-zero exit."""
import pytest

import render_harness as h


@pytest.mark.parametrize("flags,message", [
    (["--engine", "eevee", "--method", "osl", "--density", "0.1"], "needs --engine cycles"),
    (["--engine", "cycles", "--preset", "smog"], "unknown preset"),
    (["--engine", "cycles", "--density", "nan"], "density"),
    (["--engine", "cycles", "--anisotropy", "0.5", "--density", "0.1"], "anisotropy"),
])
def test_render_refuses(tmp_path, flags, message):
    blend = h.scene_blend("spheres", tmp_path)
    out = tmp_path / "out.png"
    r = h.run(["-m", "fog_addon", "render", blend, *flags, "--out", out], check=False)
    assert r.returncode != 0 and message in (r.stdout + r.stderr), (r.returncode, r.stdout[-500:], r.stderr[-500:])
    assert not out.exists()
