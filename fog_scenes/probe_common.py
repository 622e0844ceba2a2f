"""What the per-pixel probes share: the tiny render set-up, the camera and its ray of each pixel centre, and
point lights that light only the fog."""
import bpy
import numpy as np

from fog_addon import measure


def tiny_render(scene, engine, width, height):
    """1 sample at each pixel centre, no bounces (Cycles), point lights unwindowed (EEVEE)."""
    scene.render.engine = engine
    measure.set_resolution(scene, width, height)
    measure.set_samples(scene, 1)
    measure.set_pixel_centre_filter(scene)
    scene.cycles.max_bounces = 0
    scene.eevee.light_threshold = 1e-4


def camera_rays(cam, width, height):
    """(camera position, unit world direction of each pixel centre's ray (height, width, 3)) of a perspective camera
    with horizontal sensor fit."""
    ys, xs = np.mgrid[0:height, 0:width]
    sw, f = cam.data.sensor_width, cam.data.lens
    d = np.stack([((xs + 0.5) / width - 0.5) * sw, (0.5 - (ys + 0.5) / height) * sw * height / width,
                  -np.full(xs.shape, f)], -1)
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    return np.array(cam.location), d @ np.array(cam.matrix_world.to_3x3()).T


def look_at(scene, location, target, lens, name="cam"):
    """The scene's camera at ``location`` looking at ``target``: perspective, ``lens`` mm on a 36 mm sensor
    fitted horizontally (as ``camera_rays`` assumes), clip start 1 mm (the fog starts there in Cycles)."""
    from mathutils import Vector
    cam = bpy.data.objects.new(name, bpy.data.cameras.new(name))
    scene.collection.objects.link(cam)
    scene.camera = cam
    cam.location = location
    cam.rotation_euler = (Vector(target) - Vector(location)).to_track_quat("-Z", "Y").to_euler()
    cam.data.clip_start = 0.001
    cam.data.lens, cam.data.sensor_width, cam.data.sensor_fit = lens, 36.0, "HORIZONTAL"
    return cam


def light_fog_only(ob):
    """Make the light object ``ob`` light nothing but the fog: EEVEE by its diffuse and specular factors,
    Cycles by hiding it from diffuse and glossy rays (the factors alone still let it light surfaces)."""
    ob.data.diffuse_factor = ob.data.specular_factor = 0.0
    ob.visible_diffuse = ob.visible_glossy = False


def add_point_lights(scene, specs, fog_only=True):
    """Point lights of radius 0 named L000, L001, ... from [(location, power W, RGB colour)];
    ``fog_only``: see ``light_fog_only``."""
    for k, (where, power, colour) in enumerate(specs):
        ob = bpy.data.objects.new(f"L{k:03d}", bpy.data.lights.new(f"L{k:03d}", "POINT"))
        ob.data.energy, ob.data.color, ob.data.shadow_soft_size = power, colour, 0.0
        if fog_only:
            light_fog_only(ob)
        ob.location = where
        scene.collection.objects.link(ob)


def white_furnace(base_color, roughness, specular_ior_level=0.5, size=1e4):
    """A new empty scene with one plane of ``size`` m (at z = 0, selected) of a Principled BSDF under a
    uniform white World of radiance 1: the light a point of it reflects is its directional albedo."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    bpy.ops.mesh.primitive_plane_add(size=size)
    mat = bpy.data.materials.new("Furnace")
    mat.use_nodes = True
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*base_color, 1.0)
    bsdf.inputs["Roughness"].default_value = roughness
    bsdf.inputs["Specular IOR Level"].default_value = specular_ior_level
    bpy.context.object.data.materials.append(mat)
    world = bpy.data.worlds.new("White")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    scene.world = world
    return scene


def light_pixel(scene, light):
    """The light's position in the picture, px from the bottom-left corner (far away behind the camera)."""
    from bpy_extras.object_utils import world_to_camera_view

    from fog_addon import view
    p = world_to_camera_view(scene, scene.camera, light.matrix_world.translation)
    w, h = view.render_size(scene)
    return (p.x * w, p.y * h, 0.0) if p.z > 0 else (1e6, 1e6, 0.0)


def mesh_object(scene, name, make, mat, location=(0, 0, 0), rotation=(0, 0, 0)):
    """A mesh object ``name`` in ``scene`` whose mesh ``make(bm)`` builds in a bmesh, with material ``mat``."""
    import bmesh
    bm = bmesh.new()
    make(bm)
    me = bpy.data.meshes.new(name)
    bm.to_mesh(me)
    bm.free()
    me.materials.append(mat)
    ob = bpy.data.objects.new(name, me)
    ob.location, ob.rotation_euler = location, rotation
    scene.collection.objects.link(ob)
    return ob


def glass_material(name="Glass"):
    """A material of one sharp Glass BSDF (roughness 0) into its output."""
    mat = bpy.data.materials.new(name)
    nt = mat.node_tree
    for node in list(nt.nodes):
        if node.bl_idname != "ShaderNodeOutputMaterial":
            nt.nodes.remove(node)
    glass = nt.nodes.new("ShaderNodeBsdfGlass")
    glass.inputs["Roughness"].default_value = 0.0
    out = next(node for node in nt.nodes if node.bl_idname == "ShaderNodeOutputMaterial")
    nt.links.new(glass.outputs[0], out.inputs["Surface"])
    return mat


def set_up_mode(scene, mode, beta, samples, configure):
    """A probe's scene for ``mode``: ``reference`` (Cycles' World volume of ``beta``, ``fog_addon.reference``) or
    ``fog`` / ``none`` (Cycles on the CPU, pixel centres, no denoiser); then ``configure(scene, samples)`` (its bounces
    and visibility: before the fog, which reads the casters as they render).  Returns the samples used."""
    from fog_addon import reference   # noqa: PLC0415
    samples = int(samples or (2048 if mode == "reference" else 64))
    if mode == "reference":
        reference.configure_reference(scene, beta, samples=samples)
    else:
        scene.render.engine = "CYCLES"
        measure.set_cycles_cpu(scene)
        measure.set_pixel_centre_filter(scene)
        scene.cycles.use_denoising = False
    configure(scene, samples)
    return samples


def add_fog(scene, beta, method):
    """The add-on registered and its fog added (``apply.apply_fog``); returns its notes."""
    import fog_addon   # noqa: PLC0415
    from fog_addon.ops import apply   # noqa: PLC0415
    fog_addon.register()
    return apply.apply_fog(scene, beta, method=method)


PRINCIPLED_GLASS = {"Base Color": (1.0, 1.0, 1.0, 1.0), "Transmission Weight": 1.0, "Roughness": 0.0, "IOR": 1.5}
#                    Blender's usual glass: a Principled BSDF of Transmission 1, roughness 0


def bsdf_material(name, bl_idname, **inputs):
    """A material of one BSDF node ``bl_idname`` into its output, its ``inputs`` (name: value) set."""
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    bsdf = nt.nodes.new(bl_idname)
    for key, value in inputs.items():
        bsdf.inputs[key].default_value = value
    nt.links.new(bsdf.outputs[0], out.inputs["Surface"])
    return mat


def see_through_bounces(scene, width, height):
    """A glass probe's resolution and bounces (single scattering: volume 0; one diffuse bounce, the fog's light
    on a wall; glossy 2 and transmission 4 for the paths through a pane; max_bounces caps every kind: their sum),
    its meshes hidden from diffuse rays (no light from surface to surface, as in the model)."""
    measure.set_resolution(scene, width, height)
    c = scene.cycles
    c.volume_bounces, c.diffuse_bounces, c.glossy_bounces, c.transmission_bounces = 0, 1, 2, 4
    c.max_bounces = 7
    c.transparent_max_bounces = 8
    for ob in scene.objects:
        if ob.type == "MESH":
            ob.visible_diffuse = False
