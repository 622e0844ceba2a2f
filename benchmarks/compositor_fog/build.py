"""The fog's light computed in Blender's compositor (the Compositor method, ``fog_addon/nodes/comp_fog.py``)
on the many-lights scene: timing and pass renders.

    .venv/bin/python benchmarks/compositor_fog/build.py N MODE OUT.exr
MODE: nofog   the many-lights scene without fog;
      ratio   nofog, then comp in the same process (the issue's protocol: fog over no fog, one run);
      (CF_SPOTS=1: every light a spot as in benchmarks/overhead.py --spots; CF_ANISOTROPY=g: the fog's g)
      exact   the fog in the materials (Quality Exact, Fog Passes: the Fog Light AOV is the reference)
              plus the compositor's fog light alone as the Composite (for ``compare.py``);
      comp    the Compositor method as it ships (``apply_fog(method="compositor")``).
Prints one JSON line: render CPU and wall seconds (best of REPS), set-up seconds.
"""
import json
import math
import os
import pathlib
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path[:0] = [str(ROOT), str(ROOT / "tests" / "scenes")]

import bpy  # noqa: E402

import many_lights  # noqa: E402
from fog_addon import measure  # noqa: E402
from fog_addon.nodes import comp_fog, groups, images, passes  # noqa: E402
from fog_addon.ops import apply, view  # noqa: E402
from fog_addon.precompute import rungs  # noqa: E402

W, H, SPP = 320, 180, 16


def light_pixel(scene, light):
    """The light's position in the picture, px from the bottom-left corner (far away behind the camera)."""
    from bpy_extras.object_utils import world_to_camera_view
    p = world_to_camera_view(scene, scene.camera, light.matrix_world.translation)
    w, h = view.render_size(scene)
    return (p.x * w, p.y * h, 0.0) if p.z > 0 else (1e6, 1e6, 0.0)


def write_light_pixels(scene, path):
    """``path``.json: the fog lights' positions in the picture (``light_pixel``), for ``compare.py``."""
    pixels = [light_pixel(scene, o) for o in apply.fog_lights(scene)[0]]
    pathlib.Path(str(path) + ".json").write_text(json.dumps({"light_pixels": pixels}))


def compositor_fog_alone(scene):
    """The scene fogged in its materials (with the fog passes) gets the Compositor method's AOVs and a
    compositor whose Composite is the compositor's fog light alone, to compare with the Fog Light pass.
    Each light gets the models its Quality chose (the stored choice)."""
    lights = apply.fog_lights(scene)[0]
    g = groups.get_anisotropy()
    choice = apply.stored_choice()
    lights, models = zip(*[(o, rungs.choose("nodes", choice["lights"][o.name][0], g, view.is_spot(o)))
                           for o in lights])
    imgs = comp_fog.build_fog_group(scene, lights, models, images.all_table_images(g))
    comp_fog.add_surface_aovs(bpy.data.node_groups[groups.SURFACE])
    passes.add_view_layer_aovs(scene, comp_fog.AOVS)
    tree = bpy.data.node_groups.new("CF Compare", "CompositorNodeTree")
    tree.interface.new_socket("Image", in_out="OUTPUT", socket_type="NodeSocketColor")
    rl = tree.nodes.new("CompositorNodeRLayers")
    node = tree.nodes.new("CompositorNodeGroup")
    node.node_tree = bpy.data.node_groups[comp_fog.FOG_GROUP]
    for sock in node.inputs:
        tree.links.new(rl.outputs[sock.name], sock)
    tree.links.new(node.outputs["Fog Light"], tree.nodes.new("NodeGroupOutput").inputs[0])
    scene.compositing_node_group = tree
    scene.render.use_compositing = True



def _render_best(reps):
    """(min CPU s, min wall s) of ``reps`` renders of the scene to its output file."""
    best = [1e9, 1e9]
    for _ in range(reps):
        c0, w0 = time.process_time(), time.perf_counter()
        bpy.ops.render.render(write_still=True)
        best = [min(best[0], time.process_time() - c0), min(best[1], time.perf_counter() - w0)]
    return best


def main(n, mode, out_path):
    """``mode`` "ratio": the render without fog, then with the compositor's fog (``comp``), in one process."""
    scene, _ = many_lights.build_scene(n, direct_light=True)
    for ob in scene.objects if os.environ.get("CF_SPOTS") == "1" else ():   # as benchmarks/overhead.py --spots
        if ob.type == "LIGHT":
            ob.data.type = "SPOT"
            ob.data.spot_size, ob.data.spot_blend = math.radians(60.0), 0.3
            ob.rotation_euler = (0.0, 0.0, 0.0)   # local -Z: straight down
    scene.render.engine = "CYCLES"
    measure.set_resolution(scene, W, H)
    measure.set_samples(scene, SPP)
    measure.set_cycles_cpu(scene)
    scene.cycles.use_denoising = False
    scene.render.use_persistent_data = False
    bpy.context.view_layer.update()   # matrix_world of the new objects, read below
    measure.configure_output(scene, out_path)
    if mode != "ratio":   # the passes, for compare.py (timing writes only the picture, as a render would)
        scene.render.image_settings.media_type = "MULTI_LAYER_IMAGE"
        scene.render.image_settings.file_format = "OPEN_EXR_MULTILAYER"
    reps = int(os.environ.get("REPS", 2))
    row = {"n": n, "mode": mode}
    if mode in ("nofog", "ratio"):
        row["cpu_nofog"], row["wall_nofog"] = _render_best(reps)
    if mode != "nofog":
        t0 = time.perf_counter()
        apply.apply_fog(scene, many_lights.BETA, albedo=many_lights.ALBEDO, with_passes=mode == "exact",
                        error="exact" if mode == "exact" else "final",
                        method="nodes" if mode == "exact" else "compositor",
                        anisotropy=float(os.environ.get("CF_ANISOTROPY", 0.0)))
        if mode == "exact":
            compositor_fog_alone(scene)
            write_light_pixels(scene, out_path)
        row["setup"] = time.perf_counter() - t0
        row["cpu"], row["wall"] = _render_best(reps)
    if mode == "ratio":
        row["ratio_cpu"], row["ratio_wall"] = row["cpu"] / row["cpu_nofog"], row["wall"] / row["wall_nofog"]
    print(json.dumps(row), flush=True)


if __name__ == "__main__":
    main(int(sys.argv[-3]), sys.argv[-2], sys.argv[-1])
