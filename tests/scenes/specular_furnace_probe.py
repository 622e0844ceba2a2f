"""Cycles' own directional albedo of a black Principled BSDF's specular layer (a white furnace).

    python tests/scenes/specular_furnace_probe.py OUT_DIR

A huge plane with a Principled BSDF (base colour black: the specular layer alone, IOR 1.5, IOR Level 0.5)
under a uniform white World of radiance 1, seen by a narrow camera (4x4 px) at the view cosine mu: the
radiance it reflects is the layer's directional albedo E(mu).  Roughness 0.2, 0.45, 0.7; mu 1, 0.5, 0.2,
0.1; 2 048 spp, one bounce.  Prints ``SPECULAR_FURNACE_JSON {"r mu": E}``.
"""
import json
import math
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import bpy  # noqa: E402

from fog_addon import imageio, measure  # noqa: E402
from fog_scenes import probe_common  # noqa: E402

ROUGHNESS = (0.2, 0.45, 0.7)
COS_VIEW = (1.0, 0.5, 0.2, 0.1)


def furnace(roughness, mu, out):
    scene = probe_common.white_furnace((0.0, 0.0, 0.0), roughness)
    cam = bpy.data.objects.new("cam", bpy.data.cameras.new("cam"))
    scene.collection.objects.link(cam)
    scene.camera = cam
    angle = math.acos(mu)
    cam.location = (0.0, -10.0 * math.sin(angle), 10.0 * math.cos(angle))
    cam.rotation_euler = (angle, 0.0, 0.0)
    cam.data.lens = 200.0
    scene.render.engine = "CYCLES"
    measure.set_resolution(scene, 4, 4)
    measure.set_samples(scene, 2048)
    scene.cycles.max_bounces = scene.cycles.glossy_bounces = scene.cycles.diffuse_bounces = 1
    measure.render_to_file(scene, str(out))
    return float(imageio.read_rgb(out).mean())


def main(out_dir):
    res = {f"{r} {mu}": furnace(r, mu, pathlib.Path(out_dir) / "furnace.exr") for r in ROUGHNESS for mu in COS_VIEW}
    print("SPECULAR_FURNACE_JSON " + json.dumps(res))


if __name__ == "__main__":
    main(sys.argv[1])
