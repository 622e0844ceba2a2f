"""The Compositor method's fog light beside the node groups' per-sample Fog Light pass, for ``compare.py``
and ``peaks.py``.

    .venv/bin/python benchmarks/compositor_fog/build.py N OUT.exr
The many-lights scene with N lights (320x180, 16 spp, Blender's default pixel filter): the fog in the
materials (Quality Exact, Fog Passes: the Fog Light AOV is the reference) plus the Compositor method's
AOVs and fog group, whose Fog Light is the Composite; a multilayer EXR and OUT.exr.json (the lights'
pixels).  Prints one JSON line: set-up and render seconds.  Smoke mode (``FOG_BENCH_SMOKE=1``,
benchmarks/smoke.py): 32x18 px, 1 spp.  (Its cost: ``benchmarks/overhead.py
--methods cycles_compositor``.)
"""
import json
import pathlib
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))   # a script run by path: the repository root
sys.path.insert(0, str(ROOT / "benchmarks"))

import bpy  # noqa: E402

from fog_scenes import many_lights  # noqa: E402
from fog_addon import measure  # noqa: E402
from fog_addon.nodes import comp_fog, groups, images, passes  # noqa: E402
from fog_addon import view  # noqa: E402
from fog_addon.ops import apply  # noqa: E402
from fog_addon.precompute.model import rungs  # noqa: E402
from fog_scenes.probe_common import light_pixel  # noqa: E402,F401  (peaks.py reads it here)
import smoke  # noqa: E402

W, H, SPP = smoke.pick((320, 180, 16), (32, 18, 1))


def write_light_pixels(scene, path):
    """``path``.json: the fog lights' positions in the picture (``light_pixel``), for ``compare.py``."""
    pixels = [light_pixel(scene, o) for o in apply.fog_lights(scene)[0]]
    pathlib.Path(str(path) + ".json").write_text(json.dumps({"light_pixels": pixels}))


def compositor_fog_alone(scene):
    """The scene fogged in its materials (with the fog passes) gets the Compositor method's AOVs and a
    compositor whose Composite is the compositor's fog light alone, to compare with the Fog Light pass.
    Each light gets the models its Quality chose (the stored choice)."""
    lights = apply.fog_lights(scene)[0]
    g = apply.spec_of(scene).anisotropy
    choice = apply.stored_choice()
    lights, models = zip(*[(o, rungs.choose("nodes", choice["lights"][o.name][0], g, view.light_kind(o)))
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



def main(n, out_path):
    scene, _ = many_lights.build_scene(n, direct_light=True)
    scene.render.engine = "CYCLES"
    measure.set_resolution(scene, W, H)
    measure.set_samples(scene, SPP)
    measure.set_cycles_cpu(scene)
    scene.cycles.use_denoising = False
    bpy.context.view_layer.update()   # matrix_world of the new objects, read below
    measure.configure_output(scene, out_path)
    scene.render.image_settings.media_type = "MULTI_LAYER_IMAGE"
    scene.render.image_settings.file_format = "OPEN_EXR_MULTILAYER"
    t0 = time.perf_counter()
    apply.apply_fog(scene, many_lights.BETA, albedo=many_lights.ALBEDO, with_passes=True, error="exact")
    compositor_fog_alone(scene)
    write_light_pixels(scene, out_path)
    t1 = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    print(json.dumps({"n": n, "setup": t1 - t0, "render": time.perf_counter() - t1}), flush=True)


if __name__ == "__main__":
    main(int(sys.argv[-2]), sys.argv[-1])
