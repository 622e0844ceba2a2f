"""A glowing sphere over a grey ground in fog, nothing else: the glowing object's fog light on the ground (the
Compositor method's ``comp_fog.emitter_fog_light``) against Cycles' path-traced fog.

    python tests/scenes/glowing_ground.py MODE OUT.exr SAMPLES [SHAPE]
        (MODE: reference | reference-direct | ours | ours-without | ours-one-point | viewport;
         SHAPE: sphere | bar)

An emissive UV sphere (Emission, white, STRENGTH W/(m^2 sr), radius RADIUS m) HEIGHT m over a grey Lambertian
ground (base colour 0.5, roughness 1, Specular IOR Level 0), a camera looking down at it; World black, no lamp.
SHAPE ``bar``: a glowing bar BAR m long and BAR_WIDTH thick across the view instead (a neon tube).
``reference``: Cycles' World volume (Volume Scatter, white, density BETA; volume bounces 0: single scattering, the
ground's light of the fog through one diffuse bounce; clip start 1 mm); ``reference-direct``: the same without the
bounce, so the ground has its direct light alone (the difference is the fog light it reflects).  ``ours``: the
add-on's fog (the Compositor method, Dense Fog off, no shafts), as F12 renders it; ``ours-without``: the same with
the glowing object's fog light on surfaces left out (what the method rendered before it); ``ours-one-point``: each
glowing object one point, not cut along its length (``methods.compositor.EMITTER_PIECES`` 1); ``viewport``: the
add-on's fog as the rendered viewport shows it (``preview.forced``, compositing off: the preview's glowing objects
sampled as points along each, ``methods.compositor.sampled_points``).
"""
import math
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

sys.path.insert(0, str(pathlib.Path(__file__).parent))

import bpy  # noqa: E402
import glowing_preview  # noqa: E402  (its glowing sphere and the references' World fog)

from fog_addon import measure  # noqa: E402

BETA = 0.2
STRENGTH = 60.0
RADIUS = 0.15
HEIGHT = 1.0
RES = (96, 54)
BAR, BAR_WIDTH, BAR_STRENGTH = 2.4, 0.08, 30.0


def build(shape="sphere"):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    glowing = glowing_preview.add_glowing_sphere(RADIUS, (0, 0, HEIGHT), STRENGTH)
    if shape == "bar":   # the sphere's material on a box along x
        bpy.ops.mesh.primitive_cube_add(size=1.0, location=(0, 0, HEIGHT))
        bar = bpy.context.active_object
        bar.scale = (BAR, BAR_WIDTH, BAR_WIDTH)
        bar.data.materials.append(glowing.data.materials[0])
        glowing.data.materials[0].node_tree.nodes["Emission"].inputs["Strength"].default_value = BAR_STRENGTH
        bpy.data.objects.remove(glowing)
    bpy.ops.mesh.primitive_plane_add(size=60.0, location=(0, 0, 0))
    ground = bpy.context.active_object
    ground.name = "Ground"
    grey = bpy.data.materials.new("Grey")
    grey.use_nodes = True
    bsdf = grey.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (0.5, 0.5, 0.5, 1.0)
    bsdf.inputs["Roughness"].default_value = 1.0
    bsdf.inputs["Specular IOR Level"].default_value = 0.0
    ground.data.materials.append(grey)
    cam = bpy.data.cameras.new("Camera")
    cam.lens, cam.clip_start = 28.0, 0.001
    camera = bpy.data.objects.new("Camera", cam)
    scene.collection.objects.link(camera)
    scene.camera = camera
    camera.location, camera.rotation_euler = (0.0, -5.0, 3.0), (math.radians(62.0), 0.0, 0.0)
    scene.world = bpy.data.worlds.new("World")
    scene.render.engine = "CYCLES"
    measure.set_cycles_cpu(scene)
    scene.render.resolution_x, scene.render.resolution_y = RES
    scene.cycles.use_denoising = False
    scene.cycles.pixel_filter_type, scene.cycles.filter_width = "BOX", 0.01
    return scene


def reference(scene):
    glowing_preview.world_fog(scene, BETA)
    c = scene.cycles
    c.volume_bounces, c.max_bounces, c.diffuse_bounces, c.glossy_bounces = 0, 2, 1, 1


def main(mode, out, samples, shape="sphere"):
    scene = build(shape)
    scene.cycles.samples = samples
    if mode.startswith("reference"):
        reference(scene)
        if mode == "reference-direct":   # no bounce off the ground: its direct light alone, no fog light
            scene.cycles.diffuse_bounces = 0
        measure.render_to_file(scene, out)
        return
    import fog_addon
    from fog_addon.methods import compositor
    from fog_addon.ops import apply
    from fog_addon.precompute.core.spec import FogSpec
    fog_addon.register()
    if mode == "ours-without":   # (the fog light on surfaces alone: the points' far glows stay)
        from fog_addon.nodes import comp_fog
        fog_light = comp_fog.emitter_fog_light
        comp_fog.emitter_fog_light = lambda m, *args: m.scale(fog_light(m, *args), 0.0)
    if mode == "ours-one-point":
        compositor.EMITTER_PIECES = 1
    apply.apply(scene, FogSpec(density=BETA, method="compositor", shafts=False, multiple_scattering=False))
    if mode == "viewport":
        from fog_addon.nodes import preview
        scene.render.use_compositing = False
        with preview.forced():
            measure.render_to_file(scene, out)
        return
    measure.render_to_file(scene, out)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], int(sys.argv[3]), *sys.argv[4:5])
