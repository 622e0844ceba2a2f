"""Process A of the farm test (WITH the add-on): build a scene, render expectations, save .blend files.

    python farm_build.py nodes OUTDIR    # nofog_cycles.exr, nodes_cycles.exr, nodes_eevee.exr, nodes.blend
    python farm_build.py osl OUTDIR      # nofog_cycles.exr, osl_cycles.exr, osl.blend
    python farm_build.py anim OUTDIR     # anim.blend (the light's position and power and the camera keyframed), then
                                         # expect_<f>.exr: the same scene made STATIC at frame f, fog re-added
    python farm_build.py anim_shafts OUTDIR   # anim_shafts.blend (a lamp moving behind a panel, light shafts), then
                                         # stale_shafts_<f>.exr (frame 1's map) and expect_shafts_<f>.exr (static at f)
    python farm_build.py anim_sun_shafts OUTDIR   # anim_sun_shafts.blend (the ball moving across a sun's light in a
                                         # fog layer), then stale_sun_<f>.exr and expect_sun_<f>.exr, as anim_shafts

The last line of stdout is one JSON object (see tests/test_farm.py).
"""
import os
import pathlib
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import bpy  # noqa: E402

import fog_addon  # noqa: E402
from demo_scenes import add_camera, add_plane, add_point_light, add_sphere, material, set_world  # noqa: E402
from farm_common import ANIM_FRAMES, emit, render_exr, render_settings  # noqa: E402

DENSITY = 0.1   # 1/m: optical thickness about 0.6 from the camera to the sphere

LIGHT_A = "Lamp A"       # moves in the animation: x from -2 (frame 1) to 3 (frame 10)
LIGHT_B = "Lamp B"       # stays put
LIGHT_A_X = {1: -2.0, 10: 3.0}
LIGHT_A_POWER = {1: 150.0, 10: 450.0}   # the intensity drivers must follow too
CAMERA_LOC = {1: (-1.0, -6.0, 1.4), 10: (1.5, -5.0, 2.0)}


def build(scene):
    """A ground plane, a sphere, two point lights, a camera and a dark world."""
    world = set_world(scene)
    # The fog makes the World non-constant, so Cycles' AUTOMATIC world sampling builds a
    # 2048x1024 importance map by evaluating the whole fog World shader there (measured 37 s of
    # a 37.5 s render here; 0.4 s with this 64 map, same picture to 1e-5).  A small MANUAL map
    # keeps the test fast and still has Cycles build and sample one in both processes.
    world.cycles.sampling_method = "MANUAL"
    world.cycles.sample_map_resolution = 64
    world.probe_resolution = "128"   # EEVEE's world probe (default 1024): 9 s -> 5 s per EEVEE render here
    ground = material("Ground", (0.5, 0.5, 0.5), roughness=0.8, specular_ior_level=0.2)
    ball = material("Ball", (0.8, 0.3, 0.2), roughness=0.4, specular_ior_level=0.5)
    add_plane(scene, "Ground", -6.0, 6.0, -3.0, 8.0, 0.0, ground)
    add_sphere(scene, "Ball", (0.3, 1.0, 0.7), 0.7, ball, segments=24, rings=12)
    add_point_light(scene, LIGHT_A, (-1.5, 0.0, 1.6), 300.0)
    b = add_point_light(scene, LIGHT_B, (1.8, 2.0, 1.3), 200.0)
    b.data.color = (1.0, 0.8, 0.6)
    add_camera(scene, (0.0, -6.0, 1.5), (0.0, 1.0, 0.6), lens=30.0)
    render_settings(scene, "CYCLES")
    return scene


def packed_report():
    return {img.name: img.packed_file is not None for img in bpy.data.images if img.type == "IMAGE"}


def timed(log, name, fn, *args):
    t = time.perf_counter()
    out = fn(*args)
    log[name] = round(time.perf_counter() - t, 2)
    return out


def nodes(outdir):
    """The fog by the operator (method nodes): Cycles and EEVEE expectations, then nodes.blend."""
    log = {}
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = build(bpy.context.scene)
    timed(log, "nofog_cycles", render_exr, scene, os.path.join(outdir, "nofog_cycles.exr"))
    fog_addon.register()
    scene.analytic_fog.method = "NODES"   # (Auto would pick the compositor: its own lanes below)
    assert bpy.ops.fog.add(density=DENSITY) == {"FINISHED"}
    timed(log, "nodes_cycles", render_exr, scene, os.path.join(outdir, "nodes_cycles.exr"))
    render_settings(scene, "BLENDER_EEVEE")
    timed(log, "nodes_eevee", render_exr, scene, os.path.join(outdir, "nodes_eevee.exr"))
    render_settings(scene, "CYCLES")
    packed = packed_report()
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(outdir, "nodes.blend"))
    emit({"packed": packed, "render_s": log})


def osl(outdir, method="osl", engine="CYCLES", dense=False):
    """The fog by apply_fog(method=``method``: "osl" or "compositor") in ``engine`` (EEVEE: the compositor
    only): expectation, then <method>.blend (EEVEE: <method>_eevee.blend); ``dense``: Dense Fog on (its table
    packed like the others): <method>_dense.blend."""
    from fog_addon.ops import apply
    log = {}
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = build(bpy.context.scene)
    tag = "cycles" if engine == "CYCLES" else "eevee"
    render_settings(scene, engine)
    timed(log, f"nofog_{tag}", render_exr, scene, os.path.join(outdir, f"nofog_{tag}.exr"))
    fog_addon.register()
    skipped = apply.apply_fog(scene, DENSITY, method=method, albedo=(0.9, 0.9, 0.9) if dense else (1.0, 1.0, 1.0),
                              anisotropy=0.85 if dense else 0.0, multiple_scattering=dense)
    label = f"{method}_dense" if dense else method
    timed(log, f"{label}_{tag}", render_exr, scene, os.path.join(outdir, f"{label}_{tag}.exr"))
    packed = packed_report()
    name = f"{label}.blend" if engine == "CYCLES" else f"{label}_{tag}.blend"
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(outdir, name))
    emit({"packed": packed, "skipped": skipped, "shading_system_osl": bool(scene.cycles.shading_system),
          "render_s": log})


def add_daylight(scene):
    """A light-blue sky and a sun 40 degrees up (strength 3), as the daylight lanes have them."""
    import math
    bg = next(n for n in scene.world.node_tree.nodes if n.bl_idname == "ShaderNodeBackground")
    bg.inputs["Color"].default_value = (0.35, 0.5, 0.8, 1.0)
    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
    sun.data.energy = 3.0
    sun.rotation_euler = (math.radians(50.0), 0.0, math.radians(-50.0))
    scene.collection.objects.link(sun)
    return sun


def daylight(outdir):
    """The scene under a sun (40 degrees, strength 3) and a light-blue sky, in a fog layer 3 m deep with a falloff
    of 1 m above it (the Compositor method): expectation, then daylight.blend (the fog light's map packed, the
    sun and the sky followed by simple-expression drivers)."""
    from fog_addon.ops import apply
    from fog_addon.precompute.core.spec import FogSpec
    log = {}
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = build(bpy.context.scene)
    add_daylight(scene)
    timed(log, "nofog_cycles", render_exr, scene, os.path.join(outdir, "nofog_cycles.exr"))
    fog_addon.register()
    skipped = apply.apply(scene, FogSpec(density=DENSITY, albedo=(0.9, 0.9, 0.9), method="compositor",
                                         fog_top=3.0, height_falloff=1.0))
    timed(log, "daylight_cycles", render_exr, scene, os.path.join(outdir, "daylight_cycles.exr"))
    packed = packed_report()
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(outdir, "daylight.blend"))
    emit({"packed": packed, "skipped": skipped, "render_s": log})


def _key(idb, path, frames_values, index=-1):
    """Keyframe ``idb.path`` (or its component ``index``) with {frame: value} (linear interpolation)."""
    bpy.context.preferences.edit.keyframe_new_interpolation_type = "LINEAR"
    for f, v in frames_values.items():
        if index >= 0:
            getattr(idb, path)[index] = v
        else:
            setattr(idb, path, v)
        idb.keyframe_insert(path, index=index, frame=f)


def anim(outdir, method="NODES"):
    """anim.blend: one light moving (and its power animated), the camera moving; then the expectations.
    ``method``: the panel's Method the fog is added with."""
    log = {}
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = build(bpy.context.scene)
    scene.frame_start, scene.frame_end = 1, 10
    lamp, cam = scene.objects[LIGHT_A], scene.camera
    _key(lamp, "location", LIGHT_A_X, index=0)
    _key(lamp.data, "energy", LIGHT_A_POWER)
    _key(cam, "location", CAMERA_LOC)
    fog_addon.register()
    scene.analytic_fog.method = method
    # this file tests the drivers and windows alone (the moving lamp's shafts: ``anim_shafts``, an atlas of its maps)
    scene.analytic_fog.use_shafts = False
    # and Dense Fog off: its field's scale beside the ground is one value for the whole animation
    # (``escape.field_scales``: the mean over the sampled frames), where each static expectation takes its own pose's
    scene.analytic_fog.use_multiple_scattering = False
    assert bpy.ops.fog.add(density=DENSITY) == {"FINISHED"}
    scene.frame_set(1)
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(outdir, "anim.blend"))

    # The state at each frame, then the same scene without animation, posed as at that frame.
    states = {}
    for f in ANIM_FRAMES:
        scene.frame_set(f)
        dg = bpy.context.evaluated_depsgraph_get()
        states[f] = {ob.name: ob.evaluated_get(dg).matrix_world.copy() for ob in (lamp, cam)}
        states[f]["power"] = lamp.data.evaluated_get(dg).energy
    for idb in (lamp, cam, lamp.data):
        idb.animation_data_clear()
    poses = {}
    for f in ANIM_FRAMES:
        for ob in (lamp, cam):
            ob.matrix_world = states[f][ob.name]
        lamp.data.energy = states[f]["power"]
        scene.frame_current = f
        assert bpy.ops.fog.add(density=DENSITY) == {"FINISHED"}   # re-add the fog on the static scene
        poses[f] = {"lamp": list(lamp.matrix_world.translation), "camera": list(cam.matrix_world.translation),
                    "power": lamp.data.energy}
        timed(log, f"expect_{f}", render_exr, scene, os.path.join(outdir, f"expect_{f}.exr"))
    emit({"packed": packed_report(), "poses": poses, "render_s": log})


def render_stale(scene, atlas, frames, prefix, log, outdir):
    """The stale farm: ``frames`` rendered (``<prefix>_<f>.exr``) with frame 1's map at every frame (the atlas's
    first tile copied into each channel and slot: what a farm rendered before the atlas), the add-on's frame
    handler held off; the atlas then restored."""
    import numpy as np
    from fog_addon import shadow_maps
    px = np.empty(atlas.size[0] * atlas.size[1] * 4, np.float32)
    atlas.pixels.foreach_get(px)
    w, h = int(atlas[shadow_maps.ATLAS][5]), int(atlas[shadow_maps.ATLAS][6])
    first = px.reshape(atlas.size[1], atlas.size[0], 4)[:h, :w, 0]
    stale = np.repeat(np.tile(first, (atlas.size[1] // h, atlas.size[0] // w))[..., None], 4, axis=-1)
    saved = px.copy()
    atlas.pixels.foreach_set(stale.ravel())
    atlas.update()
    handlers = list(bpy.app.handlers.frame_change_post)
    bpy.app.handlers.frame_change_post.clear()   # (the add-on's frame handler would bake the frame's map again)
    for f in frames:
        scene.frame_set(f)
        timed(log, f"{prefix}_{f}", render_exr, scene, os.path.join(outdir, f"{prefix}_{f}.exr"))
    bpy.app.handlers.frame_change_post.extend(handlers)
    atlas.pixels.foreach_set(saved)
    atlas.update()


SHAFT_FRAMES = (1, 5, 8)   # the frames the moving shafts are rendered at (tests/test_farm.py)
SHAFT_RES = (64, 36)
SCREEN = ((0.3, -0.45, 1.3), (0.6, 0.03, 1.0))   # (centre, half extents) m: a panel Lamp A passes 0.45 m behind


def anim_shafts(outdir):
    """anim_shafts.blend: the farm scene with a panel before the path of Lamp A, which moves behind it and the ball
    over frames 1..10, with light shafts (the Compositor method, 64 x 36): the saved file holds an atlas of the lamp's
    shadow maps at every frame, picked by a driver on the frame.  Then the expectations expect_shafts_<f>.exr: the
    scene made static at frame f (the add-on bakes the lamp's map at its pose, at the full resolution of a still map,
    as its frame handler did for each frame) for f in SHAFT_FRAMES, and stale_shafts_<f>.exr: frame f rendered with
    the map of frame 1 (what a farm rendered before the atlas: the map of the frame the file was saved at)."""
    from demo_scenes import add_box
    from fog_addon import shadow_maps
    log = {}
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = build(bpy.context.scene)
    add_box(scene, "Screen", *SCREEN, material("Screen", (0.6, 0.6, 0.6), roughness=0.7))
    scene.render.resolution_x, scene.render.resolution_y = SHAFT_RES
    scene.frame_start, scene.frame_end = 1, 10
    lamp = scene.objects[LIGHT_A]
    _key(lamp, "location", LIGHT_A_X, index=0)
    fog_addon.register()
    scene.analytic_fog.method = "COMPOSITOR"
    scene.analytic_fog.use_shafts = True
    scene.analytic_fog.use_multiple_scattering = False   # (one Dense Fog scale per animation: see ``anim``)
    scene.frame_set(1)
    t = time.perf_counter()
    assert bpy.ops.fog.add(density=DENSITY) == {"FINISHED"}
    log["add_s"] = round(time.perf_counter() - t, 2)
    atlas = bpy.data.images[shadow_maps.IMAGE_PREFIX + LIGHT_A]
    still = bpy.data.images[shadow_maps.IMAGE_PREFIX + LIGHT_B]
    info = {"atlas": list(atlas.get(shadow_maps.ATLAS, [])), "atlas_size": list(atlas.size),
            "atlas_packed_bytes": atlas.packed_file.size, "still_size": list(still.size),
            "still_packed_bytes": still.packed_file.size, "still_atlas": shadow_maps.ATLAS in still}
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(outdir, "anim_shafts.blend"))
    packed = packed_report()

    render_stale(scene, atlas, SHAFT_FRAMES, "stale_shafts", log, outdir)

    # the add-on's frame f: the lamp still at its pose, its map baked there
    states = {}
    for f in SHAFT_FRAMES:
        scene.frame_set(f)
        states[f] = lamp.matrix_world.copy()
    lamp.animation_data_clear()
    poses = {}
    for f in SHAFT_FRAMES:
        lamp.matrix_world = states[f]
        scene.frame_current = f
        # removed first: a fog added again for the same lights keeps its groups and maps (a still light's map is baked
        # when the groups are built, and at frame changes while something moves)
        assert bpy.ops.fog.remove() == {"FINISHED"}
        assert bpy.ops.fog.add(density=DENSITY) == {"FINISHED"}
        img = bpy.data.images[shadow_maps.IMAGE_PREFIX + LIGHT_A]
        assert shadow_maps.ATLAS not in img and tuple(img.size) == (1024, 512), (f, tuple(img.size))
        poses[f] = {"lamp": list(lamp.matrix_world.translation)}
        timed(log, f"expect_shafts_{f}", render_exr, scene, os.path.join(outdir, f"expect_shafts_{f}.exr"))
    emit({"packed": packed, "poses": poses, "render_s": log, "maps": info})


SUN_SHAFT_FRAMES = (1, 5, 8)   # the frames the sun's moving shafts are rendered at (tests/test_farm.py)
BALL_X = {1: -1.2, 10: 2.2}      # the ball's x: it crosses the sun's light before the camera
SUN_CAMERA_LOC = {1: (0.0, -6.0, 1.5), 10: (0.6, -5.6, 1.7)}


def anim_sun_shafts(outdir):
    """anim_sun_shafts.blend: the daylight lane's scene (a sun at 40 degrees in a fog layer 3 m deep), the ball
    moving across the sunlight and the camera moving over frames 1..10, keyed after the fog was added, with light
    shafts (the Compositor method, 64 x 36): the save bakes an atlas of the sun's maps at every frame into the file,
    picked by a driver on the frame.  Then
    expect_sun_<f>.exr: the scene made static at f (the sun's map baked at the pose, a still map's full resolution)
    and stale_sun_<f>.exr: frame f with frame 1's map at every frame (what a farm rendered before the atlas)."""
    from fog_addon import shadow_maps
    log = {}
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = build(bpy.context.scene)
    scene.render.resolution_x, scene.render.resolution_y = SHAFT_RES
    add_daylight(scene)
    scene.frame_start, scene.frame_end = 1, 10
    ball, cam = scene.objects["Ball"], scene.camera
    fog_addon.register()
    settings = scene.analytic_fog
    settings.method, settings.use_fog_top, settings.fog_top, settings.height_falloff = "COMPOSITOR", True, 3.0, 1.0
    settings.color = (0.9, 0.9, 0.9)
    settings.use_multiple_scattering = False   # (one Dense Fog scale per animation: see ``anim``)
    t = time.perf_counter()
    assert bpy.ops.fog.add(density=DENSITY) == {"FINISHED"}
    log["add_s"] = round(time.perf_counter() - t, 2)
    # animated after the fog was added, as an artist does: the handler's rebuild keeps this frame's map (it does not
    # step through frames), and the file's save bakes the atlas of every frame's
    _key(ball, "location", BALL_X, index=0)
    _key(cam, "location", SUN_CAMERA_LOC)
    bpy.context.view_layer.update()
    scene.frame_set(1)
    info = {"before_save_atlas": shadow_maps.ATLAS in bpy.data.images[shadow_maps.SUN_IMAGE]}
    t = time.perf_counter()
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(outdir, "anim_sun_shafts.blend"))
    log["save_s"] = round(time.perf_counter() - t, 2)
    atlas = bpy.data.images[shadow_maps.SUN_IMAGE]
    info.update(atlas=list(atlas.get(shadow_maps.ATLAS, [])), atlas_size=list(atlas.size),
                atlas_packed_bytes=atlas.packed_file.size)
    packed = packed_report()

    render_stale(scene, atlas, SUN_SHAFT_FRAMES, "stale_sun", log, outdir)

    # the add-on's frame f: the ball and the camera still at their poses, the sun's map baked there
    states = {}
    for f in SUN_SHAFT_FRAMES:
        scene.frame_set(f)
        states[f] = (ball.matrix_world.copy(), cam.matrix_world.copy())
    for ob in (ball, cam):
        ob.animation_data_clear()
    poses = {}
    for f in SUN_SHAFT_FRAMES:
        ball.matrix_world, cam.matrix_world = states[f]
        scene.frame_current = f
        assert bpy.ops.fog.remove() == {"FINISHED"}
        assert bpy.ops.fog.add(density=DENSITY) == {"FINISHED"}
        img = bpy.data.images[shadow_maps.SUN_IMAGE]
        assert shadow_maps.ATLAS not in img, f
        poses[f] = {"ball": list(ball.matrix_world.translation), "still_size": list(img.size)}
        timed(log, f"expect_sun_{f}", render_exr, scene, os.path.join(outdir, f"expect_sun_{f}.exr"))
    emit({"packed": packed, "poses": poses, "render_s": log, "maps": info})


if __name__ == "__main__":
    mode, outdir = sys.argv[1], sys.argv[2]
    {"nodes": nodes, "osl": osl, "anim": anim, "compositor": lambda out: osl(out, "compositor"),
     "compositor_eevee": lambda out: osl(out, "compositor", "BLENDER_EEVEE"),
     "dense": lambda out: osl(out, "compositor", dense=True), "daylight": daylight,
     "anim_compositor": lambda out: anim(out, "COMPOSITOR"), "anim_shafts": anim_shafts,
     "anim_sun_shafts": anim_sun_shafts}[mode](outdir)
