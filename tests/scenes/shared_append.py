"""Append a fogged object (and world) from fogged file B into fogged scene A; report what arrives, what
``dedupe.merge_duplicates`` makes of it and what a following apply_fog does (JSON).

Usage: python shared_append.py WORKDIR MODE METHOD [render]

MODE: ``append`` (bpy.ops.wm.append of B's "Diffuse Sphere", merged with the
pulled objects removed), ``append_keep`` (the same, pulled objects kept),
``load`` (bpy.data.libraries.load(link=False) of the sphere and B's World).
METHOD: ``nodes`` or ``osl`` (both files).  ``render``: also render A (tiny
Cycles) before the merge, after merge + apply_fog, and with the appended
material re-wrapped natively in A; report the differences.
"""
import json
import sys

from shared_common import bundle_driver_targets, copies, driver_targets, expected_names, fog_groups_of, fog_ids, fog_references, beta

import bpy  # noqa: E402

from demo_scenes import add_camera, add_plane, add_point_light, material, render_settings, set_world, spheres  # noqa: E402
from fog_addon.nodes import dedupe, groups  # noqa: E402
from fog_addon.nodes.material import unwrap_material, wrap_material  # noqa: E402
from fog_addon.ops import apply  # noqa: E402

A_DENSITY, B_DENSITY = 0.05, 0.3
APPENDED = "Diffuse Sphere"        # B's object; its material is "Diffuse"
RENDER_SIZE, RENDER_SAMPLES = (48, 27), 4


def build_b(path, method):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.name = "B"
    spheres.build(scene)
    for coll, old, new in ((bpy.data.objects, "Lamp", "LampB"), (bpy.data.lights, "Lamp", "LampB"),
                           (bpy.data.objects, "Camera", "CameraB")):
        coll[old].name = new
    apply.apply_fog(scene, B_DENSITY, method=method)
    bpy.ops.wm.save_as_mainfile(filepath=path)


def build_a(method):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.name = "A"
    render_settings(scene)
    set_world(scene)
    add_plane(scene, "Floor", -4, 4, -2, 6, -1.0, material("Floor", (0.5, 0.5, 0.5)))
    add_point_light(scene, "LampA", (1.0, -1.5, 2.0), 400.0)
    add_camera(scene, spheres.CAMERA_LOCATION, spheres.CAMERA_TARGET)
    apply.apply_fog(scene, A_DENSITY, method=method)
    return scene


def state(scene):
    ids = fog_ids()
    count, suffixed = copies(ids)
    mat = bpy.data.materials.get("Diffuse")
    return {
        "fog": ids,
        "max_count": max(count.values(), default=0),
        "suffixed": suffixed,
        "suffixed_refs": [r for r in fog_references() if r[1][-4:-3] == "." and r[1][-3:].isdigit()],
        "objects": sorted(o.name for o in bpy.data.objects),
        "scene_objects": sorted(o.name for o in scene.objects),
        "lights": sorted(l.name for l in bpy.data.lights),
        "object_users": {o.name: o.users for o in bpy.data.objects},
        "appended_material_groups": fog_groups_of(mat) if mat else None,
        "surface_drivers": bundle_driver_targets(groups.SURFACE),
        "world_drivers": bundle_driver_targets(groups.WORLD),
        "beta": beta(),
        "light_params": {l.name: sorted(n.node_tree.name for n in l.node_tree.nodes
                                        if n.bl_idname == "ShaderNodeGroup" and n.node_tree)
                         for l in bpy.data.lights if l.node_tree},
    }


def render(scene, workdir, tag):
    from fog_addon import imageio, measure
    scene.render.engine = "CYCLES"
    measure.set_resolution(scene, *RENDER_SIZE)
    measure.set_samples(scene, RENDER_SAMPLES)
    measure.set_cycles_cpu(scene)
    scene.cycles.seed = 0
    out = measure.render_to_file(scene, f"{workdir}/shared_append_{tag}.exr")
    return imageio.read_rgb(out)


def main():
    workdir, mode, method = sys.argv[1:4]
    do_render = "render" in sys.argv[4:]
    b_path = f"{workdir}/B_{method}.blend"
    build_b(b_path, method)
    scene = build_a(method)
    res = {"mode": mode, "method": method, "expect": expected_names(method, scene), "a": state(scene)}
    if mode in ("append", "append_keep"):
        r = bpy.ops.wm.append(filepath=f"{b_path}/Object/{APPENDED}", directory=f"{b_path}/Object/",
                              filename=APPENDED)
        assert r == {"FINISHED"}, r
    else:
        with bpy.data.libraries.load(b_path, link=False) as (src, dst):
            dst.objects = [APPENDED]
            dst.worlds = ["B World"]
        for ob in dst.objects:
            scene.collection.objects.link(ob)
    res["arrived"] = state(scene)
    images = {}
    if do_render:
        images["before_merge"] = render(scene, workdir, "before_merge")
    merged, pulled = dedupe.merge_duplicates(remove_pulled=mode != "append_keep")
    res["merged"], res["pulled"] = merged, pulled
    res["after_merge"] = state(scene)
    res["merge_again"] = dedupe.merge_duplicates(remove_pulled=mode != "append_keep")
    apply.apply_fog(scene, A_DENSITY, method=method)
    res["after_apply"] = state(scene)
    res["expect_after_apply"] = expected_names(method, scene)
    if do_render:
        images["merged"] = render(scene, workdir, "merged")
        mat = bpy.data.materials["Diffuse"]
        unwrap_material(mat)
        assert wrap_material(mat) is None
        images["native"] = render(scene, workdir, "native")
        ref = images["native"]
        scale = float(abs(ref).max())
        res["render"] = {k: float(abs(v - ref).max()) / scale for k, v in images.items()}
    apply.remove_fog(scene)
    apply.apply_fog(scene, A_DENSITY, method=method)
    res["after_remove_add"] = state(scene)
    print(json.dumps(res))


if __name__ == "__main__":
    main()
