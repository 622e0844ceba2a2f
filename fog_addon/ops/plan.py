"""The plan of a build: the lights taking part, the method, and each light's models at the Quality.

spec -> lights (``fog_lights``) -> method (``resolve_method``: ``methods.resolve``, Auto chooses by the scene)
-> ``check_method`` -> plan (``plan``: each light's models, ``choose_models`` from the view and ``predict.py``,
within the method's budget) -> ``build.build_scene_groups``.  The Surface group keeps the choice
(``stored_choice``) and the method (``built_method``) it was built with.
"""
import json
import math
from typing import Any, NamedTuple

import bpy

from .. import escape, methods, view
from ..nodes import budgets, groups
from ..precompute.model import predict, rungs
from ..precompute.physics.spot import spot
from .left_out import (dense_fog, dense_served, emitters_dense, glows_emitters, kept_scales, sees_past_glass,
                       shadow_fog, with_other)

SUPPORTED_LIGHTS = ("POINT", "SPOT", "AREA")
PREFERENCE_KEY = "analytic_fog_preference"   # on the Surface group: the method it was built with (methods.get)
CHOICE_KEY = "analytic_fog_choice"   # on the Surface group: the Quality, {light: [step, predicted error]}, the total,
#                                      the method and why (Auto)
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
                near = AT_CAMERA * view.scene_size(scene)
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


def scene_materials(scene, objects=None):
    """Materials of ``objects`` (default: every object in the scene), each once."""
    mats = []
    for obj in scene.objects if objects is None else objects:
        for slot in getattr(obj, "material_slots", ()):
            if slot.material is not None and slot.material not in mats:
                mats.append(slot.material)
    return mats


def choose_models(scene, spec, method, lights, budget=None, previous=None, judged=None):
    """Each light's models (rungs.LightModels) at the spec's Quality with ``method``, and the choice for reports.

    The view is sampled by ray casts (``view.py``) and every light's step down
    the ladder chosen by the predicted error (``predict.py``).  Where the method has a budget
    (``method.budget``: EEVEE's uniform block, Cycles OSL's shader group layers), lights
    step down beyond the target, least error first, until they fit.  Dense Fog is chosen per light as well
    (``dense_fog``).  Returns (models, choice) with choice = {"lights": {name: [step, error]}, "rims": {name: point
    count} of the spots whose glow's rim takes fewer than spot.RIM_NODES points, "error": total, "target": t,
    "engine": the render engine chosen for, "limited": what forced steps beyond the target, or None, and
    ``dense_fog``'s "thin", "dense": its account of the multiply scattered light left out}.  ``budget``: this budget
    instead of the method's (the viewport's preview: ``preview_models``).  ``previous``: the stored choice, whose
    Dense Fog scales a light keeps while its new one is within a step of it (``left_out.dense_fog``).  ``judged``:
    a dict that keeps the view's samples, the scales and the lights' terms for another choice of the same plan (the
    preview's), which then takes them instead of judging the same view again.
    """
    target = spec.target_error
    engine = scene.render.engine
    budget = method.budget(scene, spec, lights) if budget is None else budget
    steps = [0] * len(lights)
    choice = {"target": target, "error": 0.0, "lights": {}, "rims": {}, "engine": engine, "limited": None}
    samples, fog = None, {}
    served = dense_served(spec, method, engine)
    dense = any(served(o) and not view.has_shape(o) for o in lights)   # (the predictor's Dense Fog: point lights)
    judged = {} if judged is None else judged
    # each served light's Dense Fog field scaled by the share the surfaces leave, as the ladder judges it and builds it
    scaled = [o for o in lights if served(o)]
    scales = _judged(judged, ("scales", tuple(o.name for o in scaled)), lambda: escape.field_scales(
        scene, spec, scaled, previous=((previous or {}).get("dense") or {}).get("scales")))
    if lights and (target is not None or (budget is not None and not budget.fits(steps))):
        past = sees_past_glass(scene, method)
        viewed = (tuple(o.name for o in lights), past)   # (the samples of another view are another view's)
        seen = _judged(judged, ("view", viewed), lambda: view.view_samples(
            scene, lights, grid=view.judged_grid(scene, len(lights)), past_glass=past))
        samples = _judged(judged, ("samples", viewed, glows_emitters(scene, method)),
                          lambda: with_other(scene, spec, seen, method))
        scale = [scales.get(o.name, 1.0) for o in lights] if dense else None
        args = (samples, view.light_intensities(lights), spec.beta_per_unit)
        terms = _judged(judged, ("terms", viewed, dense, None if scale is None else tuple(scale)),
                        lambda: predict.light_terms(*args, spec.anisotropy, spec.grey_albedo if dense else None, scale))
        pred = predict.predict(*args, target, budget, spec.anisotropy, terms=terms)
        steps = [int(k) for k in pred.steps]
        fog = {"dense" if dense else "single": pred.fog, **({"single": pred.single} if pred.single is not None else {})}
        choice["error"] = pred.error
        choice["lights"] = {o.name: [int(k), float(e)] for o, k, e in zip(lights, pred.steps, pred.light_error)}
        choice["rims"] = {o.name: int(n) for o, n in zip(lights, pred.rims)   # (a light off keeps RIM_NODES)
                          if view.is_spot(o) and n != spot.RIM_NODES}
        if pred.limited or not pred.fits:
            choice["limited"] = budget.name + ("" if pred.fits else ": too many lights even with every light off")
    else:
        choice["lights"] = {o.name: [0, 0.0] for o in lights}
    # (where a budget forced steps beyond the target, thin lights are judged against the target alone)
    choice.update(dense_fog(scene, spec, method, lights, samples, 0.0 if choice["limited"] else choice["error"],
                            **fog, scales=scales))
    choice["error"] += choice["dense"]["missing"] + choice["dense"].get("surplus_missing", 0.0)
    return _models(spec, method, lights, steps, choice["rims"], set(choice["thin"]), choice["dense"]["scales"]), choice


def _judged(judged, key, compute):
    """``judged[key]``, computed once (``choose_models``' ``judged``)."""
    if key not in judged:
        judged[key] = compute()
    return judged[key]


def _models(spec, method, lights, steps, rims, thin=frozenset(), scales=None):
    """Each light's models at its step, a spot's glow with its rim's point count (``rims``: by name), Dense Fog
    left out for the lights ``thin`` names and its field scaled by ``scales`` (by name; 1 for the others)."""
    scales = scales or {}
    return [rungs.choose(method.preference, k, spec.anisotropy, view.light_kind(o), rims.get(o.name, spot.RIM_NODES),
                         multiple_albedo=None if o.name in thin else spec.multiple_albedo,
                         multiple_scale=scales.get(o.name, 1.0),
                         cone=view.spot_cone(o) if view.is_spot(o) else None)
            for o, k in zip(lights, steps)]


def stored_choice():
    """The choice the scene groups were last built with (see choose_models, plus its "quality"), or None."""
    surface = bpy.data.node_groups.get(groups.SURFACE)
    if surface is None or CHOICE_KEY not in surface:
        return None
    return json.loads(surface[CHOICE_KEY])


def lights_in_groups(lights, choice):
    """The ``lights`` the fog's groups hold: all but those ``choice`` stepped out to fit a budget (rungs.LEFT_OUT;
    a light the choice does not know is in)."""
    return [o for o in lights if choice["lights"].get(o.name, [0])[0] != rungs.LEFT_OUT]


def preview_models(scene, spec, lights, budget, judged=None):
    """(lights, models, choice) of the viewport's preview within ``budget`` (``Method.preview_budget``), or None
    without lights: the Node Groups method's models of the lights that matter most to the picture, chosen as the
    Quality chooses (``choose_models``) within the budget; the lights it leaves off are not in it
    (``choice["lights"]`` gives each light's step and what it leaves out)."""
    if not lights:
        return None
    nodes = methods.get("nodes")
    models, choice = choose_models(scene, spec, nodes, lights, budget, judged=judged)
    kept = [(o, mod) for o, mod in zip(lights, models) if choice["lights"][o.name][0] < rungs.OFF]
    return [o for o, _ in kept], [mod for _, mod in kept], choice


class Plan(NamedTuple):
    """What a method builds (``Method.build``): the lights' models, where they go, and the choice for reports."""
    lights: list              # the lights taking part
    models: list              # their models (rungs.LightModels)
    choice: dict              # ``choose_models``'s, with "quality", "method" and "method_reason"
    in_groups: list           # the lights the fog's groups hold (``lights_in_groups``)
    grouped_models: list      # their models
    shader_lights: list       # the lights the materials' and World's groups hold (``Method.shader_lights``)
    shader_models: list
    windows: Any              # where the compositor evaluates each term (``view.windows``), or None
    partial: bool             # the windows are this frame's only (the handlers')
    this_frame: bool          # a handler's rebuild, which must not step through the frames (``plan``)
    preview: Any = None       # (lights, models, choice) of the viewport's preview (``preview_models``), or None


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
            or (old.get("engine") == budgets.EEVEE_ENGINE) != (scene.render.engine == budgets.EEVEE_ENGINE)):
        kept = [old["lights"].get(o.name, [0, 0.0])[0] for o in lights]
        budget = method.budget(scene, spec, lights)
        if budget is not None and not budget.fits(kept):   # e.g. the method switched to OSL: choose again
            kept = None
    judged = {}   # (the view's samples, scales and terms, for the preview's choice too)
    if kept is None:
        models, choice = choose_models(scene, spec, method, lights, previous=old, judged=judged)
        choice.update(shadow_fog(scene, spec, method, lights))
        choice["error"] += choice["shadows"]["missing"]
        choice["dense"]["emitters"] = emitters_dense(scene, spec)
    else:
        rims = {o.name: old["rims"][o.name] for o in lights if o.name in old.get("rims", {})}
        dense = dict(old.get("dense") or {})
        models = _models(spec, method, lights, kept, rims, set(old.get("thin", ())),
                         kept_scales(scene, spec, method, lights, dense))
        choice = dict(old, lights={o.name: old["lights"].get(o.name, [0, 0.0]) for o in lights}, rims=rims,
                      dense=dense)
    choice.update(quality=quality, method=method.name, method_reason=reason)
    # lights stepped out of the groups to fit a budget (rungs.LEFT_OUT) keep their own dimming (wrap_light)
    in_groups = lights_in_groups(lights, choice)
    grouped = [mod for o, mod in zip(lights, models) if o in in_groups]
    shader_lights, shader_models = method.shader_lights(scene, spec, in_groups, grouped)
    partial = this_frame and view.animated(scene)
    preview = None
    if (preview_budget := method.preview_budget(scene, spec, in_groups)) is not None:
        old_preview = (old or {}).get("preview")
        if kept is not None and old_preview is not None:   # (the stored steps: no view sampled)
            steps = [old_preview["lights"].get(o.name, [rungs.OFF])[0] for o in in_groups]
            shown = [(o, k) for o, k in zip(in_groups, steps) if k < rungs.OFF]
            preview = ([o for o, _ in shown], _models(spec, methods.get("nodes"), [o for o, _ in shown],
                                                      [k for _, k in shown], {}, frozenset(),
                                                      choice["dense"].get("scales")), old_preview)
        else:
            preview = preview_models(scene, spec, in_groups, preview_budget, judged)
        choice["preview"] = {"lights": preview[2]["lights"], "error": preview[2]["error"]} if preview else None
    return Plan(lights, models, choice, in_groups, grouped, shader_lights, shader_models,
                method.windows(scene, in_groups, partial), partial, this_frame, preview)
