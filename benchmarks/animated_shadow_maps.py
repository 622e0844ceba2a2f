"""What an animation's shadow-map atlases cost (issue 43 item 8, "Farms render animations without the add-on"):
bake time, memory and packed size of the atlas of a moving light's maps (``shadow_maps.ensure_atlases``), against a
still map.

    .venv/bin/python benchmarks/animated_shadow_maps.py [--frames 100] [--scene farm|hall]
                                                        [--light point|spot]

One process, one scene: ``farm`` (tests/scenes/farm_build.py's scene and panel, 295 faces) or ``hall``
(benchmarks/shafts_cost.py's 16 x 16 columns, 1 537 faces, one lamp among the columns); the lamp moves 5 m over
frames 1..N (a spot also turns by 30 degrees).  Prints one JSON line: the add's time (``fog.add``, Compositor method,
shafts on), the atlas's time (``ensure_atlases``: stepping the frames, the casters' BVH and the ray casts of every
frame), a still map's bake for comparison, the atlas's layout, its pixels in memory (16 bytes a texel: float RGBA),
its packed size (ZIP OpenEXR) and Blender's own (uncompressed) packing of the same pixels, the .blend's size (zstd,
Blender's default) and what a copy of the atlas packed Blender's way adds to it, the process's peak memory.
Figures: docs/measurements/2026-11-29-animated-shadow-maps.md.  Smoke mode (``FOG_BENCH_SMOKE=1``,
benchmarks/smoke.py): 3 frames.
"""
import argparse
import json
import math
import os
import pathlib
import resource
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "scenes"))
sys.path.insert(0, str(ROOT / "benchmarks"))

import bpy  # noqa: E402
import numpy as np  # noqa: E402

import smoke  # noqa: E402


def build(kind, light_kind, frames):
    import farm_build as fb
    from demo_scenes import add_box, add_spot_light, material
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    if kind == "farm":
        fb.build(scene)
        add_box(scene, "Screen", *fb.SCREEN, material("Screen", (0.6, 0.6, 0.6), roughness=0.7))
        start = (-2.0, 0.0, 1.6)
    else:
        import shafts_cost
        shafts_cost.hall(scene, 4)
        for o in [o for o in scene.objects if o.type == "LIGHT"][1:]:
            bpy.data.objects.remove(o)
        start = (-3.0, -3.0, 2.0)
    lamps = [o for o in scene.objects if o.type == "LIGHT"]
    if kind == "farm":
        bpy.data.objects.remove(scene.objects[fb.LIGHT_A])
        lamps = [o for o in scene.objects if o.type == "LIGHT"]
    if light_kind == "spot":
        lamp = add_spot_light(scene, "Moving", start, (start[0], start[1] + 2.0, 0.0), 800.0, 50.0, 0.2)
    else:
        from demo_scenes import add_point_light
        lamp = add_point_light(scene, "Moving", start, 300.0)
    scene.render.resolution_x, scene.render.resolution_y = 64, 36
    scene.frame_start, scene.frame_end = 1, frames
    bpy.context.preferences.edit.keyframe_new_interpolation_type = "LINEAR"
    lamp.keyframe_insert("location", frame=1)
    if light_kind == "spot":
        lamp.keyframe_insert("rotation_euler", frame=1)
        lamp.rotation_euler.z += math.radians(30.0)
        lamp.keyframe_insert("rotation_euler", frame=frames)
    lamp.location.x += 5.0
    lamp.keyframe_insert("location", frame=frames)
    scene.frame_set(1)
    return scene, lamp, lamps


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--frames", type=int, default=smoke.pick(100, 3))
    ap.add_argument("--scene", choices=("farm", "hall"), default="farm")
    ap.add_argument("--light", choices=("point", "spot"), default="point")
    args = ap.parse_args()
    import fog_addon
    from fog_addon import shadow_maps
    scene, lamp, _ = build(args.scene, args.light, args.frames)
    fog_addon.register()
    scene.analytic_fog.method = "COMPOSITOR"
    timing = {}
    inner = shadow_maps.ensure_atlases

    def timed(*a, **k):
        t = time.perf_counter()
        try:
            return inner(*a, **k)
        finally:
            timing["atlas_s"] = timing.get("atlas_s", 0.0) + time.perf_counter() - t
    shadow_maps.ensure_atlases = timed
    t = time.perf_counter()
    assert bpy.ops.fog.add(density=0.1) == {"FINISHED"}
    add_s = time.perf_counter() - t
    img = bpy.data.images[shadow_maps.IMAGE_PREFIX + lamp.name]
    atlas = shadow_maps.Atlas(*(int(v) for v in img[shadow_maps.ATLAS]))
    geometry = shadow_maps.scene_bvh(scene)
    t = time.perf_counter()
    still = shadow_maps.bake(lamp, geometry)
    still_s = time.perf_counter() - t
    t = time.perf_counter()
    union = json.loads(img[shadow_maps.LAYOUT])[2]
    union = None if union is None else (tuple(tuple(v) for v in union[0]), union[1])
    shadow_maps._bake_tile(lamp, geometry, union, (atlas.width, atlas.height))
    tile_s = time.perf_counter() - t
    pixels = np.empty(img.size[0] * img.size[1] * 4, np.float32)
    img.pixels.foreach_get(pixels)
    plain = bpy.data.images.new("plain", img.size[0], img.size[1], alpha=True, float_buffer=True, is_data=True)
    plain.pixels.foreach_set(pixels)
    plain.pack()
    raw_pack = plain.packed_file.size
    with tempfile.TemporaryDirectory() as d:   # the .blend (zstd-compressed: Blender's default) with and without
        path = os.path.join(d, "a.blend")       # a copy of the atlas packed Blender's way
        plain.use_fake_user = True
        bpy.ops.wm.save_as_mainfile(filepath=path, copy=True)
        with_plain = os.path.getsize(path)
        bpy.data.images.remove(plain)
        t = time.perf_counter()
        bpy.ops.wm.save_as_mainfile(filepath=path)
        save_s = time.perf_counter() - t
        blend = os.path.getsize(path)
    faces = sum(len(o.data.polygons) for o in scene.objects if o.type == "MESH")
    print(json.dumps({
        "scene": args.scene, "light": args.light, "frames": args.frames, "faces": faces,
        "add_s": round(add_s, 2), "atlas_s": round(timing.get("atlas_s", 0.0), 2),
        "atlas_per_map_s": round(timing.get("atlas_s", 0.0) / shadow_maps.frames_of(scene)[2], 3),
        "still_map_bake_s": round(still_s, 3), "still_map_grid": [still[0].spec.width, still[0].spec.height],
        "tile_bake_s": round(tile_s, 3), "atlas": atlas._asdict(), "atlas_px": list(img.size),
        "atlas_memory_MiB": round(img.size[0] * img.size[1] * 16 / 2 ** 20, 1),
        "per_frame_memory_KiB": atlas.width * atlas.height * 4 / 1024,
        "packed_MiB": round(img.packed_file.size / 2 ** 20, 2), "blender_pack_MiB": round(raw_pack / 2 ** 20, 2),
        "blend_MiB": round(blend / 2 ** 20, 2),
        "blend_blender_pack_extra_MiB": round((with_plain - blend) / 2 ** 20, 2),
        "save_s": round(save_s, 2),
        "peak_rss_MiB": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)}))


if __name__ == "__main__":
    main()
