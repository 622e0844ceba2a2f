"""Demo scenes for Analytic Fog and the helpers they share (need bpy).

Each scene module has ``build(scene)`` (adds its objects, lights, camera,
world and render settings to ``scene``) and runs as a script::

    python demo_scenes/street_lamps.py OUT.blend

Conventions shared by every demo: Principled BSDF materials, a dark constant
world colour, point lights of radius 0 with shadows on, camera clip start
1 mm (Cycles starts camera rays at the near clip), 640x360 Cycles.
Meshes are made with bmesh so ``build`` needs no operator context.
"""
import math
import os
import sys

import bpy
import bmesh
from mathutils import Vector

RESOLUTION = (640, 360)
WORLD_COLOR = (0.004, 0.005, 0.008)
CLIP_START = 0.001
CLIP_END = 1000.0          # clip ratio 1e6: EEVEE draws a black world at 1e8
DEMO_SAMPLES = 128


def material(name, base_color, roughness=0.5, metallic=0.0, specular_ior_level=0.5):
    """A Principled BSDF material (specular_ior_level 0 = pure Lambertian diffuse)."""
    mat = bpy.data.materials.new(name)
    if mat.node_tree is None:
        mat.use_nodes = True
    bsdf = next(n for n in mat.node_tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
    bsdf.inputs["Base Color"].default_value = (*base_color, 1.0)
    bsdf.inputs["Roughness"].default_value = roughness
    bsdf.inputs["Metallic"].default_value = metallic
    bsdf.inputs["Specular IOR Level"].default_value = specular_ior_level
    mat.diffuse_color = (*base_color, 1.0)
    return mat


def _object_from_bmesh(scene, name, bm, mat, smooth=False):
    mesh = bpy.data.meshes.new(name)
    bm.to_mesh(mesh)
    bm.free()
    if smooth:
        mesh.shade_smooth()
    mesh.materials.append(mat)
    ob = bpy.data.objects.new(name, mesh)
    scene.collection.objects.link(ob)
    return ob


def add_plane(scene, name, x0, x1, y0, y1, z, mat):
    bm = bmesh.new()
    vs = [bm.verts.new(v) for v in ((x0, y0, z), (x1, y0, z), (x1, y1, z), (x0, y1, z))]
    bm.faces.new(vs)
    return _object_from_bmesh(scene, name, bm, mat)


def add_cylinder(scene, name, base, radius, height, mat, segments=16):
    bm = bmesh.new()
    bmesh.ops.create_cone(bm, cap_ends=True, cap_tris=False, segments=segments,
                          radius1=radius, radius2=radius, depth=height)
    ob = _object_from_bmesh(scene, name, bm, mat, smooth=False)
    ob.location = Vector(base) + Vector((0.0, 0.0, 0.5 * height))
    return ob


def add_sphere(scene, name, center, radius, mat, segments=64, rings=32):
    bm = bmesh.new()
    bmesh.ops.create_uvsphere(bm, u_segments=segments, v_segments=rings, radius=radius)
    ob = _object_from_bmesh(scene, name, bm, mat, smooth=True)
    ob.location = center
    return ob


def add_box(scene, name, center, half_extents, mat):
    """An axis-aligned box of half extents (hx, hy, hz) centred at ``center``."""
    bm = bmesh.new()
    bmesh.ops.create_cube(bm, size=1.0)
    bmesh.ops.scale(bm, vec=tuple(2.0 * h for h in half_extents), verts=bm.verts)
    ob = _object_from_bmesh(scene, name, bm, mat)
    ob.location = center
    return ob


def add_box_between(scene, name, x0, x1, y0, y1, z0, z1, mat):
    """An axis-aligned box from (x0, y0, z0) to (x1, y1, z1) m (``add_box`` by its corners)."""
    return add_box(scene, name, (0.5 * (x0 + x1), 0.5 * (y0 + y1), 0.5 * (z0 + z1)),
                   (0.5 * (x1 - x0), 0.5 * (y1 - y0), 0.5 * (z1 - z0)), mat)


def add_point_light(scene, name, location, power):
    """Point light of radius 0 (a true point: Sun's isotropic source, I0 = P / 4 pi)."""
    light = bpy.data.lights.new(name, 'POINT')
    light.energy = power
    light.shadow_soft_size = 0.0
    light.use_shadow = True
    light.color = (1.0, 1.0, 1.0)
    ob = bpy.data.objects.new(name, light)
    ob.location = location
    scene.collection.objects.link(ob)
    return ob


def add_spot_light(scene, name, location, target, power, size_deg, blend, color=(1.0, 1.0, 1.0)):
    """Spot light of radius 0 aimed at ``target`` (its axis is local -Z): Blender's cone of ``size_deg``
    degrees and ``blend``; within the cone it shines as a point light of the same power."""
    light = bpy.data.lights.new(name, 'SPOT')
    light.energy = power
    light.shadow_soft_size = 0.0
    light.use_shadow = True
    light.color = color
    light.spot_size = math.radians(size_deg)
    light.spot_blend = blend
    ob = bpy.data.objects.new(name, light)
    ob.location = location
    ob.rotation_euler = (Vector(target) - Vector(location)).to_track_quat('-Z', 'Y').to_euler()
    scene.collection.objects.link(ob)
    return ob


def add_camera(scene, location, target, lens=35.0):
    cam = bpy.data.cameras.new("Camera")
    cam.lens = lens
    cam.sensor_fit = 'AUTO'
    cam.sensor_width = 36.0
    cam.clip_start = CLIP_START
    cam.clip_end = CLIP_END
    ob = bpy.data.objects.new("Camera", cam)
    ob.location = location
    direction = Vector(target) - Vector(location)
    ob.rotation_euler = direction.to_track_quat('-Z', 'Y').to_euler()
    scene.collection.objects.link(ob)
    scene.camera = ob
    return ob


def set_world(scene, color=WORLD_COLOR):
    world = bpy.data.worlds.new(scene.name + " World")
    if world.node_tree is None:
        world.use_nodes = True
    bg = next(n for n in world.node_tree.nodes if n.bl_idname == "ShaderNodeBackground")
    bg.inputs["Color"].default_value = (*color, 1.0)
    bg.inputs["Strength"].default_value = 1.0
    scene.world = world
    return world


def render_settings(scene, resolution=RESOLUTION, samples=DEMO_SAMPLES):
    scene.render.engine = 'CYCLES'
    scene.cycles.device = 'CPU'
    scene.cycles.samples = samples
    scene.render.resolution_x, scene.render.resolution_y = resolution
    scene.render.resolution_percentage = 100
    scene.view_settings.view_transform = 'AgX'
    scene.view_settings.look = 'None'
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0


def clear_scene(scene):
    for ob in list(scene.objects):
        bpy.data.objects.remove(ob)


def main(build, argv=None):
    """Script entry: ``python demo_scenes/<name>.py OUT.blend`` builds a fresh file and saves it."""
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) != 1 or not argv[0].endswith(".blend"):
        print(f"usage: python {os.path.basename(sys.argv[0])} OUT.blend", file=sys.stderr)
        return 2
    out = os.path.abspath(argv[0])
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    build(scene)
    os.makedirs(os.path.dirname(out), exist_ok=True)
    bpy.ops.wm.save_as_mainfile(filepath=out, compress=True)
    print(f"saved {out}")
    return 0


def script_path_setup():
    """Make ``import demo_scenes`` work when a scene file runs as a script."""
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    if root not in sys.path:
        sys.path.insert(0, root)


__all__ = ["material", "add_plane", "add_cylinder", "add_sphere", "add_box", "add_point_light", "add_camera",
           "set_world", "render_settings", "clear_scene", "main", "math"]
