"""A street lamp near the top of a fog layer at night (issue 29: "point and spot lights inside the layer keep their
glows; say what happens at and above the top"): the camera 1.6 m up looks 8 degrees up at a lamp 30 m away, 5 m up,
in a layer 10 m deep (a hard top, or a 6 m top with a 4 m falloff), under a black sky.  Half the picture's rays
leave the layer above the lamp, where the fog's glow must end.

    python -m fog_scenes.lamp_layer OUT.blend [--case hard|falloff] [--fog] [--samples N]

The reference is Cycles' single scattering (volume bounces 0, a white Volume Scatter of density beta(z) in a mesh
box from 1 m below the ground to the layer's top, h0 + 8 H with a falloff, its density graded by a Math node), the
camera's clip start 1 mm, as ``daylight.py``'s.  The add-on's render: ``fog_flags``.  The lamp's own 3 x 3 pixels
are left out of comparisons, as the render tests do.
"""
import argparse
import math
import pathlib
import sys

from . import daylight
from . import render_harness as h

NAME = "lamp_layer"
RESOLUTION = (160, 90)
BETA = 0.05                       # 1/m
LAMP = dict(location=(0.0, 30.0, 5.0), power_w=800.0)
CAMERA = dict(location=(0.0, 0.0, 1.6), pitch_deg=8.0, lens_mm=50.0)
CASES = {"hard": dict(h0=10.0, H=0.0), "falloff": dict(h0=6.0, H=4.0)}
FALLOFF_LENGTHS = 8.0
# (spp, seeds) of each case's reference: the graded density's is noisier (two 1024-spp seeds 5.3 % apart)
REFERENCE_SAMPLES = {"hard": (1024, 2), "falloff": (8192, 2)}
GROUND_ALBEDO = 0.3


def layer(case):
    """dict(beta0, albedo, g, h0, H, box_top) of ``case`` (``daylight.fog_material``'s fields)."""
    c = CASES[case]
    return dict(beta0=BETA, albedo=1.0, g=0.0, h0=c["h0"], H=c["H"], box_top=c["h0"] + FALLOFF_LENGTHS * c["H"])


def fog_flags(case):
    """``python -m fog_addon render``'s flags for the add-on's fog of ``case``, besides ``--density``."""
    f = layer(case)
    return ("--anisotropy", "0.0", "--color", "1.0,1.0,1.0", "--fog-top", repr(f["h0"]), "--height-falloff",
            repr(f["H"]))


def build(scene, case, with_fog=True, samples=1024):
    """Fill ``scene`` (needs bpy): ground, lamp, camera, black World, the fog box if ``with_fog``."""
    import bpy
    from mathutils import Vector
    from demo_scenes import add_box_between, add_camera, add_plane, material, render_settings
    from fog_addon import reference
    render_settings(scene, resolution=RESOLUTION)
    scene.world = bpy.data.worlds.new("Night")
    scene.world.use_nodes = True
    scene.world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
    ground = add_plane(scene, "Ground", -400.0, 400.0, -400.0, 400.0, 0.0,
                       material("Ground", (GROUND_ALBEDO,) * 3, roughness=1.0, specular_ior_level=0.0))
    ld = bpy.data.lights.new("Lamp", 'POINT')
    ld.energy = LAMP["power_w"]
    ld.shadow_soft_size = 0.0
    lamp = bpy.data.objects.new("Lamp", ld)
    lamp.location = LAMP["location"]
    scene.collection.objects.link(lamp)
    loc = Vector(CAMERA["location"])
    p = math.radians(CAMERA["pitch_deg"])
    cam = add_camera(scene, tuple(loc), tuple(loc + Vector((0.0, math.cos(p), math.sin(p)))), lens=CAMERA["lens_mm"])
    cam.data.sensor_width = daylight.SENSOR_WIDTH_MM
    cam.data.clip_start = daylight.CLIP_START_M
    cam.data.clip_end = daylight.CLIP_END_M
    scene.view_settings.view_transform = 'Standard'
    scene.view_settings.look = 'None'
    reference.set_single_scattering_integrator(scene, samples, single_scattering=True)
    ground.visible_shadow = False
    ground.visible_diffuse = ground.visible_glossy = ground.visible_transmission = False
    ground.visible_volume_scatter = False
    if with_fog:
        f = layer(case)
        mat = daylight.layer_material(f)
        ob = add_box_between(scene, daylight.FOG_NAME, -400.0, 400.0, -400.0, 400.0, daylight.FOG_BOX_BOTTOM_M,
                             f["box_top"], mat)
        for attr in ("visible_camera", "visible_shadow", "visible_diffuse", "visible_glossy", "visible_transmission",
                     "visible_volume_scatter"):
            setattr(ob, attr, True)
    scene.render.film_transparent = False
    bpy.context.view_layer.update()
    return scene


def build_scene(path, case, with_fog=True, samples=1024):
    """Save the scene of ``case`` as ``path`` in a fresh Blender process; returns the path."""
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    args = ["-m", "fog_scenes.lamp_layer", path, "--case", case, "--samples", int(samples)]
    if with_fog:
        args.append("--fog")
    h.run(args)
    return path


def reference_name(case, samples, seeds):
    f = layer(case)
    w, hh = RESOLUTION
    return (f"{NAME}_beta{f['beta0']:g}_h{f['h0']:g}_H{f['H']:g}_lamp{LAMP['location'][2]:g}_vb0_{w}x{hh}"
            f"_{int(samples)}spp_x{int(seeds)}.exr")


def render_reference(case, samples=None, seeds=None, regen=False, directory=None, timeout=3600):
    """Path of the cached single-scattering Cycles reference of ``case`` (``REFERENCE_SAMPLES`` unless given),
    rendered if missing (``daylight``'s seed renders and their mean)."""
    samples = samples or REFERENCE_SAMPLES[case][0]
    seeds = seeds or REFERENCE_SAMPLES[case][1]
    directory = pathlib.Path(directory) if directory else h.REFERENCES
    path = directory / reference_name(case, samples, seeds)
    if path.is_file() and not regen:
        return path
    work = pathlib.Path(h._env()["TMPDIR"]) / "fog_lamp_layer"
    blend = work / f"{NAME}_{case}_fog.blend"
    if not blend.is_file():
        build_scene(blend, case, with_fog=True)
    return daylight._render_seeds(blend, path, samples, seeds, True, regen, timeout=timeout)


def lamp_mask():
    """(H, W) bool: True except the lamp's own 3 x 3 pixels (pinhole projection of its position)."""
    import numpy as np
    w, hh = RESOLUTION
    p = math.radians(CAMERA["pitch_deg"])
    fwd = np.array([0.0, math.cos(p), math.sin(p)])
    up = np.array([0.0, -math.sin(p), math.cos(p)])
    right = np.array([1.0, 0.0, 0.0])
    d = np.array(LAMP["location"]) - np.array(CAMERA["location"])
    half = daylight.SENSOR_WIDTH_MM / (2.0 * CAMERA["lens_mm"])
    x = (d @ right) / (d @ fwd) / half * (w / 2.0) + w / 2.0
    y = hh / 2.0 - (d @ up) / (d @ fwd) / half * (w / 2.0)
    keep = np.ones((hh, w), bool)
    c, r = int(math.floor(x)), int(math.floor(y))
    keep[max(r - 1, 0):r + 2, max(c - 1, 0):c + 2] = False
    return keep


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out")
    ap.add_argument("--case", default="hard", choices=sorted(CASES))
    ap.add_argument("--fog", action="store_true")
    ap.add_argument("--samples", type=int, default=1024)
    a = ap.parse_args(argv)
    import bpy
    bpy.ops.wm.read_factory_settings(use_empty=True)
    build(bpy.context.scene, a.case, with_fog=a.fog, samples=a.samples)
    h.save_blend(a.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
