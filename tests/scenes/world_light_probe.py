"""The World's light on surfaces through the fog (``shading.shade_background``'s ``world_light``).

    python tests/scenes/world_light_probe.py OUT_DIR [CASE ...]

A white Lambertian plane under a uniform white World (radiance 1), no lamps, seen straight down from
2 m (4x4 px at pixel centres).  Without fog it reflects radiance 1 (a white furnace).  Fogged at
beta = 0.2 1/m, World Light off: the fog fills all space, so the World's light never reaches the plane
(0, as under Cycles' World volume); on: the plane keeps it, seen through e^{-beta 2 m}.  Rendered in
Cycles (nodes and OSL) and EEVEE (CASE: cycles_nodes, cycles_osl, blender_eevee_nodes; default all);
prints ``WORLD_LIGHT_JSON {...}``: the mean radiance per case and the pixels' mean e^{-beta D}.
"""
import json
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import bpy  # noqa: E402
import numpy as np  # noqa: E402

from fog_addon import imageio, measure  # noqa: E402
from fog_addon.ops import apply  # noqa: E402
from fog_scenes import probe_common  # noqa: E402

BETA, HEIGHT, SIZE = 0.2, 2.0, 4


def build():
    scene = probe_common.white_furnace((1.0, 1.0, 1.0), 1.0, specular_ior_level=0.0, size=200.0)
    cam = probe_common.look_at(scene, (0.0, 0.0, HEIGHT), (0.0, 0.0, 0.0), 50.0)
    return scene, cam


def render(scene, engine, out):
    probe_common.tiny_render(scene, engine, SIZE, SIZE)
    scene.cycles.max_bounces = scene.cycles.diffuse_bounces = 1
    measure.set_samples(scene, 1024 if engine == "CYCLES" else 16)
    measure.render_to_file(scene, str(out))
    return float(imageio.read_rgb(out).mean())


CASES = (("CYCLES", "nodes"), ("CYCLES", "osl"), ("BLENDER_EEVEE", "nodes"))


def main(out_dir, *cases):
    out_dir = pathlib.Path(out_dir)
    res = {}
    for engine, method in CASES:
        key = f"{engine.lower()}_{method}"
        if cases and key not in cases:
            continue
        scene, cam = build()
        _, d = probe_common.camera_rays(cam, SIZE, SIZE)
        res["transmittance"] = float(np.mean(np.exp(-BETA * HEIGHT / np.abs(d[..., 2]))))
        res[f"{key}_no_fog"] = render(scene, engine, out_dir / f"{key}_none.exr")
        for on in (False, True):
            apply.apply_fog(scene, BETA, method=method, world_light=on)
            res[f"{key}_world_light_{'on' if on else 'off'}"] = render(scene, engine, out_dir / f"{key}_{on}.exr")
    print("WORLD_LIGHT_JSON " + json.dumps(res))


if __name__ == "__main__":
    main(*sys.argv[1:])
