"""Glass panes and spot lights in Cycles' SVM (Node Groups): what the fogged glass material costs SVM's stack.

    python tests/scenes/glass_svm.py OUT.exr [SPOTS] [POINTS]

A ground, a glossy sphere and two panes facing the camera: a Glass BSDF (``Glass``: its tails past the pane,
``glass_tails.place_tails``) and a Principled BSDF of Transmission 1 (``Trans``), roughness 0 both; SPOTS spot
lights (default 1) and POINTS point lights (default 0) above the sphere, fog added by ``apply.apply_fog`` with
Quality Exact, g = 0.85; 16 x 12 px, 1 sample, enough bounces for the panes' paths.  Cycles' debug log is turned
on (``fog_scenes.cycles_debug_log``): its "Peak stack usage" lines, after RENDER_START, give each shader's peak.
Prints ``GLASS_SVM {...}``: per object hit by the pixel centres' rays (``sky`` for none) its pixel count, black
pixels, median and max of R + G + B.

Before the tails were a closure each (``glass_tails.build_tail_bundle``) one spot took the Glass material to 255
floats (out of SVM stack space): the pane rendered black.
"""
import json
import math
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import bpy  # noqa: E402, I001
import bmesh  # noqa: E402 (after bpy: a module of Blender's)
import numpy as np  # noqa: E402

from fog_addon import measure  # noqa: E402
from fog_addon.ops import apply  # noqa: E402
from fog_scenes import cycles_debug_log  # noqa: E402
from fog_scenes.probe_common import glass_material, mesh_object  # noqa: E402
from fog_scenes.probe_common import camera_rays, look_at  # noqa: E402

WIDTH, HEIGHT = 16, 12
PANES = {"Glass": (-1.0, -4.0, 1.5), "Trans": (1.0, -4.0, 1.5)}   # centres, 1.2 m square, facing the camera


def _principled(name, base, rough, **inputs):
    mat = bpy.data.materials.new(name)
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*base, 1.0)
    bsdf.inputs["Roughness"].default_value = rough
    for key, value in inputs.items():
        bsdf.inputs[key].default_value = value
    return mat


def _glass_bsdf(name):
    return glass_material(name)




def build(spots=1, points=0):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    look_at(scene, (0.0, -9.0, 2.5), (0.0, 0.0, 1.2), 30.0)
    mesh_object(scene, "Ground", lambda bm: bmesh.ops.create_grid(bm, x_segments=1, y_segments=1, size=30.0),
          _principled("Ground", (0.4, 0.4, 0.4), 0.8))
    mesh_object(scene, "Glossy", lambda bm: bmesh.ops.create_uvsphere(bm, u_segments=24, v_segments=12, radius=1.0),
          _principled("Glossy", (0.2, 0.4, 0.8), 0.2), (0.0, 0.0, 1.0))
    mats = {"Glass": _glass_bsdf("Glass"),
            "Trans": _principled("Trans", (1.0, 1.0, 1.0), 0.0, **{"Transmission Weight": 1.0})}
    for name, where in PANES.items():
        mesh_object(scene, name, lambda bm: bmesh.ops.create_grid(bm, x_segments=1, y_segments=1, size=0.6), mats[name],
              where, (math.pi / 2, 0.0, 0.0))
    n = spots + points
    for i in range(n):
        kind = "SPOT" if i < spots else "POINT"
        data = bpy.data.lights.new(f"L{i:03d}", kind)
        data.energy = 1000.0
        if kind == "SPOT":
            data.spot_size, data.spot_blend = math.radians(60.0), 0.2
        ob = bpy.data.objects.new(f"L{i:03d}", data)
        # a generic pose (no axis-aligned rows that Cycles would fold into constants), the cone on the sphere
        ob.location = (-1.5 + 3.0 * i / max(n - 1, 1), 2.5, 3.0)
        ob.rotation_euler = (math.radians(-35.0), 0.0, math.radians(10.0))
        scene.collection.objects.link(ob)
    scene.world = bpy.data.worlds.new("World")
    scene.world.node_tree.nodes["Background"].inputs["Color"].default_value = (0, 0, 0, 1)
    scene.render.engine = "CYCLES"
    measure.set_resolution(scene, WIDTH, HEIGHT)
    measure.set_samples(scene, 1)
    measure.set_cycles_cpu(scene)
    measure.set_pixel_centre_filter(scene)
    c = scene.cycles
    c.volume_bounces, c.diffuse_bounces, c.glossy_bounces, c.transmission_bounces = 0, 1, 2, 4
    c.max_bounces = 7
    c.use_denoising = False
    return scene


def object_stats(scene, img):
    """{object name or 'sky': {n, black, median, max}} of R + G + B over the pixels whose centre ray hits it."""
    dg = bpy.context.evaluated_depsgraph_get()
    origin, d = camera_rays(scene.camera, WIDTH, HEIGHT)
    names = np.empty((HEIGHT, WIDTH), dtype=object)
    for j in range(HEIGHT):
        for i in range(WIDTH):
            hit, _, _, _, ob, _ = scene.ray_cast(dg, tuple(origin), tuple(d[j, i]))
            names[j, i] = ob.name if hit else "sky"
    total = img.sum(-1)
    return {name: {"n": int((names == name).sum()), "black": int((total[names == name] <= 0.0).sum()),
                   "median": float(np.median(total[names == name])), "max": float(total[names == name].max())}
            for name in sorted(set(names.ravel()))}


def main(out, spots=1, points=0):
    scene = build(int(spots), int(points))
    apply.apply_fog(scene, 0.1, anisotropy=0.85, method="nodes", error=None, shafts=False)
    debug = cycles_debug_log.enable()
    print("RENDER_START", flush=True)
    measure.render_to_file(scene, out)
    print("RENDER_END", flush=True)
    img = bpy.data.images.load(str(out), check_existing=False)
    px = np.array(img.pixels[:], dtype=np.float32).reshape(HEIGHT, WIDTH, 4)[::-1, :, :3]   # row 0 = top
    print("GLASS_SVM " + json.dumps({"debug_log": debug, "objects": object_stats(scene, px)}), flush=True)


if __name__ == "__main__":
    main(*sys.argv[1:])
