"""Building the scene's groups for a plan: the Surface and World groups (and the method's own), the Dense Fog
tables they read, Cycles' OSL switch, the view layers' AOVs and the compositor set-up the built method needs.

What the Surface group keeps of a build (the lights and camera it was built for, the spec, the choice, the method)
decides whether the next build is needed (``build_scene_groups``); materials are never touched here.
"""
import json

import bpy

from .. import caveats, methods, sunsky
from ..nodes import comp_fog, groups, images, passes
from ..nodes.light import unwrap_light, wrap_light
from ..nodes.owned import is_fogged
from ..precompute.model import bakers
from ..precompute.model import rungs
from ..precompute.physics.point import multiple
from . import progress as progress_
from .plan import CHOICE_KEY, PREFERENCE_KEY, built_method, fog_lights, plan, resolve_method
from .report import limit_text

OSL_WAS = "analytic_fog_osl_was"   # scene custom property: Cycles' OSL switch before the OSL method set it
LIGHTS_KEY = "analytic_fog_lights"  # on the Surface group: the lights, their models and the camera it was built for
SPEC_KEY = "analytic_fog_spec"   # on the Surface group: a copy of the FogSpec it was built with (for farms and
#                                  people reading the file; the add-on reads the scene's settings, never this)
AOV_KINDS = dict(passes.AOVS + comp_fog.AOVS + comp_fog.EEVEE_AOVS + (comp_fog.DIRECTION_AOV,))   # every AOV the fog adds to view layers


def use_osl(scene, on):
    """Switch Cycles' Open Shading Language on for the OSL method (and back to what it was)."""
    if on and OSL_WAS not in scene:
        scene[OSL_WAS] = scene.cycles.shading_system
        scene.cycles.shading_system = True
    elif not on and OSL_WAS in scene:
        scene.cycles.shading_system = bool(scene[OSL_WAS])
        del scene[OSL_WAS]


def _extra_tables(spec, models=()):
    """The tables beyond ``bakers.bakers``' that ``spec``'s models read: the multiply scattered field's, and
    each spot's (``spot_multiple``) that ``models`` read."""
    if spec.multiple_albedo is None:
        return ()
    spots = [t for t in rungs.tables_of([r for light in models for r in light]) if bakers.is_spot_multiple(t)]
    return (multiple.table_spec(spec.anisotropy, spec.multiple_albedo), *spots)


class TablesMissing(Exception):
    """A build needs Dense Fog tables not yet baked, and its caller may not bake them in line (the depsgraph
    handler with a window: the cancellable ``fog.bake_tables`` bakes them, then syncs)."""


def bake_missing_tables(spec, models, progress=progress_.silent, in_line=True):
    """Bake the Dense Fog tables ``models`` read that are not cached yet, each announced with its estimate
    (``bakers.missing``) and reporting through ``progress`` (``progress.bake_progress``); a BakeCancelled raised
    by it propagates before anything is built (nothing half-baked is cached).  ``in_line`` False: raise
    TablesMissing instead of baking."""
    tables = bakers.missing(_extra_tables(spec, models))
    if tables and not in_line:
        raise TablesMissing(", ".join(bakers.label(t) for t, _ in tables))
    for table, seconds in tables:
        bakers.table_array(table, spec.anisotropy,
                           progress=progress_.bake_progress(progress, bakers.label(table), seconds))


def missing_tables(scene, spec):
    """[(TableSpec, seconds)]: the Dense Fog tables the next build of ``scene``'s fog for ``spec`` would bake
    first (``bakers.missing``), so that an operator can bake them on a worker thread, cancellable
    (``bake_job``).  In two rounds: the point light's table (the Quality's choice reads it) if it is missing,
    else the tables of the lights' chosen models; empty once nothing is left to bake."""
    first = bakers.missing(_extra_tables(spec, ()))
    if first or spec.multiple_albedo is None:
        return first
    lights = fog_lights(scene)[0]
    method, reason = resolve_method(scene, spec, lights)
    return bakers.missing(_extra_tables(spec, plan(scene, spec, method, lights, reason).models))


def _tails_key(scene):
    """What the glows past glass and mirrors depend on: whether the scene has such paths, and then the engine (a
    sharp mirror's reflected fog is the tails' in Cycles, its glossy lobe's in EEVEE: ``surface_group``)."""
    paths = caveats.specular_paths(bpy.data.materials)
    return f"{paths}:{scene.render.engine}" if paths else "False"


def _signature(scene, spec, method, plan_):
    camera = scene.camera
    return "|".join([groups.code_fingerprint()] + [f"{o.name_full}:{'/'.join(r.name for r in mod)}"
                                                    for o, mod in zip(plan_.in_groups, plan_.grouped_models)]
                     + ["camera:" + (camera.name_full if camera else ""), f"passes:{spec.passes}",
                        f"method:{method.name}", f"tails:{_tails_key(scene)}",
                        method.signature(scene, spec, plan_.shader_lights), sunsky.key(scene, spec)]
                     + ([] if plan_.preview is None else
                        ["preview:" + ",".join(f"{o.name_full}:{'/'.join(r.name for r in mod)}"
                                               for o, mod in zip(*plan_.preview[:2]))]))


rebuilt = set()   # names of scenes whose groups ``build_scene_groups`` rebuilt since ``refresh_lights`` asked


def build_scene_groups(scene, spec, lights, method=None, reason=None, rechoose=True, this_frame=False,
                       progress=progress_.silent, bake_in_line=True, force=False):
    """(Re)build the Surface and World groups (and the method's own) for ``spec`` and ``lights`` with ``method``
    (default: ``resolve_method``) unless built for them already; per-light groups no longer used are deleted,
    lights that no longer take part lose the fog's attenuation, Cycles' OSL is switched on while some model
    needs it, and the view layers have the method's AOVs.  ``rechoose``, ``this_frame``: see ``plan``;
    ``bake_in_line``: see ``bake_missing_tables``; ``force``: rebuilt even if built for them (what the groups
    read changed: the sun's map became an atlas).

    Returns [(name, reason)] for lights left unfogged, clashing AOVs and a choice the render engine limited.
    """
    if method is None:
        method, reason = resolve_method(scene, spec, lights, keep=not rechoose)
    bake_missing_tables(spec, (), progress, bake_in_line)   # Dense Fog's point table: the choice reads it
    plan_ = plan(scene, spec, method, lights, reason, rechoose, this_frame)
    signature = _signature(scene, spec, method, plan_)
    surface = bpy.data.node_groups.get(groups.SURFACE)
    if (surface is None or bpy.data.node_groups.get(groups.WORLD) is None
            or surface.get(LIGHTS_KEY) != signature or not method.is_built() or force):
        bake_missing_tables(spec, plan_.models, progress, bake_in_line)
        imgs = method.build(scene, spec, plan_,
                            images.all_table_images(spec.anisotropy, _extra_tables(spec, plan_.models)))
        rebuilt.add(scene.name)   # the compositor's chain must take the new groups (``refresh_lights``)
        surface = bpy.data.node_groups[groups.SURFACE]
        surface[LIGHTS_KEY] = signature
        surface[PREFERENCE_KEY] = method.name
        for name in comp_fog.all_group_names()[1:] + groups.all_group_names():
            ng = bpy.data.node_groups.get(name)
            if ng is not None and ng.users == 0 and name not in (groups.PARAMS, groups.SURFACE, groups.WORLD):
                bpy.data.node_groups.remove(ng)
        for name in images.table_names():   # another anisotropy's tables (one g per file: the params group's)
            img = bpy.data.images.get(name)
            if img is not None and name not in imgs:
                bpy.data.images.remove(img)
        taking_part = {o.data for o in lights}
        for light in bpy.data.lights:
            if light.users and light not in taking_part and is_fogged(light):
                unwrap_light(light)
    else:
        method.update(scene, spec, plan_)
        sunsky.refresh_glow_table(scene, spec)   # the camera moved up or down: its glow table, in place
    if surface.get(SPEC_KEY) != spec.to_json():
        surface[SPEC_KEY] = spec.to_json()
    if surface.get(CHOICE_KEY) != json.dumps(plan_.choice):
        surface[CHOICE_KEY] = json.dumps(plan_.choice)
    use_osl(scene, any(rungs.needs_osl(mod) for mod in plan_.models))
    notes = [(light.data.name, why) for light in lights if (why := wrap_light(light.data))]
    if (limit := limit_text(plan_.choice)) is not None:
        notes.append((scene.render.engine, f"{limit}, predicted error {plan_.choice['error']:.2%} "
                                           "(render --explain lists each light's models)"))
    notes += method.notes(scene, spec, plan_)
    aovs = tuple(method.passes(scene, spec))
    passes.remove_view_layer_aovs(scene, AOV_KINDS, keep=[name for name, _ in aovs])
    return notes + passes.add_view_layer_aovs(scene, aovs)


def follow_compositor(scene, rebuild=False):
    """The scene's compositor set-up as the built method needs it (``Method.follow``): the Compositor
    method's chain, else the denoiser's where Cycles denoises; returns [(name, note)]."""
    method = built_method() or methods.get("nodes")
    notes = method.follow(scene, rebuild)
    for other in methods.METHODS_BY_NAME.values():   # a method the scene changed from: what it left behind goes
        if other is not method:
            other.teardown(scene)
    return notes
