"""The Compositor method's windows (``precompute/model/footprint.py``) change no pixel: renders with them against
renders without them (every term over the whole picture), the same scene, frame and settings.

    python tests/scenes/compositor_windows.py OUT_DIR [portrait]

The many-lights scene with four spots set to hard cases: one whose cone holds the camera, one aimed sideways
with a non-uniform scale, a 10-degree cone with no blend, a 170-degree cone animated across the picture over
frames 1-5 (the windows hold the whole range); and a fifth just beyond the ground's right edge (the ground
narrowed to 12 m, its edges in the picture, and cut into 4 x 4 faces) aimed down past it: the ground hides the
beam below its plane only where the ground is in front (the ground is an occluder:
``footprint.occluded_window``). Renders (Cycles, 1 spp, Gaussian filter at pixel centres): frame 1 and frame
5, then frame 1 again after a spot moved and ``apply.refresh_lights`` ran as the depsgraph handler runs it
(this frame only), and at frame 5 after it moved again and the frame-change handler ran
(``apply.grow_windows``), each with and without windows; then whether the windows were marked grown
(``comp_fog.windows_partial``) and are no longer after the refresh that saving a file runs. Writes the
pictures as EXR and prints one line ``WINDOWS_JSON {...}``: the pictures' paths by case and each window's
share of the picture, and each spot's without occluders ("<name> plain"). ``portrait``: the same at 41 x 73 px
at 150 % (odd sizes), the sensor fitted vertically, the lens shifted.
"""
import json
import math
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import bpy  # noqa: E402

from fog_scenes import many_lights  # noqa: E402
from fog_addon import measure  # noqa: E402
from fog_addon.nodes import comp_fog  # noqa: E402
from fog_addon import view  # noqa: E402
from fog_addon.methods.compositor import has_fog_surface, lets_nothing_through  # noqa: E402
from fog_addon.ops import apply  # noqa: E402
from fog_addon.precompute.model import footprint  # noqa: E402

BETA = 0.1
PORTRAIT = "portrait" in sys.argv
W, H = (61, 109) if PORTRAIT else (96, 54)   # the render's pixels


def build():
    import bmesh   # (after bpy)
    scene, _ = many_lights.build_scene(4, direct_light=True)
    spots = sorted((o for o in scene.objects if o.type == "LIGHT"), key=lambda o: o.name)
    for o in spots:
        o.data.type = "SPOT"
        o.data.spot_size, o.data.spot_blend = math.radians(60.0), 0.3
    cam = scene.camera.matrix_world.translation
    spots[0].location = (cam.x + 0.5, cam.y + 6.0, cam.z + 0.5)   # aimed back at the camera: it is in the cone
    spots[0].rotation_euler = (math.radians(-90.0), 0.0, 0.0)
    spots[1].rotation_euler = (0.0, math.radians(80.0), 0.3)      # sideways, squashed
    spots[1].scale = (1.0, 0.3, 1.0)
    spots[2].data.spot_size, spots[2].data.spot_blend = math.radians(10.0), 0.0
    spots[3].data.spot_size = math.radians(170.0)
    edge = bpy.data.objects.new("L004", bpy.data.lights.new("L004", "SPOT"))
    edge.data.energy, edge.data.spot_size, edge.data.spot_blend = 400.0, math.radians(40.0), 0.2
    edge.location = (6.5, 8.0, 1.5)
    ground = scene.objects["ground"]
    ground.scale.x = 0.2   # x in [-6, 6] m, of 4 x 4 faces: the occluder is its outline (footprint.flat_outline)
    bm = bmesh.new()
    bm.from_mesh(ground.data)
    bmesh.ops.subdivide_edges(bm, edges=bm.edges[:], cuts=3, use_grid_fill=True)
    bm.to_mesh(ground.data)
    bm.free()
    scene.collection.objects.link(edge)
    spots.append(edge)
    for frame, x in ((1, -6.0), (5, 6.0)):
        spots[3].location.x = x
        spots[3].keyframe_insert("location", index=0, frame=frame)
    scene.frame_start, scene.frame_end = 1, 5
    scene.frame_set(1)
    scene.render.engine = "CYCLES"
    measure.set_resolution(scene, W, H)
    if PORTRAIT:
        measure.set_resolution(scene, 41, 73)
        scene.render.resolution_percentage = 150
        scene.camera.data.sensor_fit = "VERTICAL"
        scene.camera.data.shift_x, scene.camera.data.shift_y = 0.13, -0.07
    measure.set_samples(scene, 1)
    measure.set_cycles_cpu(scene)
    scene.cycles.use_denoising = False
    scene.cycles.pixel_filter_type = "GAUSSIAN"
    scene.cycles.filter_width = 0.01
    scene.render.threads_mode, scene.render.threads = "FIXED", 1   # the same float sums in both renders
    im = scene.render.image_settings
    im.file_format, im.color_depth, im.color_mode = "OPEN_EXR", "32", "RGB"
    return scene, spots


def render(scene, path):
    scene.render.filepath = str(path)
    bpy.ops.render.render(write_still=True)
    return str(path)


def run(out, windowed):
    scene, spots = build()
    tag = "windows" if windowed else "whole"
    if not windowed:   # every term over the whole picture: the groups built without windows
        view.windows = lambda *args, **kwargs: None
        view.full_windows = lambda lights: None
    apply.apply_fog(scene, BETA, method="compositor", shafts=False)   # the windows alone
    paths = {"frame 1": render(scene, out / f"{tag}_f1.exr")}
    scene.frame_set(5)
    paths["frame 5"] = render(scene, out / f"{tag}_f5.exr")
    scene.frame_set(1)
    spots[2].location.x -= 4.0   # the narrow spot moves and turns: the handler's refresh (this frame) grows its window
    spots[2].rotation_euler = (0.0, 0.3, 0.0)
    bpy.context.view_layer.update()
    apply.refresh_lights(scene, this_frame=True)
    paths["moved"] = render(scene, out / f"{tag}_moved.exr")
    flags = {"grown": comp_fog.windows_partial()}
    spots[2].location.x += 8.0   # moved again, then the frame changes: the frame-change handler grows the windows
    scene.frame_set(5)
    if windowed:   # (without windows there are none to grow)
        apply.grow_windows(scene)
    paths["moved, frame 5"] = render(scene, out / f"{tag}_moved_f5.exr")
    lights = sorted((o for o in scene.objects if o.type == "LIGHT"), key=lambda o: o.name)
    shares = None
    if windowed:   # what saving the file does with grown windows (handlers.on_save_pre): over the range again
        flags["grown, frame 5"] = comp_fog.windows_partial()
        apply.refresh_lights(scene)
        flags["saved"] = comp_fog.windows_partial()
        shares = flags
        surfaces, glows = view.windows(scene, lights, fogged=has_fog_surface, opaque=lets_nothing_through)
        shares.update({"surfaces": _share(surfaces), **{o.name: _share(g) for o, g in zip(lights, glows)}})
        found, view.occluders = view.occluders, lambda *args: []   # the windows without occluders
        plain = view.windows(scene, lights, fogged=has_fog_surface, opaque=lets_nothing_through)[1]
        shares.update({o.name + " plain": _share(g) for o, g in zip(lights, plain)})
        view.occluders = found
        shares["occluders"] = occluder_cases(scene)
    return paths, shares


def occluder_cases(scene):
    """{case: the ground is among ``view.occluders``}: as built, then with each change that must take it (or
    every occluder) away, undone after: the ground left out of renders (itself or its collection), its
    material letting light through (Alpha), an unfogged object in the picture, a holdout, depth of field."""
    import numpy as np

    def ground_found():
        depsgraph = bpy.context.evaluated_depsgraph_get()
        cam = scene.camera.evaluated_get(depsgraph)
        mw = np.array(cam.matrix_world)
        faces = view.occluders(depsgraph, cam, mw, view.frame_extent(scene, cam), view.occlusion_margin(scene),
                               has_fog_surface, lets_nothing_through)
        return any(np.abs(face[:, 2]).max() < 1e-6 and len(face) == 4 for face, _ in faces)

    ground = scene.objects["ground"]
    out = {"as built": ground_found()}
    bsdf = next(n for n in ground.active_material.node_tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
    folder = bpy.data.collections.new("Hidden")
    scene.collection.children.link(folder)
    cube = bpy.data.objects.new("Unfogged", bpy.data.meshes.new("Unfogged"))
    cube.data.from_pydata([(0, 5, 1), (1, 5, 1), (1, 6, 1)], [], [(0, 1, 2)])
    cube.data.materials.append(bpy.data.materials.new("Unfogged"))

    def toggle(case, on):
        if case == "hidden in renders":
            ground.hide_render = on
        elif case == "collection hidden in renders":
            (folder.objects.link if on else folder.objects.unlink)(ground)
            (scene.collection.objects.unlink if on else scene.collection.objects.link)(ground)
            folder.hide_render = on
        elif case == "alpha":
            bsdf.inputs["Alpha"].default_value = 0.5 if on else 1.0
        elif case == "unfogged object":
            (scene.collection.objects.link if on else scene.collection.objects.unlink)(cube)
        elif case == "holdout":
            scene.objects["matte"].is_holdout = on
        elif case == "depth of field":
            scene.camera.data.dof.use_dof = on
        bpy.context.view_layer.update()

    for case in ("hidden in renders", "collection hidden in renders", "alpha", "unfogged object", "holdout",
                 "depth of field"):
        toggle(case, True)
        out[case] = ground_found()
        toggle(case, False)
    out["undone"] = ground_found()
    return out


def _share(win):
    x, y, w, h = footprint.pixels(win, W, H)
    return w * h / (W * H)


def main():
    out = pathlib.Path(sys.argv[1])
    out.mkdir(parents=True, exist_ok=True)
    windowed, shares = run(out, True)
    whole, _ = run(out, False)
    print("WINDOWS_JSON " + json.dumps({"windows": windowed, "whole": whole, "shares": shares, "portrait": PORTRAIT}),
          flush=True)


if __name__ == "__main__":
    main()
