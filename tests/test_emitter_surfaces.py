"""A glowing object's fog light on the surfaces around it (the Compositor: ``comp_fog.emitter_fog_light``, each
glowing object a point source at its centre through the point lights' scatter kernel), against Cycles' path-traced
single scattering: a glowing sphere over a grey ground (``tests/scenes/glowing_ground.py``).

The fog light the ground reflects is the reference with one diffuse bounce off the ground less the same with none
(its direct light alone), both committed (``--regen-references`` renders them again, 512 spp); ours is the render
with the term less the same without it.  Over the ground's half of the picture they agree within 10 % (measured
1.076, the reference's noise and the sphere taken as a point); the ground's light against path tracing comes up
from 0.66 (without the term: the light it lacked) to 0.88 (the rest is the glow along the rays far from the sphere).
"""
import numpy as np
import pytest

from fog_addon import imageio
from fog_scenes import render_harness as h

pytestmark = pytest.mark.render

SCENE = h.ROOT / "tests" / "scenes" / "glowing_ground.py"
REFERENCES = {"reference": "glowing_ground.exr", "reference-direct": "glowing_ground_direct.exr"}
REFERENCE_SAMPLES = 512
SAMPLES = 64


def _grey(path):
    return imageio.read_rgb(path).mean(axis=-1)


def test_a_glowing_sphere_lights_the_ground_through_the_fog(tmp_path, regen):
    ref = {}
    for mode, name in REFERENCES.items():
        if regen or not (h.REFERENCES / name).is_file():
            h.run([SCENE, mode, h.REFERENCES / name, REFERENCE_SAMPLES])
        ref[mode] = _grey(h.REFERENCES / name)
    ours = {}
    for mode in ("ours", "ours-without"):
        h.run([SCENE, mode, tmp_path / f"{mode}.exr", SAMPLES])
        ours[mode] = _grey(tmp_path / f"{mode}.exr")
    ground = slice(int(ref["reference"].shape[0] * 0.55), None)   # the rows that see the ground alone
    want = (ref["reference"] - ref["reference-direct"])[ground].sum()
    got = (ours["ours"] - ours["ours-without"])[ground].sum()
    with_term = ours["ours"][ground].mean() / ref["reference"][ground].mean()
    without = ours["ours-without"][ground].mean() / ref["reference"][ground].mean()
    print(f"the ground's fog light: ours / path traced {got / want:.3f}; the ground: {with_term:.3f} "
          f"(without the term {without:.3f})")
    assert got / want == pytest.approx(1.0, abs=0.10)
    assert with_term > without + 0.15
