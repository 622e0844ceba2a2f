"""A glowing sphere and a lamp in fog, no other surface: the viewport preview's glow of a glowing object (the
Compositor method's ``sampled_points``) against Cycles' path-traced fog.

    python tests/scenes/glowing_preview.py MODE OUT.exr SAMPLES      (MODE: reference | preview)

An emissive UV sphere (Emission, white, STRENGTH W/(m^2 sr), radius RADIUS m) at the origin, a point lamp of
LAMP_W watts at LAMP_AT (the preview holds it one by one, so that it exists), a camera 6 m away on -Y looking at the
sphere; World black.  ``reference``: Cycles' World volume (Volume Scatter, white, density BETA; volume bounces 0:
single scattering; clip start 1 mm), the lamp and the sphere lighting it.  ``preview``: the add-on's fog (the
Compositor method, Dense Fog off, no shafts) rendered as the rendered viewport shows it (``preview.forced``).
"""
import math
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import bpy  # noqa: E402

from fog_addon import measure  # noqa: E402

BETA = 0.15
STRENGTH = 40.0
RADIUS = 0.15
LAMP_W = 300.0
LAMP_AT = (3.0, 4.0, 1.0)
RES = (96, 54)


def add_glowing_sphere(radius, location, strength):
    """An emissive UV sphere "Glowing Sphere" (Emission, white, ``strength`` W/(m^2 sr))."""
    bpy.ops.mesh.primitive_uv_sphere_add(radius=radius, location=location, segments=48, ring_count=24)
    sphere = bpy.context.active_object
    sphere.name = "Glowing Sphere"
    mat = bpy.data.materials.new("Glow")
    mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.clear()
    emit = nt.nodes.new("ShaderNodeEmission")
    emit.inputs["Strength"].default_value = strength
    nt.links.new(emit.outputs[0], nt.nodes.new("ShaderNodeOutputMaterial").inputs[0])
    sphere.data.materials.append(mat)
    return sphere


def world_fog(scene, beta):
    """The World's volume: Volume Scatter, white, density ``beta`` (the references' fog)."""
    world = scene.world
    world.use_nodes = True
    wn = world.node_tree
    wn.nodes.clear()
    scatter = wn.nodes.new("ShaderNodeVolumeScatter")
    scatter.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    scatter.inputs["Density"].default_value = beta
    wn.links.new(scatter.outputs[0], wn.nodes.new("ShaderNodeOutputWorld").inputs["Volume"])


def build():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    add_glowing_sphere(RADIUS, (0, 0, 0), STRENGTH)
    light = bpy.data.lights.new("Lamp", "POINT")
    light.energy, light.shadow_soft_size = LAMP_W, 0.0
    lamp = bpy.data.objects.new("Lamp", light)
    scene.collection.objects.link(lamp)
    lamp.location = LAMP_AT
    cam = bpy.data.cameras.new("Camera")
    cam.lens, cam.clip_start = 35.0, 0.001
    camera = bpy.data.objects.new("Camera", cam)
    scene.collection.objects.link(camera)
    scene.camera = camera
    camera.location, camera.rotation_euler = (0.0, -6.0, 0.0), (math.pi / 2, 0.0, 0.0)
    scene.world = bpy.data.worlds.new("World")
    scene.render.engine = "CYCLES"
    measure.set_cycles_cpu(scene)
    scene.render.resolution_x, scene.render.resolution_y = RES
    scene.cycles.use_denoising = False
    return scene


def reference(scene):
    world_fog(scene, BETA)
    scene.cycles.volume_bounces, scene.cycles.max_bounces = 0, 4


def main(mode, out, samples):
    scene = build()
    scene.cycles.samples = samples
    if mode == "reference":
        reference(scene)
        measure.render_to_file(scene, out)
        return
    import fog_addon
    from fog_addon.nodes import preview
    from fog_addon.ops import apply
    from fog_addon.precompute.core.spec import FogSpec
    fog_addon.register()
    apply.apply(scene, FogSpec(density=BETA, method="compositor", shafts=False, multiple_scattering=False))
    scene.render.use_compositing = False
    with preview.forced():
        measure.render_to_file(scene, out)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], int(sys.argv[3]))
