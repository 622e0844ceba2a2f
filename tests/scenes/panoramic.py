"""Two lamps over a floor seen by an equirectangular camera, fogged (Node Groups or Compositor, Cycles) or
path-traced.

    python tests/scenes/panoramic.py MODE OUT.exr [SAMPLES] [METHOD]

MODE: ``reference`` (Cycles' World volume, Volume Scatter white of density BETA, single scattering), ``fog`` (the
add-on's fog with METHOD, default ``compositor``) or ``none``.  Writes OUT.exr.

An equirectangular camera (the whole sphere, 128 x 64 px) 1.5 m over a grey Lambertian floor 40 m wide; two
point lamps, 100 W white at 3 m to one side and 60 W warm 2.5 m away on another, both above the floor, so
nothing casts a shadow into the fog (the floor lies below them).  The picture holds the lamps' glows, the floor
dimmed and lit by the fog, and the sky through the fog in every direction: a panoramic camera's rays, which the
Compositor reads per pixel from the render (``comp_fog.add_world_aovs``).  Traps of blender-facts.md: Volume
Scatter white, clip start 1 mm, pixel centres (Gaussian 0.01 px).
"""
import math
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import bpy  # noqa: E402

from fog_addon import measure  # noqa: E402
from fog_scenes import probe_common  # noqa: E402

BETA = 0.12          # 1/m
WIDTH, HEIGHT = 128, 64
LAMPS = [((3.0, 1.0, 2.5), 100.0, (1.0, 1.0, 1.0)), ((-1.5, -2.0, 2.0), 60.0, (1.0, 0.7, 0.4))]


def build():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    cam = probe_common.look_at(scene, (0.0, 0.0, 1.5), (0.0, 1.0, 1.5), 35.0)
    cam.data.type = "PANO"
    cam.data.panorama_type = "EQUIRECTANGULAR"
    cam.data.clip_end = 1000.0
    scene.world = bpy.data.worlds.new("World")
    scene.world.use_nodes = True
    scene.world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    floor = probe_common.bsdf_material("Floor", "ShaderNodeBsdfDiffuse", Color=(0.5, 0.5, 0.5, 1.0))

    def plane(bm):
        s = 20.0
        verts = [bm.verts.new(v) for v in ((-s, -s, 0.0), (s, -s, 0.0), (s, s, 0.0), (-s, s, 0.0))]
        bm.faces.new(verts)
    probe_common.mesh_object(scene, "Floor", plane, floor)
    probe_common.add_point_lights(scene, LAMPS, fog_only=False)
    return scene


def configure(scene, samples):
    measure.set_resolution(scene, WIDTH, HEIGHT)
    measure.set_samples(scene, samples)
    scene.cycles.max_bounces = scene.cycles.diffuse_bounces = 1   # the fog's light on the floor (Eq. 17)
    scene.cycles.glossy_bounces = scene.cycles.transmission_bounces = 0
    scene.cycles.volume_bounces = 0


def main(mode, out, samples=None, method="compositor"):
    scene = build()
    probe_common.set_up_mode(scene, mode, BETA, samples, configure)
    if mode == "fog":
        probe_common.add_fog(scene, BETA, method)
    measure.render_to_file(scene, str(pathlib.Path(out)))


if __name__ == "__main__":
    main(*sys.argv[1:])
