"""Adding and removing the fog on a scene (what the operators and the command line call)."""
import bpy

from ..nodes import groups, images, osl, wrap
from ..precompute import presets

SUPPORTED_LIGHTS = ("POINT",)
OSL_WAS = "analytic_fog_osl_was"   # scene custom property: Cycles' OSL switch before the OSL method set it


def fog_lights(scene):
    """(lights taking part, [(name, reason)] for lights left out)."""
    lights, skipped = [], []
    for obj in scene.objects:
        if obj.type != "LIGHT":
            continue
        if obj.data.type not in SUPPORTED_LIGHTS:
            skipped.append((obj.name, f"{obj.data.type.lower()} lights are not supported yet"))
        else:
            lights.append(obj)
    return lights, skipped


def scene_materials(scene):
    mats = []
    for obj in scene.objects:
        for slot in getattr(obj, "material_slots", ()):
            if slot.material is not None and slot.material not in mats:
                mats.append(slot.material)
    return mats


def use_osl(scene, on):
    """Switch Cycles' Open Shading Language on for the OSL method (and back to what it was)."""
    if on and OSL_WAS not in scene:
        scene[OSL_WAS] = scene.cycles.shading_system
        scene.cycles.shading_system = True
    elif not on and OSL_WAS in scene:
        scene.cycles.shading_system = bool(scene[OSL_WAS])
        del scene[OSL_WAS]


def apply_fog(scene, density, albedo=(1.0, 1.0, 1.0), anisotropy=0.0, method="nodes"):
    """Add (or update) the fog on ``scene``; adding twice is the same as once.

    ``method``: "nodes" (node groups, Cycles and EEVEE) or "osl" (the airlight
    by an OSL script, Cycles only; switches Cycles' OSL on).
    Returns a list of (data-block name, reason) for what was left out.
    Raises ValueError for bad settings before anything is changed.
    """
    beta = presets.validate_density(density)
    if anisotropy != 0.0:
        raise ValueError("anisotropic fog (anisotropy != 0) is not supported yet; use 0")
    if method not in groups.METHODS:
        raise ValueError(f"unknown method {method!r}; use one of {', '.join(groups.METHODS)}")
    lights, skipped = fog_lights(scene)
    imgs = images.all_table_images()
    groups.set_params(beta, tuple(albedo))
    groups.build_light(imgs, method)
    groups.build_background_light(imgs, method)
    use_osl(scene, method == "osl")
    groups.build_surface(lights)
    groups.build_world(lights, scene.camera)
    for mat in scene_materials(scene):
        why = wrap.wrap_material(mat)
        if why:
            skipped.append((mat.name, why))
    if scene.world is None:
        skipped.append((scene.name, "has no World: no airlight on the background"))
    else:
        why = wrap.wrap_world(scene.world)
        if why:
            skipped.append((scene.world.name, why))
    for light in lights:
        wrap.wrap_light(light.data)
    return skipped


def remove_fog(scene):
    """Take the fog out of every material, light and world, and delete its node groups and tables."""
    for coll in (bpy.data.materials, bpy.data.worlds):
        for idb in coll:
            wrap.unwrap(idb)
    for light in bpy.data.lights:
        wrap.unwrap_light(light)
    for name in (groups.SURFACE, groups.WORLD, groups.LIGHT, groups.BACKGROUND_LIGHT, groups.PARAMS):
        ng = bpy.data.node_groups.get(name)
        if ng is not None:
            bpy.data.node_groups.remove(ng)
    for name in images.table_names():
        img = bpy.data.images.get(name)
        if img is not None:
            bpy.data.images.remove(img)
    text = bpy.data.texts.get(osl.TEXT)
    if text is not None:
        bpy.data.texts.remove(text)
    use_osl(scene, False)
