"""What a build leaves out of the picture, and Dense Fog by the Quality (``plan.plan``'s accounts, issue 46): the
multiply scattered light each light gets or lacks (``dense_fog``; the glowing objects', ``emitters_dense``) and the
shadows a scene without shafts lacks (``shadow_fog``), each as the largest share of a judged view sample's fog that
it leaves out: in the predicted error, the notes (``caveats``) and the panel (``report.left_out_lines``).
"""
import math

import numpy as np

from .. import escape, methods, shadow_maps, sunsky, view
from ..precompute.model import capabilities, predict
from ..precompute.physics.shafts import shafts

MULTIPLE_ENTRIES = 1_000_000   # samples x lights at most for Dense Fog's shares (``dense_fog``): every nth sample
#                                beyond (the choice's time stays that of the ladder's alone)


def view_samples(scene, spec, lights, method=None):
    """``view.view_samples`` of ``lights`` holding the fog light that no step of theirs leaves out
    (``predict.ViewSamples.other``), in every sample's fog: a fog layer's sun and sky (``sunsky.sampled_fog``) and,
    where ``method`` glows them, the glowing objects' (``emitters_fog``); past glass where ``method`` shades the fog
    there (``sees_past_glass``)."""
    return with_other(scene, spec, view.view_samples(scene, lights, past_glass=sees_past_glass(scene, method)), method)


def _method_can(scene, method, feature):
    """Whether ``method`` (a Method or its name, or None) draws ``feature`` in the scene's engine (``capabilities``)."""
    return method is not None and capabilities.can(getattr(method, "name", method), feature, scene.render.engine)


def sees_past_glass(scene, method):
    """Whether ``method`` shades the fog past glass in the scene's engine: the view's samples then go straight
    through glass (``view.view_samples``)."""
    return _method_can(scene, method, "glass")


def glows_emitters(scene, method):
    """Whether ``method`` glows the glowing objects in the scene's engine."""
    return _method_can(scene, method, "emitters")


def with_other(scene, spec, samples, method=None):
    """``samples`` (``predict.ViewSamples``) with ``view_samples``' ``other``."""
    parts = [sunsky.sampled_fog(scene, spec, samples)]
    if glows_emitters(scene, method):
        parts.append(emitters_fog(scene, spec, samples))
    parts = [p for p in parts if p is not None]
    return samples._replace(other=sum(parts[1:], parts[0]) if parts else None)


def emitters_fog(scene, spec, samples):
    """(P, 3) W/(m^2 sr): the glowing objects' glow and fog light at the view ``samples``, each object taken as a
    point source (``methods.compositor.glowing_points``) through the lamps' kernels (``predict.light_fog``); None
    without one whose radiance can be read (plain values, an image).  An estimate for the denominator: the
    Compositor blurs the objects' own pixels (``comp_emitters``)."""
    shining, centres, intensities = methods.compositor.glowing_points(scene)
    if not shining:
        return None
    glow, scatter = predict.light_fog(_at_centres(samples, centres), intensities, spec.beta_per_unit, spec.anisotropy)
    return np.nan_to_num(glow + scatter, nan=0.0, posinf=0.0).sum(axis=1)


def _at_centres(samples, centres):
    """``samples`` with point lights at ``centres`` ((N, 3) m)."""
    return samples._replace(lights=np.broadcast_to(centres, (len(samples.distance),) + centres.shape).copy(),
                            shapes=None)


def shadow_fog(scene, spec, method, lights):
    """What the shadows would take from the fog where it has none: the lights with objects near them
    (``caveats.shadowing_lights``) whose shafts the picture lacks (Light Shafts off, a method without them, or
    beyond the lights the Quality shafts: ``shadow_maps.shafted_split``), judged at the view's samples
    (``shadow_maps.shadowed_parts``).  Returns {"shadows": {"left_out": {name: share}, "missing": their share of a
    judged sample's fog together, at the sample where it is largest (the shrunk maps' "maps" with them: their
    lights' maps within the Quality's budget, ``shadow_maps.map_level_error``), "why": "off", "cap" (the
    Quality's) or the method's name}}."""
    name, engine = getattr(method, "name", method), scene.render.engine
    casting = spec.shafts and capabilities.can(name, "shafts", engine)
    cap = shafts.shaft_lights(spec.quality) if casting else None
    out = {"left_out": {}, "missing": 0.0, "why": "cap" if casting else "off" if not spec.shafts else name}
    shafted, over = shadow_maps.shafted_split(scene, lights, spec.beta_per_unit, cap) \
        if lights and spec.beta_per_unit > 0.0 else ([], [])
    unshafted = over if casting else shafted
    judged = shadow_maps.shadowed_parts(scene, spec, unshafted, others=[o for o in lights if o not in unshafted]
                                        if casting else ()) if unshafted else None
    if judged is not None:
        names, parts = judged
        out["left_out"] = {n: float(parts[:, k].max(initial=0.0)) for k, n in enumerate(names)}
        out["missing"] = float(parts.sum(axis=1).max(initial=0.0))
    if casting and len(shafted) > 1:   # the shafted lights' maps shrunk to the Quality's budget
        still = [o for o in shafted if o not in shadow_maps.moving_lights(scene, shafted)] \
            if shadow_maps.frames_of(scene)[2] > 1 else shafted
        levels = shadow_maps.map_levels(scene, still, spec.beta_per_unit, shafts.map_budget(spec.quality))
        out["maps"] = shadow_maps.map_level_error(scene, spec, lights, levels)
        out["missing"] += out["maps"]
    return {"shadows": out}


EMITTER_GRID = (40, 23)   # the view's samples the glowing objects' Dense Fog is judged at (``emitters_dense``)


def emitters_dense(scene, spec):
    """Whether the glowing objects' glows get Dense Fog's multiply scattered light (the Compositor's
    ``comp_emitters.glows``): Dense Fog on and, at the Quality, more than THIN_SHARE of the target at some view
    sample for a point source at some glowing object's centre (``predict.multiple_parts``; every one with Quality
    Exact).  Where it adds nothing they keep the single-scattering kernel, whose flat emitters' facing term Dense
    Fog's lacks."""
    glowing = methods.compositor.glowing_objects(scene) if spec.multiple_scattering else []
    target = spec.target_error
    if not glowing or target is None or scene.camera is None:
        return bool(glowing)
    grid = tuple(min(a, b) for a, b in zip(view.sample_grid(scene), EMITTER_GRID))
    centres = np.array([methods.compositor.object_centre(o) for o in glowing])
    samples = _at_centres(view.view_samples(scene, [], frames=[scene.frame_current], grid=grid), centres)
    parts = predict.multiple_parts(samples, np.ones((len(glowing), 3)), spec.beta_per_unit, spec.anisotropy,
                                   spec.grey_albedo)
    return bool(parts.max(initial=0.0) > predict.THIN_SHARE * target)


def dense_served(spec, method, engine):
    """light -> whether ``method`` models its multiply scattered light (Dense Fog on and the capability its
    kind needs, ``capabilities`` "dense_point" or "dense_shaped", in ``engine``)."""
    name = getattr(method, "name", method)
    point, shaped = (spec.multiple_scattering and capabilities.can(name, key, engine)
                     for key in ("dense_point", "dense_shaped"))
    return lambda o: shaped if view.has_shape(o) else point


def dense_fog(scene, spec, method, lights, samples=None, error=0.0, single=None, dense=None, previous=None,
              scales=None):
    """Dense Fog by the Quality: which ``lights`` get their multiply scattered light, at which scale, and what the
    picture misses without it (``predict.multiple_parts``, at the view's samples: ``samples``, else sampled here
    where needed; ``single``, ``dense``: their (glow, scatter) without and with it, where computed).

    Each served light's field is scaled by the share the scene's surfaces leave of it (``escape.field_scales``:
    a hood, a wall or the ground stops part of the light's power before it scatters), and judged so.  A light the
    method models it for (``dense_served``) gets it unless it is at most THIN_SHARE of the Quality's target at
    every judged sample and what all such lights and the left-out ones miss together keeps the predicted error
    (``error`` before Dense Fog) within the target ("thin": left out at no cost, the thinnest first; with Quality
    Exact no light is thin).  A light it is not modelled for (Dense Fog off: a stylised look; a method without
    it) is "left out", with its share.  Returns {"thin": {name: share}, "dense": {"left_out": {name: share},
    "missing": the share of a judged sample's fog that the thin and the left-out lights miss together, at the
    sample where it is largest, "why": "off" or the method's name, "scales": {name: scale below 1}, and
    ``scale_error``'s}}.  ``previous``: {name: scale} stored, kept while within a step (``escape.field_scales``);
    ``scales``: the served lights' scales if already judged (``plan.choose_models``, whose ladder judges with them).
    """
    target, engine = spec.target_error, scene.render.engine
    served = dense_served(spec, method, engine)
    need = [o for o in lights if not served(o)] + ([o for o in lights if served(o)] if target is not None else [])
    out = {"thin": {}, "dense": {"left_out": {}, "missing": 0.0, "scales": {},
                                 "why": "off" if not spec.multiple_scattering else getattr(method, "name", method)}}
    if scene.camera is None:
        return out
    if scales is None:
        scales = escape.field_scales(scene, spec, [o for o in lights if served(o)], previous=previous)
    if not need:
        out["dense"].update(_scales_account(scales, spec))
        return out
    if samples is None:
        samples = view_samples(scene, spec, lights, method)
    if len(samples.distance) * len(lights) > MULTIPLE_ENTRIES:   # (every nth sample)
        n = math.ceil(len(samples.distance) * len(lights) / MULTIPLE_ENTRIES)
        samples = predict.every_nth(samples, n)
        single, dense = (None if f is None else tuple(a[::n] for a in f) for f in (single, dense))
    scale = np.array([scales.get(o.name, 1.0) for o in lights])
    unscaled = view.multiple_parts(scene, spec, lights, samples, single, dense)
    parts = unscaled * scale[None, :]
    share = parts.max(axis=0, initial=0.0)
    missed = [k for k, o in enumerate(lights) if not served(o)]
    out["dense"]["left_out"] = {lights[k].name: float(share[k]) for k in missed}
    if target is not None:   # the thinnest first, while the picture stays within the target
        room, acc = target - error, parts[:, missed].sum(axis=1)
        for k in sorted((k for k, o in enumerate(lights) if served(o)), key=lambda k: share[k]):
            if share[k] > predict.THIN_SHARE * target or (acc + parts[:, k]).max(initial=0.0) > room:
                break
            acc = acc + parts[:, k]
            missed.append(k)
            out["thin"][lights[k].name] = float(share[k])
    out["dense"]["missing"] = predict.missing_share(parts, missed)
    kept = [k for k in range(len(lights)) if k not in missed]   # (those that get Dense Fog)
    out["dense"].update(_scales_account({lights[k].name: float(scale[k]) for k in kept}, spec))
    scaled = [k for k, o in enumerate(lights) if served(o)]   # (kept and thin: a thin light's miss is scaled too)
    escapes = escape.escape_fractions(scene, spec, [lights[k] for k in scaled])
    out["dense"].update(scale_error([lights[k].name for k in scaled], scale[scaled],
                                    np.array([escapes.get(lights[k].name, 1.0) for k in scaled]), unscaled[:, scaled]))
    return out


def scales_key(spec):
    """What Dense Fog's scales beside surfaces were judged with (the fog's density and anisotropy)."""
    return [round(spec.beta_per_unit, 9), round(spec.anisotropy, 6)]


def _scales_account(scales, spec):
    """A Dense Fog account's "scales" (those of ``scales`` below 1) and "scales_at" (``scales_key``)."""
    return {"scales": {n: k for n, k in scales.items() if k < 1.0}, "scales_at": scales_key(spec)}


def kept_scales(scene, spec, method, lights, dense):
    """The scales of a stored Dense Fog account ``dense`` (``dense_fog``'s, the handlers' cheap path that keeps the
    lights' steps), judged again where the density or the anisotropy changed since (``escape.field_scales``);
    ``dense`` is updated in place.  Returns {name: scale}."""
    if dense.get("scales_at") != scales_key(spec):
        served = dense_served(spec, method, scene.render.engine)
        dense.update(_scales_account(escape.field_scales(scene, spec, [o for o in lights if served(o)]), spec))
    return dense.get("scales") or {}


def scale_error(names, scales, escapes, parts):
    """What the scale of Dense Fog's field beside surfaces may miss (``escape.field_scales``: one traced share a
    light, for the whole picture, from a few hundred photons): each light's unbounded multiply scattered share
    ``parts`` times the larger of k (1 - f), its field too bright where the share over the picture is more than the
    fog near a surface keeps (f its escape fraction, ``escapes``: the share of a flight from the light that
    scatters before a surface), and (1 - k) / 2, its field scaled down too far (k its scale, ``scales``).  An
    upper bound measured against Cycles with surfaces that absorb the scattered light, at least the measured error
    on nine scenes (docs/measurements/2026-11-30-dense-walls.md).  Returns {"surplus": {name: share},
    "surplus_missing": their share together at the sample where it is largest}."""
    if not names:
        return {"surplus": {}, "surplus_missing": 0.0}
    k, f = np.asarray(scales, float), np.asarray(escapes, float)
    extra = parts * np.maximum(k * (1.0 - f), 0.5 * (1.0 - k))[None, :]
    share = extra.max(axis=0, initial=0.0)
    return {"surplus": {n: float(share[j]) for j, n in enumerate(names) if share[j] > 0.0},
            "surplus_missing": float(extra.sum(axis=1).max(initial=0.0))}
