"""The command line refuses what it can't do with a clear message and a non-zero exit."""
import pytest

from fog_scenes import render_harness as h

pytestmark = pytest.mark.render   # every test here starts Blender (bpy) in a subprocess


@pytest.mark.parametrize("flags,message", [
    (["--engine", "eevee", "--method", "osl", "--density", "0.1"], "needs --engine cycles"),
    (["--engine", "cycles", "--preset", "smog"], "unknown preset"),
    (["--engine", "cycles", "--density", "nan"], "density"),
    (["--engine", "cycles", "--anisotropy", "0.96", "--density", "0.1"], "anisotropy"),
    (["--engine", "cycles", "--method", "nodes", "--anisotropy", "-0.9", "--density", "0.1"], "use the OSL method"),
    (["--engine", "cycles", "--error", "2"], "--error must be a fraction"),
    (["--engine", "cycles", "--error", "best"], "--error must be a fraction"),
])
def test_render_refuses(tmp_path, flags, message):
    blend = h.scene_blend("spheres", tmp_path)
    out = tmp_path / "out.png"
    r = h.run(["-m", "fog_addon", "render", blend, *flags, "--out", out], check=False)
    assert r.returncode != 0 and message in (r.stdout + r.stderr), (r.returncode, r.stdout[-500:], r.stderr[-500:])
    assert not out.exists()


def test_render_explains_the_models(tmp_path):
    """``--explain`` prints each light's models and the predicted error; ``--error`` sets the Quality."""
    blend = h.scene_blend("street_lamps", tmp_path)
    out = tmp_path / "out.png"
    r = h.run(["-m", "fog_addon", "render", blend, "--engine", "cycles", "--samples", "1", "--resolution", "32x18",
               "--error", "0.5", "--explain", "--out", out], check=False)
    text = r.stdout + r.stderr
    assert r.returncode == 0, text[-2000:]
    lines = [line for line in text.splitlines() if line.startswith("models: ")]
    assert lines[0].startswith("models: Quality 0.5: predicted error"), lines
    assert lines[1].startswith("models:   Method Auto: "), lines   # the method Auto chose, and why
    # the three lamps, Dense Fog left out for those it adds little to (at a target of 50 %), what Dense Fog adds
    # beyond the ground's (the lamps stand over it), then their posts' shafts (the street's posts shadow the glows)
    assert all(": " in line for line in lines[2:5]), lines
    rest = lines[5:]
    optional = ("models:   multiple scattering scaled for the surfaces near ", "models:   Dense Fog left out for ")
    rest = [line for line in rest if not line.startswith(optional)]
    assert len(rest) == 1 and rest[0].startswith("models:   Light shafts of "), lines
    assert "quality 0.5 (flag)" in text


def test_render_writes_the_fog_passes_into_a_multilayer_exr(tmp_path):
    """``--passes --out X.exr`` writes a multilayer EXR holding the fog's two passes beside the picture (it wrote R,
    G, B and A only before): the Fog Light pass is not black where the fog glows, and the transmittance lies in
    [0, 1], above 0 on the spheres."""
    import numpy as np
    from fog_addon import imageio
    blend = h.scene_blend("spheres", tmp_path)
    out = tmp_path / "out.exr"
    r = h.run(["-m", "fog_addon", "render", blend, "--engine", "cycles", "--samples", "1", "--resolution", "32x18",
               "--density", "0.1", "--passes", "--out", out], check=False)
    assert r.returncode == 0, (r.stdout + r.stderr)[-2000:]
    names = imageio.channels(out)
    light = [c for c in names if "Fog Light" in c.name]
    trans = [c for c in names if "Fog Transmittance" in c.name]
    assert len(light) >= 3 and trans, [c.name for c in names]
    values = imageio.read_channels(out, light[:3] + trans[:1])
    assert np.isfinite(values).all()
    assert values[..., :3].max() > 0.0, "the Fog Light pass is black"
    t = values[..., 3]   # (0 where the sky is seen through fog that fills all space)
    assert 0.0 <= t.min() and 0.0 < t.max() <= 1.0 + 1e-6, "the transmittance leaves [0, 1] or is 0 everywhere"
