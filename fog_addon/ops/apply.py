"""Adding, updating and removing the fog on a scene (what the operators, handlers and command line call)."""
import json
import math
import traceback
from typing import Any, NamedTuple

import bpy

from .. import caveats, methods, props, shadow_maps, sunsky
from ..nodes import comp_fog, compositor, dedupe, groups, images, osl, passes
from ..nodes.light import unwrap_light, wrap_light
from ..nodes.material import unwrap_material, wrap_material
from ..nodes.owned import is_fogged
from ..nodes.world import unwrap_world, wrap_world
from ..precompute import bakers, multiple, predict, presets, rungs, shafts, spot
from ..precompute.spec import FogSpec, validate_quality
from . import progress as progress_
from .. import view

SUPPORTED_LIGHTS = ("POINT", "SPOT", "AREA")
THIN_SHARE = 0.25   # Dense Fog is left out for a light whose multiply scattered light is at most this share of
#                     the Quality's target at every judged view sample (``predict.multiple_share``)
OSL_WAS = "analytic_fog_osl_was"   # scene custom property: Cycles' OSL switch before the OSL method set it
LIGHTS_KEY = "analytic_fog_lights"  # on the Surface group: the lights, their models and the camera it was built for
PREFERENCE_KEY = "analytic_fog_preference"   # on the Surface group: the method it was built with (methods.get)
SPEC_KEY = "analytic_fog_spec"   # on the Surface group: a copy of the FogSpec it was built with (for farms and
#                                  people reading the file; the add-on reads the scene's settings, never this)
CAVEATS_KEY = "analytic_fog_caveats"   # on the Surface group: what the fog can't model in the scene (notes)
CHOICE_KEY = "analytic_fog_choice"   # on the Surface group: the Quality, {light: [step, predicted error]}, the total,
#                                      the method and why (Auto)
AOV_KINDS = dict(passes.AOVS + comp_fog.AOVS + comp_fog.EEVEE_AOVS)   # every AOV the fog adds to view layers


AT_CAMERA = 1e-3   # a lamp nearer the camera than this share of the scene's depth is "at the camera" (a note)


def fog_lights(scene):
    """(lights taking part, [(name, reason)] for lights left out or worth a note)."""
    lights, notes = [], []
    eye = scene.camera.matrix_world.translation if scene.camera is not None else None
    near = None   # AT_CAMERA x the scene's depth, computed once a light takes part (the depsgraph handler calls this)
    for obj in scene.objects:
        if obj.type != "LIGHT":
            continue
        data = obj.data
        settings = getattr(data, "analytic_fog", None)
        if data.type == "SUN":   # the sun shines through a fog layer (``sunsky.py``), not as a fog light
            continue
        if data.type not in SUPPORTED_LIGHTS:
            notes.append((obj.name, f"{data.type.lower()} lights are not supported yet: no fog glow"))
        elif settings is not None and not settings.use:
            continue
        elif obj.hide_render:
            continue
        elif not data.energy > 0.0 or not any(c > 0.0 for c in data.color):
            notes.append((obj.name, "has zero power: it lights no fog"))
        else:
            lights.append(obj)
            if eye is not None and near is None:
                near = AT_CAMERA * scene_size(scene)
            if eye is not None and (obj.matrix_world.translation - eye).length <= near:
                notes.append((obj.name, f"is {(obj.matrix_world.translation - eye).length:.2g} units from the camera: "
                                        "the fog's light from a lamp grows without bound as it nears the camera, so "
                                        "the picture blows out; move the lamp away from the camera"))
            s = obj.matrix_world.to_scale()
            if view.is_spot(obj) and obj.matrix_world.to_3x3().determinant() < 0.0:
                notes.append((obj.name, "is mirrored (negative scale): its cone in the fog points the other way"))
            elif data.type == "POINT" and max(s) - min(s) > 1e-6 * max(abs(max(s)), 1e-30):
                notes.append((obj.name, "is scaled non-uniformly: a point light's fog ignores scale"))
            elif data.type == "AREA" and max(s) - min(s) > 1e-6 * max(abs(max(s)), 1e-30):
                notes.append((obj.name, "is scaled non-uniformly: its glow takes the emitter as scaled by the "
                                        "largest axis"))
            if data.type == "AREA" and data.spread < math.radians(179.9):
                notes.append((obj.name, f"has a Spread of {math.degrees(data.spread):.0f} degrees: its glow is "
                                        "that of a Lambertian emitter (Spread 180)"))
    return lights, notes


def check_camera(camera):
    """Raise ValueError unless ``camera`` can see analytic fog (a perspective or panoramic camera)."""
    if camera is None:
        raise ValueError("the scene has no camera: set one (Scene properties > Camera), then add the fog")
    if camera.type != "CAMERA":
        raise ValueError(f"the scene camera {camera.name!r} is not a camera object")
    if camera.data.type == "ORTHO":
        raise ValueError(f"camera {camera.name!r} is orthographic: the fog model needs rays from one point "
                         "(a perspective camera)")


def scene_materials(scene, objects=None):
    """Materials of ``objects`` (default: every object in the scene), each once."""
    mats = []
    for obj in scene.objects if objects is None else objects:
        for slot in getattr(obj, "material_slots", ()):
            if slot.material is not None and slot.material not in mats:
                mats.append(slot.material)
    return mats


def scene_size(scene):
    """Largest distance (m in scene units) from the camera to an object origin: the depth fog must cross."""
    cam = scene.camera
    if cam is None:
        return 0.0
    c = cam.matrix_world.translation
    return max(((o.matrix_world.translation - c).length for o in scene.objects if o is not cam), default=0.0)


def use_osl(scene, on):
    """Switch Cycles' Open Shading Language on for the OSL method (and back to what it was)."""
    if on and OSL_WAS not in scene:
        scene[OSL_WAS] = scene.cycles.shading_system
        scene.cycles.shading_system = True
    elif not on and OSL_WAS in scene:
        scene.cycles.shading_system = bool(scene[OSL_WAS])
        del scene[OSL_WAS]


def spec_of(scene):
    """The scene's fog settings as a validated ``FogSpec`` (``scene.analytic_fog``); raises ValueError."""
    props.ensure_registered()
    return FogSpec.from_settings(scene.analytic_fog)


def store_spec(scene, spec):
    """Write ``spec`` into ``scene.analytic_fog`` (the one store of the fog's settings), without its callbacks."""
    props.ensure_registered()
    settings = scene.analytic_fog
    with props.quiet():
        for key, value in spec.settings_values().items():
            if key == "color" or getattr(settings, key) != value:
                setattr(settings, key, value)


def choose_models(scene, spec, method, lights):
    """Each light's models (rungs.LightModels) at the spec's Quality with ``method``, and the choice for reports.

    The view is sampled by ray casts (``view.py``) and every light's step down
    the ladder chosen by the predicted error (``predict.py``).  Where the method has a budget
    (``method.budget``: EEVEE's uniform block, Cycles OSL's shader group layers), lights
    step down beyond the target, least error first, until they fit.  Returns
    (models, choice) with choice = {"lights": {name: [step, error]}, "rims": {name: point count} of the spots
    whose glow's rim takes fewer than spot.RIM_NODES points, "error": total, "target": t, "engine": the render
    engine chosen for, "limited": what forced steps beyond the target, or None, and with Dense Fog "thin":
    {name: share} of the lights whose multiply scattered light is at most THIN_SHARE of the target
    (``predict.multiple_share``): they are left without it, at no cost}.
    """
    target = spec.target_error
    engine = scene.render.engine
    budget = method.budget(scene, spec, lights)
    steps = [0] * len(lights)
    choice = {"target": target, "error": 0.0, "lights": {}, "rims": {}, "engine": engine, "limited": None}
    if lights and (target is not None or (budget is not None and not budget.fits(steps))):
        samples = view.view_samples(scene, lights)
        pred = predict.predict(samples, view.light_intensities(lights), spec.beta_per_unit, target, budget,
                               spec.anisotropy)
        steps = [int(k) for k in pred.steps]
        choice["error"] = pred.error
        choice["lights"] = {o.name: [int(k), float(e)] for o, k, e in zip(lights, pred.steps, pred.light_error)}
        choice["rims"] = {o.name: int(n) for o, n in zip(lights, pred.rims)   # (a light off keeps RIM_NODES)
                          if view.is_spot(o) and n != spot.RIM_NODES}
        if pred.limited or not pred.fits:
            choice["limited"] = budget.name + ("" if pred.fits else ": too many lights even with every light off")
        if spec.multiple_scattering and target is not None:
            share = predict.multiple_share(samples, view.light_intensities(lights), spec.beta_per_unit,
                                           spec.anisotropy, spec.multiple_albedo, pred.fog)
            choice["thin"] = {o.name: float(v) for o, v in zip(lights, share)
                              if not view.has_shape(o) and v <= THIN_SHARE * target}
            choice["error"] += max(choice["thin"].values(), default=0.0)
    else:
        choice["lights"] = {o.name: [0, 0.0] for o in lights}
    return _models(spec, method, lights, steps, choice["rims"], set(choice.get("thin", ()))), choice


def _models(spec, method, lights, steps, rims, thin=frozenset()):
    """Each light's models at its step, a spot's glow with its rim's point count (``rims``: by name), Dense Fog
    left out for the lights ``thin`` names."""
    return [rungs.choose(method.preference, k, spec.anisotropy, view.is_spot(o), rims.get(o.name, spot.RIM_NODES),
                         multiple_albedo=None if o.name in thin else spec.multiple_albedo, area=view.is_area(o),
                         cone=view.spot_cone(o) if view.is_spot(o) else None)
            for o, k in zip(lights, steps)]


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


_declined = {}   # scene name -> the spec (JSON) whose bake the user cancelled (``decline_bake``)


def decline_bake(scene, table, error=None):
    """The bake of ``table`` for ``scene``'s settings was cancelled (or failed with ``error``): the fog keeps what
    it was built with, the panel says why (``sync_error``), and the handlers do not start it again for the same
    settings (``bake_declined``).  Returns the message."""
    what = bakers.label(table) if table is not None else "Dense Fog's tables"
    why = (f"the bake of {what} was cancelled" if error is None else f"the bake of {what} failed ({error})")
    why += ": the fog keeps what it was built with; Update Fog bakes it, or turn Dense Fog off"
    _sync_errors[scene.name] = why
    try:
        _declined[scene.name] = spec_of(scene).to_json()
    except ValueError:
        pass
    return why


def bake_declined(scene):
    """True if the user cancelled the bake of the tables ``scene``'s present settings need."""
    try:
        return _declined.get(scene.name) == spec_of(scene).to_json()
    except ValueError:
        return False


def accept_bake(scene):
    """Add Fog / Update Fog asked for the fog again: a bake cancelled before may start again."""
    _declined.pop(scene.name, None)


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


def stored_choice():
    """The choice the scene groups were last built with (see choose_models, plus its "quality"), or None."""
    surface = bpy.data.node_groups.get(groups.SURFACE)
    if surface is None or CHOICE_KEY not in surface:
        return None
    return json.loads(surface[CHOICE_KEY])


def method_line(choice):
    """One line: the method ``choice`` was built with, and why where Auto chose it; None before this was stored."""
    name = choice.get("method")
    if name is None:
        return None
    label = methods.get(name).label
    reason = choice.get("method_reason")
    return f"Method Auto: {label} ({reason})" if reason else f"Method {label}"


def quality_head(choice):
    """One line: the Quality of ``choice`` (see choose_models) and the error it is predicted to make."""
    target = choice["target"]
    if target is None and not choice.get("limited"):
        return "Quality Exact: every light fully modelled"
    if target is None:
        return f"Quality Exact: predicted error {choice['error']:.2%}"
    return f"Quality {target:.3g}: predicted error {choice['error']:.2%} (target {target:.2%})"


def limit_text(choice):
    """What limited ``choice`` beyond its target (EEVEE's uniform block, OSL's group size), as a phrase, or None."""
    return f"limited by {choice['limited']}: lights step down beyond the target" if choice.get("limited") else None


def explain(choice=None):
    """Lines that say which models each light got and the error predicted (panel, operator, ``--explain``):
    the Quality (and what limited it), then one line per light.  ``choice``: default the stored one."""
    choice = stored_choice() if choice is None else choice
    if choice is None:
        return ["the fog is not on"]
    limit = limit_text(choice)
    lines = [quality_head(choice) + (f"; {limit}" if limit else "")]
    if (line := method_line(choice)) is not None:
        lines.append("  " + line)
    rims = choice.get("rims", {})
    for name, (step, err) in sorted(choice["lights"].items()):
        rim = f", {rims[name]}-point rim" if name in rims else ""
        lines.append(f"  {name}: {rungs.STEPS[step]}{rim}" + (f" (leaves out up to {err:.2%})" if step else
                                                               f" (moves up to {err:.2%})" if rim else ""))
    thin = choice.get("thin", {})
    if thin:
        lines.append(f"  Dense Fog left out for {len(thin)} light(s) ({', '.join(sorted(thin)[:3])}"
                     f"{' and more' if len(thin) > 3 else ''}): their multiply scattered light is at most "
                     f"{max(thin.values()):.2%} of the fog")
    shafted = sorted(i.name.removeprefix(shadow_maps.IMAGE_PREFIX) for i in bpy.data.images
                     if i.name.startswith(shadow_maps.IMAGE_PREFIX))
    if shafted:
        own, used = shafts.samples_for(choice.get("quality")), shafts.samples_for(choice.get("quality"), len(shafted))
        fewer = (f", fewer than the Quality's {own.view_nodes} beyond {shafts.BUDGET_LIGHTS} shafted lights"
                 if used != own else "")
        lines.append(f"  Light shafts of {len(shafted)} light(s): {used.view_nodes} nodes a ray, "
                     f"{used.surface_directions} directions x {used.surface_nodes} nodes over surfaces{fewer}; their "
                     f"error is not in the prediction ({SHAFT_ERROR_NOTE})")
    sun_map = bpy.data.images.get(shadow_maps.SUN_IMAGE)
    if sun_map is not None:
        lines.append(f"  The sun's shafts: a {sun_map.size[0]} x {sun_map.size[1]} map, "
                     f"{shafts.samples_for(choice.get('quality')).view_nodes} nodes a ray, "
                     f"{shafts.SUN_SURFACE_SAMPLES[0]} directions x {shafts.SUN_SURFACE_SAMPLES[1]} nodes over surfaces")
    return lines


# what the shafts' quadrature adds to a Quality's error, measured (docs/measurements/2026-11-26-light-shafts.md)
SHAFT_ERROR_NOTE = "at Final up to 1.5 % from Exact's 48 nodes, boulevard"


def _in_groups(lights, choice):
    """The ``lights`` the fog's groups hold: all but those ``choice`` stepped out to fit a budget (rungs.LEFT_OUT;
    a light the choice does not know is in)."""
    return [o for o in lights if choice["lights"].get(o.name, [0])[0] != rungs.LEFT_OUT]


class Plan(NamedTuple):
    """What a method builds (``Method.build``): the lights' models, where they go, and the choice for reports."""
    lights: list              # the lights taking part
    models: list              # their models (rungs.LightModels)
    choice: dict              # ``choose_models``'s, with "quality", "method" and "method_reason"
    in_groups: list           # the lights the fog's groups hold (``_in_groups``)
    grouped_models: list      # their models
    shader_lights: list       # the lights the materials' and World's groups hold (``Method.shader_lights``)
    shader_models: list
    windows: Any              # where the compositor evaluates each term (``view.windows``), or None
    partial: bool             # the windows are this frame's only (the handlers')
    this_frame: bool          # a handler's rebuild, which must not step through the frames (``plan``)


def built_method():
    """The method the scene groups were built with (``methods.Method``), or None."""
    surface = bpy.data.node_groups.get(groups.SURFACE)
    name = surface.get(PREFERENCE_KEY) if surface is not None else None
    return methods.METHODS_BY_NAME.get(name) if name else None


_resolved = {}   # scene name -> (spec JSON, lights, method name, reason) of Auto's last choice


def resolve_method(scene, spec, lights, keep=False):
    """(method, reason) for ``spec`` (``methods.resolve``; Auto chooses by the scene).  ``keep``: Auto keeps its
    last choice for this scene while the spec and the lights are the same (the handlers' cheap path)."""
    key = (spec.to_json(), tuple(o.name_full for o in lights))
    last = _resolved.get(scene.name)
    if keep and spec.method == "auto" and last is not None and last[:2] == key:
        return methods.get(last[2]), last[3]
    method, reason = methods.resolve(scene, spec, lights, scene_materials(scene))
    _resolved[scene.name] = key + (method.name, reason)
    return method, reason


def check_method(scene, spec, method):
    """Raise ValueError unless ``method`` can serve ``scene`` with ``spec`` (and its models the anisotropy)."""
    rungs.choose(method.preference, 0, spec.anisotropy)   # raises for a g the method's models don't serve
    why = method.check(scene, spec)
    if why is not None:
        raise ValueError(why)


def plan(scene, spec, method, lights, reason=None, rechoose=True, this_frame=False):
    """The ``Plan`` of ``method`` for ``lights`` at the spec's Quality.

    ``rechoose``: choose the lights' models again from the view (``choose_models``); else keep the stored
    steps (lights new to the fog get the full models).  ``this_frame``: the handlers' call (no stepping through
    frames: an animation's windows grow by this frame's)."""
    old = stored_choice()
    kept = None
    quality = spec.quality
    if not (rechoose or old is None or old.get("quality") != quality or old.get("method") != method.name
            or (old.get("engine") == groups.EEVEE_ENGINE) != (scene.render.engine == groups.EEVEE_ENGINE)):
        kept = [old["lights"].get(o.name, [0, 0.0])[0] for o in lights]
        budget = method.budget(scene, spec, lights)
        if budget is not None and not budget.fits(kept):   # e.g. the method switched to OSL: choose again
            kept = None
    if kept is None:
        models, choice = choose_models(scene, spec, method, lights)
    else:
        rims = {o.name: old["rims"][o.name] for o in lights if o.name in old.get("rims", {})}
        models = _models(spec, method, lights, kept, rims, set(old.get("thin", ())))
        choice = dict(old, lights={o.name: old["lights"].get(o.name, [0, 0.0]) for o in lights}, rims=rims)
    choice.update(quality=quality, method=method.name, method_reason=reason)
    # lights stepped out of the groups to fit a budget (rungs.LEFT_OUT) keep their own dimming (wrap_light)
    in_groups = _in_groups(lights, choice)
    grouped = [mod for o, mod in zip(lights, models) if o in in_groups]
    shader_lights, shader_models = method.shader_lights(scene, spec, in_groups, grouped)
    partial = this_frame and view.animated(scene)
    return Plan(lights, models, choice, in_groups, grouped, shader_lights, shader_models,
                method.windows(scene, in_groups, partial), partial, this_frame)


def _signature(scene, spec, method, plan_):
    camera = scene.camera
    return "|".join([groups.code_fingerprint()] + [f"{o.name_full}:{'/'.join(r.name for r in mod)}"
                                                    for o, mod in zip(plan_.in_groups, plan_.grouped_models)]
                     + ["camera:" + (camera.name_full if camera else ""), f"passes:{spec.passes}",
                        f"method:{method.name}", f"tails:{caveats.specular_paths(bpy.data.materials)}",
                        method.signature(scene, spec, plan_.shader_lights), sunsky.key(scene, spec)])


_rebuilt = set()   # names of scenes whose groups ``_build_scene_groups`` rebuilt since ``refresh_lights`` asked


def _build_scene_groups(scene, spec, lights, method=None, reason=None, rechoose=True, this_frame=False,
                        progress=progress_.silent, bake_in_line=True):
    """(Re)build the Surface and World groups (and the method's own) for ``spec`` and ``lights`` with ``method``
    (default: ``resolve_method``) unless built for them already; per-light groups no longer used are deleted,
    lights that no longer take part lose the fog's attenuation, Cycles' OSL is switched on while some model
    needs it, and the view layers have the method's AOVs.  ``rechoose``, ``this_frame``: see ``plan``;
    ``bake_in_line``: see ``bake_missing_tables``.

    Returns [(name, reason)] for lights left unfogged, clashing AOVs and a choice the render engine limited.
    """
    if method is None:
        method, reason = resolve_method(scene, spec, lights, keep=not rechoose)
    bake_missing_tables(spec, (), progress, bake_in_line)   # Dense Fog's point table: the choice reads it
    plan_ = plan(scene, spec, method, lights, reason, rechoose, this_frame)
    signature = _signature(scene, spec, method, plan_)
    surface = bpy.data.node_groups.get(groups.SURFACE)
    if (surface is None or bpy.data.node_groups.get(groups.WORLD) is None
            or surface.get(LIGHTS_KEY) != signature or not method.is_built()):
        bake_missing_tables(spec, plan_.models, progress, bake_in_line)
        imgs = method.build(scene, spec, plan_,
                            images.all_table_images(spec.anisotropy, _extra_tables(spec, plan_.models)))
        _rebuilt.add(scene.name)   # the compositor's chain must take the new groups (``refresh_lights``)
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


def merge_appended():
    """Fold fog data appended from another fogged file onto this file's copies (``dedupe``).

    Returns [(name, reason)] notes for objects the other file's drivers pulled in.
    """
    _, pulled = dedupe.merge_duplicates()
    return [(name, "came in with fog appended from another file (its drivers' target); delete it if unwanted")
            for name in pulled]


def apply(scene, spec, objects=None, progress=progress_.silent):
    """Add (or update) the fog of ``spec`` (a ``FogSpec``) on ``scene``; adding twice is the same as once.

    The spec is stored in ``scene.analytic_fog`` (the one store of the fog's settings); then the lights
    taking part are found, the method resolved (``spec.method`` "auto": ``methods/auto.py`` chooses),
    checked, planned (each light's models for the Quality) and built.  ``objects``: fog only their
    materials (default: all in the scene).  Returns a list of (data-block name, reason) for what was left
    out or fogged with a caveat.  Raises ValueError for bad settings before anything is changed.
    ``progress(stage, done, total)`` is called as the work advances (``progress.py``).
    """
    spec = spec.validated()
    check_camera(scene.camera)
    lights, notes = fog_lights(scene)
    method, reason = methods.resolve(scene, spec, lights, scene_materials(scene, objects))
    check_method(scene, spec, method)
    store_spec(scene, spec)
    spec = spec_of(scene)   # as stored (float32 properties): what every later refresh builds for
    progress("appended fog", 0, 1)
    skipped = merge_appended()   # first: the tables and groups are looked up by name below
    skipped += notes
    progress("lights and tables", 0, 1)
    groups.set_params(spec.beta_per_unit, spec.albedo, spec.anisotropy, world_light=spec.world_light)
    if bpy.data.node_groups.get(groups.SURFACE) is None:
        # The materials are wrapped around a Surface group without lights, which the lights' group then
        # replaces (``groups._install``): every node Blender's API adds to a material costs more the
        # bigger the groups it links (1 000 materials, 64 lights: 25.9 -> 16.1 s CPU,
        # benchmarks/apply_order.py).
        groups.build_surface([], [], images.all_table_images(spec.anisotropy), spec.passes)
    mats = scene_materials(scene, objects)
    for k, mat in enumerate(mats):
        progress("materials", k, len(mats))
        why = wrap_material(mat)
        if why:
            skipped.append((mat.name, why))
    progress("materials", len(mats), len(mats))
    progress("world", 0, 1)
    skipped += _build_scene_groups(scene, spec, lights, method, reason, progress=progress)
    if scene.world is None:
        skipped.append((scene.name, "has no World: no airlight on the background"))
    else:
        why = wrap_world(scene.world)
        if why:
            skipped.append((scene.world.name, why))
    skipped += follow_compositor(scene, rebuild=True)   # Cycles' denoiser kept off the fog's light
    if not lights and not sunsky.is_daylit(scene, spec):
        skipped.append((scene.name, "has no light taking part: the fog only dims"
                        + (" (and the glowing objects glow)" if getattr(method, "name", method) == "compositor"
                           and methods.compositor.glowing_objects(scene) else "")
                        + ("" if spec.layered or spec.world_light or spec.density <= 0.0 else
                           ", and the World is hidden behind it (the fog fills all space), so the picture is dark: "
                           "add a light, turn on World Light, or give the fog a top (Fog Top)")))
    skipped += [(scene.name, note) for note in scene_notes(scene, spec)]
    notes = not_modelled(scene, spec, lights, mats, method)
    surface = bpy.data.node_groups[groups.SURFACE]
    surface[CAVEATS_KEY] = json.dumps(notes)
    return skipped + [(scene.name, n) for n in notes]


GEOMETRY = ("MESH", "CURVE", "SURFACE", "META", "FONT", "VOLUME", "CURVES", "POINTCLOUD", "GREASEPENCIL")   # object
#                                                                              types with surfaces to render


def _rendered_geometry(scene):
    """The scene's objects that render geometry (``GEOMETRY``, not hidden from rendering)."""
    return [obj for obj in scene.objects if obj.type in GEOMETRY and not obj.hide_render]


def nearest_distance(scene):
    """The distance (units) from the camera to the nearest point of any rendered object's bounding box
    (``GEOMETRY``), or 0 without a camera or objects; 0 from inside one."""
    cam = scene.camera
    if cam is None:
        return 0.0
    eye = cam.matrix_world.translation
    best = math.inf
    for obj in _rendered_geometry(scene):
        box = [tuple(c) for c in obj.bound_box]
        lo = [min(c[k] for c in box) for k in range(3)]
        hi = [max(c[k] for c in box) for k in range(3)]
        try:
            local = obj.matrix_world.inverted() @ eye
        except ValueError:   # a singular (zero-scaled) object
            continue
        nearest = obj.matrix_world @ type(local)([min(max(local[k], lo[k]), hi[k]) for k in range(3)])
        best = min(best, (nearest - eye).length)
    return 0.0 if best == math.inf else best


def highest_z(scene):
    """The highest z (units) of any rendered object's bounding box, or None without objects."""
    tops = [max((obj.matrix_world @ type(obj.matrix_world.translation)(c)).z for c in obj.bound_box)
            for obj in _rendered_geometry(scene)]
    return max(tops) if tops else None


def scene_notes(scene, spec):
    """Notes on settings that make the picture useless in ``scene`` (the operator, the panel and ``render`` say
    them): a fog invisible at the scene's size, a fog opaque before the nearest object, a fog layer whose ground
    is above everything."""
    notes = []
    note = presets.invisible_fog_note(spec.beta_per_unit, scene_size(scene))
    if note:
        notes.append(note)
    note = presets.opaque_fog_note(spec.density, nearest_distance(scene) * spec.scene_scale)
    if note:
        notes.append(note)
    top = highest_z(scene) if spec.layered else None
    if top is not None and spec.ground_level > top:
        notes.append(f"Ground Level (z {spec.ground_level:.3g}) is above every object (the highest reaches z "
                     f"{top:.3g}): the whole scene lies under the fog layer's ground, where the layer's model does "
                     "not hold; set Ground Level to the ground's height")
    return notes


def _optical_distance(scene, spec):
    """light -> beta x its distance to the scene's camera (None without a camera)."""
    camera = scene.camera
    if camera is None:
        return None
    origin = camera.matrix_world.translation
    return lambda o: spec.beta_per_unit * (o.matrix_world.translation - origin).length


def not_modelled(scene, spec, lights, materials, method=None):
    """What the fog can't model in ``scene`` (``caveats.py``: light shafts where ``method`` (a method name)
    has none or they are off, their limits where it has them; glass and mirrors), as notes."""
    casting = bool(spec.shafts and getattr(method, "name", method) == "compositor")
    notes = [*caveats.shadow_notes(scene, lights, spec.beta_per_unit, max(scene_size(scene), 1e-6), casting,
                                   None if spec.shafts else "Light Shafts is off"),
             caveats.glass_note(materials, scene.objects),
             caveats.clip_note(scene, getattr(method, "name", method)),
             *caveats.multiple_notes(lights, spec.multiple_scattering, getattr(method, "name", method),
                                     view.has_shape, _optical_distance(scene, spec)),
             *caveats.glow_notes(methods.compositor.glowing_objects(scene), getattr(method, "name", method),
                                 scene.render.engine),
             *(f"{name}: {why}" for name, why in sunsky.notes(scene, spec, getattr(method, "name", method),
                                                              lights))]
    return [n for n in notes if n]


def stored_caveats():
    """The notes of ``not_modelled`` from the last Add/Update Fog (the panel shows them), [] if none."""
    surface = bpy.data.node_groups.get(groups.SURFACE)
    return json.loads(surface[CAVEATS_KEY]) if surface is not None and CAVEATS_KEY in surface else []


def apply_fog(scene, density, albedo=(1.0, 1.0, 1.0), anisotropy=0.0, method="nodes", objects=None,
              scene_scale=1.0, with_passes=False, error=predict.DEFAULT_QUALITY, world_light=False, shafts=True,
              multiple_scattering=False, progress=progress_.silent):
    """``apply`` with the spec's fields as arguments, for scripts: ``density`` (1/m), ``albedo``, ``anisotropy``
    (g), ``method`` ("auto", "nodes", "osl", "compositor"; this function's default is the node groups, the
    panel's and the command line's is Auto), ``scene_scale`` (m per unit), ``with_passes``, ``error`` (the
    Quality: a preset name or a target error; None is Exact), ``world_light``, ``shafts``, ``multiple_scattering``
    (Dense Fog).  See ``precompute/spec.py``."""
    spec = FogSpec(density=density, scene_scale=scene_scale, albedo=tuple(albedo), anisotropy=anisotropy,
                   method=method, quality=error, passes=with_passes, world_light=world_light, shafts=shafts,
                   multiple_scattering=multiple_scattering)
    return apply(scene, spec, objects, progress)


def follow_compositor(scene, rebuild=False):
    """The scene's compositor set-up as the built method needs it (``Method.follow``): the Compositor
    method's chain, else the denoiser's where Cycles denoises; returns [(name, note)]."""
    method = built_method() or methods.get("nodes")
    notes = method.follow(scene, rebuild)
    for other in methods.METHODS_BY_NAME.values():   # a method the scene changed from: what it left behind goes
        if other is not method:
            other.teardown(scene)
    return notes


_sync_errors = {}   # scene name -> why the last sync failed (the panel shows it), absent if it succeeded


def sync(scene, level="groups"):
    """Make the fog follow the scene's settings (``spec_of``): the params group, and at ``level`` "groups" or
    "rechoose" the scene groups (materials are not touched).  A failure (a setting the method can't serve)
    changes nothing, and is kept for the panel (``sync_error``) and returned."""
    try:
        spec = spec_of(scene)
        surface = bpy.data.node_groups.get(groups.SURFACE)
        if surface is not None and surface.library is not None:
            return None
        if spec.layered and level == "params":   # the layer's fog light is baked for the density and the top
            level = "groups"
        if level != "params" and surface is not None:
            lights = fog_lights(scene)[0]
            method, reason = resolve_method(scene, spec, lights)
            check_method(scene, spec, method)
            groups.set_params(spec.beta_per_unit, spec.albedo, spec.anisotropy, world_light=spec.world_light)
            _build_scene_groups(scene, spec, lights, method, reason, rechoose=level == "rechoose",
                                progress=progress_.ConsoleProgress(prefix="Analytic Fog: "))
            follow_compositor(scene, rebuild=True)
        else:
            groups.set_params(spec.beta_per_unit, spec.albedo, world_light=spec.world_light)
    except ValueError as e:
        _sync_errors[scene.name] = str(e)
        print(f"Analytic Fog: the fog keeps what it was built with: {e}")
        return str(e)
    except Exception as e:   # noqa: BLE001 - a fault of the add-on's: said, and the user's compositor spliced again
        why = f"the fog could not follow this change ({type(e).__name__}: {e}); Update Fog rebuilds it"
        _sync_errors[scene.name] = why
        traceback.print_exc()
        try:
            follow_compositor(scene, rebuild=True)
        except Exception:   # noqa: BLE001
            traceback.print_exc()
        return why
    _sync_errors.pop(scene.name, None)
    return None


def sync_error(scene):
    """Why the fog could not follow the scene's last settings change, or None."""
    return _sync_errors.get(scene.name)


def settings_error(scene):
    """Why the scene's fog settings can't be used (``spec_of``'s message: the operator's for the same values), or
    None.  The panel shows it before the fog is added (after, ``sync_error`` says it)."""
    try:
        spec_of(scene)
    except ValueError as e:
        return str(e)
    return None


def update_params(scene):
    """Push the scene's density, colour, scale and World Light into the shared params group."""
    return sync(scene, "params")


def set_anisotropy(scene, g):
    """Set the anisotropy and follow it: the lights keep their steps, now with g's models (materials are not
    touched).  Raises ValueError, changing nothing, for a g outside the range or one the method's models
    don't serve."""
    _set_and_sync(scene, anisotropy=g)


def set_method(scene, method):
    """Set the method and follow it: the lights keep their steps, now with ``method``'s models."""
    _set_and_sync(scene, method=method)


def set_passes(scene, with_passes):
    """Switch the fog passes on or off and follow it (materials are not touched)."""
    _set_and_sync(scene, passes=bool(with_passes))


def set_quality(scene, quality):
    """Set the Quality and choose every light's models again (materials are not touched)."""
    _set_and_sync(scene, "rechoose", quality=validate_quality(quality))


def _set_and_sync(scene, level="groups", **changes):
    """Store ``changes`` to the scene's spec and sync; raises ValueError (the settings kept) if it fails."""
    old = spec_of(scene)
    new = old.replace(**changes)
    surface = bpy.data.node_groups.get(groups.SURFACE)
    if surface is not None:
        lights = fog_lights(scene)[0]
        check_method(scene, new, resolve_method(scene, new, lights)[0])
    store_spec(scene, new)
    why = sync(scene, level)
    if why is not None:
        store_spec(scene, old)
        raise ValueError(why)


def refresh_lights(scene, rechoose=False, this_frame=False):
    """Rebuild the scene groups if the fog lights, their models or the camera changed; materials are not
    touched.  Called from the depsgraph handler: when nothing changed it only compares names (and sets the
    Compositor method's windows).  ``rechoose``: also choose the lights' models (and Auto's method) again from
    the view (camera, lights or objects moved); the handler does that after the scene has stopped changing
    (``handlers.py``).  ``this_frame``: the handlers' calls, which do not step through frames (the windows
    of an animation grow by this frame's; saving the file computes them over the range again)."""
    surface = bpy.data.node_groups.get(groups.SURFACE)
    if surface is None or surface.library is not None:
        return
    _rebuilt.discard(scene.name)
    try:
        spec = spec_of(scene)
        _build_scene_groups(scene, spec, fog_lights(scene)[0], rechoose=rechoose, this_frame=this_frame,
                            progress=progress_.ConsoleProgress(prefix="Analytic Fog: "),
                            bake_in_line=bpy.app.background)
    except ValueError as e:
        _sync_errors[scene.name] = str(e)
        return
    except TablesMissing:   # with a window: baked by the cancellable operator, which then syncs
        if not bake_declined(scene):
            props.request_sync(scene, "rechoose" if rechoose else "groups")
        return
    # the engine or the denoiser flag may have changed; rebuilt groups need the chain built anew
    follow_compositor(scene, rebuild=scene.name in _rebuilt)


def grow_windows(scene):
    """The frame changed (an animation plays or renders): the built method follows (``Method.frame_change``:
    the Compositor method's windows grow by this frame's, so a light moved since they were computed over the
    range is not cut on this frame)."""
    method = built_method()
    if method is None:
        return
    lights = _in_groups(fog_lights(scene)[0], stored_choice() or {"lights": {}})
    method.frame_change(scene, lights)


def remove_fog(scene, progress=progress_.silent):
    """Take the fog out of every material, light and world, and delete its node groups and tables."""
    mats = list(bpy.data.materials)
    for k, mat in enumerate(mats):
        progress("materials", k, len(mats))
        unwrap_material(mat)
    progress("materials", len(mats), len(mats))
    progress("world", 0, 1)
    for world in bpy.data.worlds:
        unwrap_world(world)
        if sunsky.PROBE_KEY in world:   # the sky's mean colour, kept for the fog layer
            del world[sunsky.PROBE_KEY]
    progress("lights", 0, 1)
    for light in bpy.data.lights:
        unwrap_light(light)
    for s in bpy.data.scenes:   # first: the compositor's chains use the fog's compositor groups
        compositor.teardown(s)
    for name in comp_fog.all_group_names() + groups.all_group_names():
        ng = bpy.data.node_groups.get(name)
        if ng is not None:
            bpy.data.node_groups.remove(ng)
    for name in images.table_names():
        img = bpy.data.images.get(name)
        if img is not None:
            bpy.data.images.remove(img)
    shadow_maps.remove_unused()
    for name in osl.text_names():
        text = bpy.data.texts.get(name)
        if text is not None:
            bpy.data.texts.remove(text)
    use_osl(scene, False)
    for s in bpy.data.scenes:
        passes.remove_view_layer_aovs(s, AOV_KINDS)


props.set_sync(sync)   # the settings' changes reach the fog through ``sync`` (props never imports this module)
