"""Adding, updating and removing the fog on a scene (what the operators, handlers and command line call)."""
import functools
import json

import bpy

from ..nodes import comp_fog, compositor, dedupe, groups, images, osl, passes
from ..nodes.light import unwrap_light, wrap_light
from ..nodes.material import unwrap_material, wrap_material
from ..nodes.owned import is_fogged
from ..nodes.world import unwrap_world, wrap_world
from ..precompute import medium, predict, presets, rungs, spot
from . import progress as progress_
from . import view

SUPPORTED_LIGHTS = ("POINT", "SPOT")
OSL_WAS = "analytic_fog_osl_was"   # scene custom property: Cycles' OSL switch before the OSL method set it
LIGHTS_KEY = "analytic_fog_lights"  # on the Surface group: the lights, their models and the camera it was built for
PREFERENCE_KEY = "analytic_fog_preference"   # on the Surface group: the method preference it was built with
PASSES_KEY = "analytic_fog_passes"   # on the Surface group: built with the fog passes (AOV outputs)
CHOICE_KEY = "analytic_fog_choice"   # on the Surface group: the Quality, {light: [step, predicted error]}, the total
AOV_KINDS = dict(passes.AOVS + comp_fog.AOVS + comp_fog.EEVEE_AOVS)   # every AOV the fog adds to view layers
COMPOSITOR = "compositor"   # the method that adds the fog's light in the compositor (``nodes/comp_fog.py``)
MANY_LIGHTS = 8   # from this many fog lights on, the panel and (in Cycles) the report suggest the Compositor method
#                   (16 lights in Cycles: 29x the fog-free render with node groups, 1.6x with the compositor;
#                   README "The Compositor method")


def fog_lights(scene):
    """(lights taking part, [(name, reason)] for lights left out or worth a note)."""
    lights, notes = [], []
    for obj in scene.objects:
        if obj.type != "LIGHT":
            continue
        data = obj.data
        settings = getattr(data, "analytic_fog", None)
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
            s = obj.matrix_world.to_scale()
            if view.is_spot(obj) and obj.matrix_world.to_3x3().determinant() < 0.0:
                notes.append((obj.name, "is mirrored (negative scale): its cone in the fog points the other way"))
            elif data.type == "POINT" and max(s) - min(s) > 1e-6 * max(abs(max(s)), 1e-30):
                notes.append((obj.name, "is scaled non-uniformly: a point light's fog ignores scale"))
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


def _signature(scene, lights, models, preference, with_passes):
    camera = scene.camera
    extra = []
    if preference == COMPOSITOR:   # what the compositor's graph is built for (the rest it reads by drivers)
        c = scene.cycles
        extra = [f"compositor:{scene.render.engine}:{c.pixel_filter_type}:{comp_fog.horizontal_fit(scene)}:"
                 f"{camera.data.sensor_fit}"]
    return "|".join([groups.code_fingerprint()] + [f"{o.name_full}:{'/'.join(r.name for r in mod)}"
                                                    for o, mod in zip(lights, models)]
                     + ["camera:" + (camera.name_full if camera else ""), f"passes:{with_passes}"] + extra)


def quality_value(quality):
    """The stored form of a Quality: a preset name ("draft", "final", "exact") or a number; raises ValueError."""
    predict.target_error(quality)
    return "exact" if quality is None else quality


def _budget(scene, preference, lights):
    """What the renderer can hold (predict.Budget) with ``lights``, or None (Cycles' SVM, the Compositor
    method): EEVEE's uniform block, Cycles OSL's shader group layers."""
    spots = [view.is_spot(o) for o in lights]
    if preference == COMPOSITOR:   # the compositor's groups hold any number; EEVEE's materials: dimming_lights
        return None
    if scene.render.engine == groups.EEVEE_ENGINE:
        return groups.eevee_budget(groups.get_anisotropy(), spots)
    if preference == "osl":
        return groups.osl_budget(spots)
    return None


def choose_models(scene, lights, preference, quality):
    """Each light's models (rungs.LightModels) at ``quality``, and the choice for reports.

    The view is sampled by ray casts (``view.py``) and every light's step down
    the ladder chosen by the predicted error (``predict.py``).  In EEVEE the
    steps must also fit its uniform block (``groups.eevee_budget``), with Cycles' OSL its shader group's
    layers (``groups.osl_budget``): lights
    step down beyond the target, least error first, until they do.  Returns
    (models, choice) with choice = {"lights": {name: [step, error]}, "rims": {name: point count} of the spots
    whose glow's rim takes fewer than spot.RIM_NODES points, "error": total, "target": t, "engine": the render
    engine chosen for, "limited": what forced steps beyond the target, or None}.
    """
    target = predict.target_error(quality)
    engine = scene.render.engine
    budget = _budget(scene, preference, lights)
    steps = [0] * len(lights)
    choice = {"target": target, "error": 0.0, "lights": {}, "rims": {}, "engine": engine, "limited": None}
    if lights and (target is not None or (budget is not None and not budget.fits(steps))):
        samples = view.view_samples(scene, lights)
        pred = predict.predict(samples, view.light_intensities(lights), groups.get_beta(), target, budget,
                               groups.get_anisotropy())
        steps = [int(k) for k in pred.steps]
        choice["error"] = pred.error
        choice["lights"] = {o.name: [int(k), float(e)] for o, k, e in zip(lights, pred.steps, pred.light_error)}
        choice["rims"] = {o.name: int(n) for o, n in zip(lights, pred.rims)   # (a light off keeps RIM_NODES)
                          if view.is_spot(o) and n != spot.RIM_NODES}
        if pred.limited or not pred.fits:
            choice["limited"] = budget.name + ("" if pred.fits else ": too many lights even with every light off")
    else:
        choice["lights"] = {o.name: [0, 0.0] for o in lights}
    return _models(preference, lights, steps, choice["rims"]), choice


def _models(preference, lights, steps, rims):
    """Each light's models at its step, a spot's glow with its rim's point count (``rims``: by name)."""
    g = groups.get_anisotropy()
    return [rungs.choose(preference, k, g, view.is_spot(o), rims.get(o.name, spot.RIM_NODES))
            for o, k in zip(lights, steps)]


def stored_choice():
    """The choice the scene groups were last built with (see choose_models, plus its "quality"), or None."""
    surface = bpy.data.node_groups.get(groups.SURFACE)
    if surface is None or CHOICE_KEY not in surface:
        return None
    return json.loads(surface[CHOICE_KEY])


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
    rims = choice.get("rims", {})
    for name, (step, err) in sorted(choice["lights"].items()):
        rim = f", {rims[name]}-point rim" if name in rims else ""
        lines.append(f"  {name}: {rungs.STEPS[step]}{rim}" + (f" (leaves out up to {err:.2%})" if step else
                                                               f" (moves up to {err:.2%})" if rim else ""))
    return lines


def _in_groups(lights, choice):
    """The ``lights`` the fog's groups hold: all but those ``choice`` stepped out to fit a budget (rungs.LEFT_OUT;
    a light the choice does not know is in)."""
    return [o for o in lights if choice["lights"].get(o.name, [0])[0] != rungs.LEFT_OUT]


def _build_scene_groups(scene, lights, preference, with_passes, quality=predict.DEFAULT_QUALITY, rechoose=True,
                        this_frame=False):
    """(Re)build the Surface and World groups for ``lights``, their models and the fog passes (on or off)
    unless built for them already; per-light groups no longer used are deleted, lights that no longer
    take part lose the fog's attenuation, Cycles' OSL is switched on while some model needs it, and the
    view layers have the passes' AOVs while the passes are on.

    ``quality``: the target error of the lights' models.  ``rechoose``: choose the lights' models again
    from the view (``choose_models``); else keep the stored steps (lights new to the fog get the full
    models).  Returns [(name, reason)] for lights left unfogged, clashing AOVs and a choice the render
    engine limited (EEVEE's uniform block).
    """
    old = stored_choice()
    kept = None
    if not (rechoose or old is None or old.get("quality") != quality_value(quality)
            or (old.get("engine") == groups.EEVEE_ENGINE) != (scene.render.engine == groups.EEVEE_ENGINE)):
        kept = [old["lights"].get(o.name, [0, 0.0])[0] for o in lights]
        budget = _budget(scene, preference, lights)
        if budget is not None and not budget.fits(kept):   # e.g. the method switched to OSL: choose again
            kept = None
    if kept is None:
        models, choice = choose_models(scene, lights, preference, quality)
    else:
        rims = {o.name: old["rims"][o.name] for o in lights if o.name in old.get("rims", {})}
        models = _models(preference, lights, kept, rims)
        choice = dict(old, lights={o.name: old["lights"].get(o.name, [0, 0.0]) for o in lights}, rims=rims)
    choice["quality"] = quality_value(quality)
    # lights stepped out of the groups to fit a budget (rungs.LEFT_OUT) keep their own dimming (wrap_light)
    in_groups = _in_groups(lights, choice)
    grouped_models = [mod for o, mod in zip(lights, models) if o in in_groups]
    in_compositor = preference == COMPOSITOR
    # the materials' lights: none in the Compositor method (Cycles' lights dim their own direct light), in
    # EEVEE's only the shared dimming of those that fit its uniform block
    in_shaders = dimming_lights(scene, in_groups, preference) if in_compositor else (in_groups, grouped_models)
    signature = _signature(scene, in_groups, grouped_models, preference, with_passes) + (
        "|dimming:" + ",".join(o.name_full for o in in_shaders[0]) if in_compositor else "")
    # where the compositor evaluates each term (``view.windows``); over an animation's frames, or (the handlers'
    # ``this_frame``: no stepping through frames) this frame's, added to the windows the groups have
    partial = this_frame and view.animated(scene)
    windows = view.windows(scene, in_groups, [scene.frame_current] if partial else None) if in_compositor else None
    surface = bpy.data.node_groups.get(groups.SURFACE)
    if (surface is None or bpy.data.node_groups.get(groups.WORLD) is None
            or surface.get(LIGHTS_KEY) != signature
            or (in_compositor and bpy.data.node_groups.get(comp_fog.FOG_GROUP) is None)):
        imgs = images.all_table_images(groups.get_anisotropy())
        aovs = functools.partial(comp_fog.add_surface_aovs, engine=scene.render.engine) if in_compositor else None
        surface = groups.build_surface(*in_shaders, imgs, with_passes, extra=aovs)
        if in_compositor:
            imgs = comp_fog.build_fog_group(scene, in_groups, grouped_models, imgs,
                                            view.full_windows(in_groups) if partial else windows, partial)
        surface[LIGHTS_KEY] = signature
        surface[PREFERENCE_KEY] = preference
        surface[PASSES_KEY] = with_passes
        groups.build_world(*(([], []) if in_compositor else in_shaders), scene.camera, imgs, with_passes)
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
    elif windows is not None:
        comp_fog.set_windows(in_groups, windows, grow=partial)
    if surface.get(CHOICE_KEY) != json.dumps(choice):
        surface[CHOICE_KEY] = json.dumps(choice)
    use_osl(scene, any(rungs.needs_osl(mod) for mod in models))
    notes = [(light.data.name, why) for light in lights if (why := wrap_light(light.data))]
    if (limit := limit_text(choice)) is not None:
        notes.append((scene.render.engine, f"{limit}, predicted error {choice['error']:.2%} "
                                           "(render --explain lists each light's models)"))
    if in_compositor and scene.render.engine == groups.EEVEE_ENGINE and len(in_shaders[0]) < len(in_groups):
        notes.append((scene.render.engine, f"{len(in_groups) - len(in_shaders[0])} of {len(in_groups)} lights are "
                      "not in the materials' shared dimming of direct light (EEVEE's uniform block): their direct "
                      "light is dimmed as the nearer lights' is"))
    if not in_compositor and scene.render.engine == "CYCLES" and len(in_groups) >= MANY_LIGHTS:
        notes.append((scene.render.engine, many_lights_note(in_groups, choice)))
    aovs = (passes.AOVS if with_passes else ()) + (comp_fog.aovs(scene.render.engine) if in_compositor else ())
    passes.remove_view_layer_aovs(scene, AOV_KINDS, keep=[name for name, _ in aovs])
    return notes + passes.add_view_layer_aovs(scene, aovs)


def many_lights_note(lights, choice):
    """Why the Compositor method suits ``lights`` (as many as MANY_LIGHTS or more) in Cycles better than the
    materials' node groups or OSL: what each fogged material holds (``groups.material_nodes``)."""
    nodes = groups.material_nodes([choice["lights"].get(o.name, [0])[0] for o in lights],
                                  [view.is_spot(o) for o in lights])
    return (f"{len(lights)} lights: each fogged material holds about {nodes:,} fog nodes and evaluates them on "
            "every sample, and Cycles' set-up before the first sample grows with their square (64 lights on 4 "
            "materials: about 20 s of CPU per render, 256 lights: about 30 min); the Compositor method's "
            "materials do not depend on the lights (1.5-1.9x the fog-free render at 16 to 64 lights)")


def dimming_lights(scene, lights, preference):
    """The Compositor method's materials' lights: ([], []) in Cycles, whose lights dim their own direct light
    (``light.py``); in EEVEE, which has no light node trees, (lights, models) of the lights whose direct
    light the materials dim by the shared weights of ``shading.surface_fog`` (rungs step "off": no fog light,
    which the compositor adds), as many as EEVEE's uniform block holds (``groups.eevee_budget``), the
    brightest at the camera first (radiant intensity over squared distance)."""
    if scene.render.engine != groups.EEVEE_ENGINE or not lights:
        return [], []
    spots = [view.is_spot(o) for o in lights]
    budget = groups.eevee_budget(0.0, spots)   # step "off" has no phase weight: its cost does not depend on g
    eye = scene.camera.matrix_world.translation
    intensity = view.light_intensities(lights).sum(axis=1)
    order = sorted(range(len(lights)), key=lambda i: -intensity[i] / max(
        (lights[i].matrix_world.translation - eye).length_squared, 1e-12))
    steps = [rungs.LEFT_OUT] * len(lights)
    for i in order:
        steps[i] = rungs.OFF
        if not budget.fits(steps):
            steps[i] = rungs.LEFT_OUT
            break
    kept = [i for i in range(len(lights)) if steps[i] == rungs.OFF]
    g = groups.get_anisotropy()
    return [lights[i] for i in kept], [rungs.choose(preference, rungs.OFF, g, spots[i]) for i in kept]


def merge_appended():
    """Fold fog data appended from another fogged file onto this file's copies (``dedupe``).

    Returns [(name, reason)] notes for objects the other file's drivers pulled in.
    """
    _, pulled = dedupe.merge_duplicates()
    return [(name, "came in with fog appended from another file (its drivers' target); delete it if unwanted")
            for name in pulled]


def apply_fog(scene, density, albedo=(1.0, 1.0, 1.0), anisotropy=0.0, method="nodes", objects=None,
              scene_scale=1.0, with_passes=False, error=predict.DEFAULT_QUALITY, world_light=False,
              progress=progress_.silent):
    """Add (or update) the fog on ``scene``; adding twice is the same as once.

    ``method``: the user's preference for the models (``rungs.PREFERENCES``):
    "nodes" (node-group tables, Cycles and EEVEE), "osl" (the glow by
    quadrature in an OSL script, Cycles only; switches Cycles' OSL on) or "compositor" (the node
    groups' models once per pixel in the compositor, Cycles and EEVEE: ``nodes/comp_fog.py``).
    ``objects``: fog only their materials (default: all in the scene).
    ``scene_scale``: real metres per Blender unit (the groups get density *
    scene_scale per unit).  Returns a list of (data-block name, reason) for
    what was left out or fogged with a caveat.  Raises ValueError for bad
    settings before anything is changed.  ``with_passes``: write the fog
    passes (``passes.py``; they cost render time).  ``error``: the Quality, a
    target relative error or a preset name of ``predict.QUALITY`` ("exact" or
    None: every light fully modelled); each light gets the cheapest models whose
    predicted error stays within it (``choose_models``).  ``world_light``: the World keeps lighting
    surfaces through the fog (default off: the fog fills all space and extinguishes it, as Cycles'
    World volume does; ``shading.shade_background``).  ``progress(stage, done, total)``
    is called as the work advances (``progress.py``).
    """
    fog = medium.medium(density, albedo, anisotropy, scene_scale)
    rungs.choose(method, 0, fog.g)   # an unknown preference or unserved g raises here, before anything changes
    predict.target_error(error)
    check_camera(scene.camera)
    if method == COMPOSITOR:
        check_compositor_method(scene, with_passes)
    progress("appended fog", 0, 1)
    skipped = merge_appended()   # first: the tables and groups are looked up by name below
    lights, notes = fog_lights(scene)
    skipped += notes
    progress("lights and tables", 0, 1)
    groups.set_params(fog.beta, fog.albedo, fog.g, world_light=bool(world_light))
    if bpy.data.node_groups.get(groups.SURFACE) is None:
        # The materials are wrapped around a Surface group without lights, which the lights' group then
        # replaces (``groups._install``): every node Blender's API adds to a material costs more the
        # bigger the groups it links (1 000 materials, 64 lights: 25.9 -> 16.1 s CPU,
        # benchmarks/apply_order.py).
        groups.build_surface([], [], images.all_table_images(fog.g), with_passes)
    mats = scene_materials(scene, objects)
    for k, mat in enumerate(mats):
        progress("materials", k, len(mats))
        why = wrap_material(mat)
        if why:
            skipped.append((mat.name, why))
    progress("materials", len(mats), len(mats))
    progress("world", 0, 1)
    skipped += _build_scene_groups(scene, lights, method, with_passes, error)
    if scene.world is None:
        skipped.append((scene.name, "has no World: no airlight on the background"))
    else:
        why = wrap_world(scene.world)
        if why:
            skipped.append((scene.world.name, why))
    skipped += follow_compositor(scene, rebuild=True)   # Cycles' denoiser kept off the fog's light
    if not lights:
        skipped.append((scene.name, "has no point light taking part: the fog only dims"))
    note = presets.invisible_fog_note(fog.beta, scene_size(scene))
    if note:
        skipped.append((scene.name, note))
    return skipped


def follow_compositor(scene, rebuild=False):
    """The scene's compositor set-up as the fog's method needs it (``compositor.follow``): the Compositor
    method's chain, else the denoiser's where Cycles denoises; returns [(name, note)]."""
    surface = bpy.data.node_groups.get(groups.SURFACE)
    in_compositor = surface is not None and surface.get(PREFERENCE_KEY) == COMPOSITOR
    fog = bpy.data.node_groups.get(comp_fog.FOG_GROUP) if in_compositor else None
    notes = compositor.follow(scene, rebuild, fog)
    old = bpy.data.node_groups.get(comp_fog.FOG_GROUP)
    if not in_compositor and old is not None and old.users == 0:   # the method changed from Compositor
        bpy.data.node_groups.remove(old)
    return notes


def check_compositor_method(scene, with_passes):
    """Raise ValueError unless ``scene`` can take the Compositor method (``comp_fog.py``'s limits)."""
    if scene.render.engine not in ("CYCLES", groups.EEVEE_ENGINE):
        raise ValueError(f"the Compositor method needs Cycles or EEVEE, not {scene.render.engine}")
    if scene.camera.data.type != "PERSP":
        raise ValueError(f"the Compositor method needs a perspective camera ({scene.camera.name!r} is "
                         f"{scene.camera.data.type.lower()}): use the Node Groups method")
    if with_passes:
        raise ValueError("the Compositor method adds the fog's light in the compositor, so there are no fog "
                         "passes: switch Fog Passes off or use the Node Groups method")


def update_params(scene):
    """Push the scene's density, colour and scale into the shared params group."""
    s = scene.analytic_fog
    groups.set_params(s.density * s.scene_scale, tuple(s.color), world_light=s.world_light)


_KEEP = object()   # _rebuild: keep the setting the scene groups were built with


def _rebuild(scene, surface, preference=_KEEP, with_passes=_KEEP, quality=_KEEP, rechoose=False,
             this_frame=False):
    """Rebuild the scene groups (materials are not touched) for the settings given, keeping the rest as
    ``surface`` (the Surface group) was built."""
    choice = stored_choice() or {}
    _build_scene_groups(scene, fog_lights(scene)[0],
                        surface.get(PREFERENCE_KEY, "nodes") if preference is _KEEP else preference,
                        bool(surface.get(PASSES_KEY, False)) if with_passes is _KEEP else with_passes,
                        choice.get("quality", predict.DEFAULT_QUALITY) if quality is _KEEP else quality,
                        rechoose=rechoose, this_frame=this_frame)


def set_anisotropy(scene, g):
    """The user changed the anisotropy: the lights keep their steps, now with g's models (materials are not
    touched).  Raises ValueError, changing nothing, for a g outside the range or one the method's models
    don't serve."""
    fog = medium.medium(1.0, (1.0, 1.0, 1.0), g)
    surface = bpy.data.node_groups.get(groups.SURFACE)
    if surface is None or fog.g == groups.get_anisotropy():
        return
    rungs.choose(surface.get(PREFERENCE_KEY, "nodes"), 0, fog.g)
    groups.set_anisotropy(fog.g)
    _rebuild(scene, surface)


def set_method(scene, method):
    """The user changed the method preference: the lights keep their steps, now with ``method``'s models."""
    surface = bpy.data.node_groups.get(groups.SURFACE)
    if surface is not None:
        rungs.choose(method, 0, groups.get_anisotropy())   # raises (nothing changed) for a g it can't serve
        if method == COMPOSITOR:
            check_compositor_method(scene, bool(surface.get(PASSES_KEY, False)))
        _rebuild(scene, surface, preference=method)
        follow_compositor(scene, rebuild=True)


def set_passes(scene, with_passes):
    """The user switched the fog passes on or off: rebuild the scene groups (materials are not touched)."""
    surface = bpy.data.node_groups.get(groups.SURFACE)
    if surface is not None:
        if with_passes and surface.get(PREFERENCE_KEY) == COMPOSITOR:
            check_compositor_method(scene, with_passes)
        _rebuild(scene, surface, with_passes=with_passes)


def set_quality(scene, quality):
    """The user changed the Quality: choose every light's models again (materials are not touched)."""
    surface = bpy.data.node_groups.get(groups.SURFACE)
    if surface is not None and surface.library is None:
        _rebuild(scene, surface, quality=quality, rechoose=True)


def refresh_lights(scene, rechoose=False, this_frame=False):
    """Rebuild the scene groups if the fog lights, their models or the camera changed; materials are not
    touched.  Called from the depsgraph handler: when nothing changed it only compares names (and sets the
    Compositor method's windows).  ``rechoose``: also choose the lights' models again from the view
    (camera, lights or objects moved); the handler does that after the scene has stopped changing
    (``handlers.py``).  ``this_frame``: the handlers' calls, which do not step through frames (the windows
    of an animation grow by this frame's; saving the file computes them over the range again)."""
    surface = bpy.data.node_groups.get(groups.SURFACE)
    if surface is None or surface.library is not None:
        return
    _rebuild(scene, surface, rechoose=rechoose, this_frame=this_frame)
    follow_compositor(scene)   # the engine or the denoiser flag may have changed


def grow_windows(scene):
    """The frame changed (an animation plays or renders): the Compositor method's windows grow by this frame's
    (``view.windows``), so a light moved since they were computed over the range is not cut on this frame."""
    surface = bpy.data.node_groups.get(groups.SURFACE)
    if surface is None or surface.get(PREFERENCE_KEY) != COMPOSITOR or comp_fog.FOG_GROUP not in bpy.data.node_groups:
        return
    lights = _in_groups(fog_lights(scene)[0], stored_choice() or {"lights": {}})
    comp_fog.set_windows(lights, view.windows(scene, lights, [scene.frame_current]), grow=True)


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
    for name in osl.text_names():
        text = bpy.data.texts.get(name)
        if text is not None:
            bpy.data.texts.remove(text)
    use_osl(scene, False)
    for s in bpy.data.scenes:
        passes.remove_view_layer_aovs(s, AOV_KINDS)
