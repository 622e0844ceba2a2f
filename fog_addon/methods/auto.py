"""Method Auto: per scene, the node groups or the compositor, by predicted cost and by what the scene needs.

The predicted cost of a method is the render time with the fog over the same render without it, from
the scene's lights, fogged materials, pixels, samples and engine (``predicted_ratio``; the model and the
measurements it is fitted to: docs/decisions/2026-11-26-method-auto.md):

* node groups: every fogged material evaluates every light on every sample, so their share of the render
  does not depend on pixels or samples, and grows with the lights (Cycles: 1 + 2.9 N^0.85; EEVEE:
  1 + 0.05 N^0.8), plus, in Cycles, the set-up before the first sample, which grows with materials x N^2
  (Cycles' node deduplication), against the fog-free render's time (pixels x samples);
* the compositor: a cost per pixel and frame, fixed plus a part per light, against the render's cost per
  pixel, which grows with the samples (Cycles: 1 + (0.27 + 0.0105 N) 16 / samples; EEVEE: 1 + (0.05 +
  0.001 N) 16 / samples), a shafted light counting 1 + SHAFT_LOAD lights.

N counts lights; a scene's Quality steps some of them down the ladder, which both methods profit from.

What the scene needs comes first:

* a camera that is not perspective (panoramic): the node groups (hard: the compositor has none);
* anisotropy below the node groups' tables (g < rungs.MIN_TABLE_ANISOTROPY): OSL in Cycles;
* EEVEE's uniform block can't hold every light's node groups: the compositor (the node groups would step
  lights down beyond the Quality's target);
* light shafts (objects casting shadows into a light's glow, ``caveats.shadowing_lights``, with Light Shafts
  on): the compositor, which alone models them;
* a fog layer with a sun or a sky (``sunsky.is_daylit``): the compositor, which alone gives them their glow;
* a fog layer with lights: the compositor, which alone ends their glows at the layer's top;
* glowing objects the camera sees (emissive materials, ``compositor.glowing_objects``): the compositor, which
  alone gives them a glow;
* spot or area lights with Dense Fog: the compositor, which alone gives them their multiply scattered light
  (``rungs.spot_multiple_rungs``);
* surfaces the compositor's one point per pixel would get wrong (transparent or refracting materials on
  objects the camera sees, a Glass BSDF in EEVEE, depth of field, motion blur): the node groups, unless their
  predicted cost exceeds SOFT_COST_LIMIT; then the compositor, and the choice says what it gets wrong.
"""
from .. import caveats, shadow_maps, sunsky, view
from ..nodes import budgets
from ..precompute.model import capabilities, predict, rungs
from ..precompute.physics.shafts import shafts
from .compositor import glowing_objects, unfogged_layers

SOFT_COST_LIMIT = 6.0   # a soft need keeps the node groups while they cost at most this (x the fog-free render)
_REFERENCE_SAMPLES = 16
_CYCLES_S_PER_PIXEL_SAMPLE = 7.2e-7   # the fog-free render's time per pixel and sample (Cycles CPU, 2 cores)
_CYCLES_SETUP_S = 1.2e-3              # Cycles' node set-up per fogged material and light squared (first render)
_COST = {   # (node groups: a, p of 1 + a N^p), (compositor: fixed, per light, at 16 samples)
    "CYCLES": ((2.9, 0.85), (0.27, 0.0105)),
    "BLENDER_EEVEE": ((0.05, 0.8), (0.05, 0.001)),
}


SHAFT_LOAD = 3.5   # a shafted light costs the compositor about this many lights more (its map's lookups along the ray
#                    and over the surface's hemisphere: benchmarks/city_night.py, 10-1 000 street lamps, and the hall of
#                    benchmarks/shafts_cost.py; docs/measurements/2026-12-01-city-night.md)
AREA_LIGHT_LOAD = 6   # an area light costs about this many point lights (benchmarks/area_cost.py, the hall at
#                        g 0.85: fog over no fog 1.69x against 1.13x with 4 lights in the compositor, 65x against 8.7x
#                        with the node groups; docs/measurements/2026-11-27-area-lights.md)


def light_load(lights):
    """The lights' count for the cost model, an area light weighing AREA_LIGHT_LOAD point lights."""
    return sum(AREA_LIGHT_LOAD if getattr(o.data, "type", "POINT") == "AREA" else 1 for o in lights)


def predicted_ratio(method, engine, lights, materials=1, pixels=320 * 180, samples=16, shafted=0):
    """The render time with the fog over without it (dimensionless) that ``method`` is predicted to cost
    (module docstring): ``lights`` taking part, fogged ``materials``, ``pixels`` and ``samples`` per pixel;
    ``shafted``: the lights the compositor shafts, each SHAFT_LOAD lights more."""
    (a, p), (fixed, per_light) = _COST.get(engine, _COST["CYCLES"])
    n = max(int(lights), 0)
    samples = max(int(samples), 1)
    if method == "compositor":
        return 1.0 + (fixed + per_light * (n + SHAFT_LOAD * max(int(shafted), 0))) * _REFERENCE_SAMPLES / samples
    ratio = 1.0 + (a * n ** p if n else 0.0)
    if engine == "CYCLES":
        base_s = _CYCLES_S_PER_PIXEL_SAMPLE * max(pixels, 1) * samples
        ratio += _CYCLES_SETUP_S * max(materials, 1) * n * n / base_s
    return ratio * (1.1 if method == "osl" else 1.0)


def samples_of(scene):
    """Samples per pixel the scene renders with."""
    if scene.render.engine == "CYCLES":
        return int(scene.cycles.samples)
    return int(getattr(scene.eevee, "taa_render_samples", 16))


def pixels_of(scene):
    r = scene.render
    return int(r.resolution_x * r.resolution_y * (r.resolution_percentage / 100.0) ** 2)


def _soft_needs(scene, materials):
    """What the compositor's one surface point per pixel would get wrong in ``scene``, as phrases."""
    needs = []
    cam = scene.camera
    if cam is not None and cam.data.dof.use_dof:
        needs.append("depth of field")
    if scene.render.use_motion_blur:
        needs.append("motion blur")
    layers = unfogged_layers(scene)
    if layers:
        needs.append(f"view layers the composite does not show ({caveats.listed(layers)})")
    # (glass in Cycles: both methods shade what lies past it, ``compositor._tails``)
    cycles = scene.render.engine == "CYCLES"
    see = caveats.see_through(materials, scene.objects, served=caveats.served_glass if cycles else None,
                              target="CYCLES" if cycles else "EEVEE")
    if see:
        shown = ", ".join(see[:3]) + (f" and {len(see) - 3} more" if len(see) > 3 else "")
        needs.append(f"see-through materials ({shown})")
    return needs


def _needs(scene, spec, lights):
    """[(capability, phrase)]: what the scene needs that one method alone may model (``capabilities.only``), in
    Auto's order of precedence, each with what in the scene needs it."""
    needs = []
    if spec.shafts and lights:
        shafted = caveats.shadowing_lights(scene, lights, spec.beta_per_unit, max(view.scene_size(scene), 1e-6))
        if shafted:
            needs.append(("shafts", f"light shafts: objects cast shadows into the glow of {len(shafted)} light(s)"))
    if sunsky.is_daylit(scene, spec):
        needs.append(("daylight_once", "daylight in a fog layer"))
    if spec.layered and lights:
        needs.append(("layer_ends", "a fog layer with lamps"))
    glowing = glowing_objects(scene)
    if glowing:
        needs.append(("emitters", f"glowing objects ({caveats.listed([o.name for o in glowing])})"))
    shaped = _dense_shaped(scene, spec, lights)
    if shaped:
        needs.append(("dense_shaped", f"Dense Fog with spot or area lights ({caveats.listed(shaped)})"))
    return needs


THIN_GRID = (40, 23)   # the view's samples Auto judges Dense Fog's share with (a coarse grid: a choice of method)


def _dense_shaped(scene, spec, lights):
    """The spot and area lights whose multiply scattered light Dense Fog models (the Quality's, ``ops/left_out.dense_fog``:
    more than THIN_SHARE of the target at some view sample; every one with Quality Exact), by name."""
    shaped = [o for o in lights if view.has_shape(o)] if spec.multiple_scattering else []
    target = spec.target_error
    if not shaped or target is None or scene.camera is None:
        return [o.name for o in shaped]
    grid = tuple(min(a, b) for a, b in zip(view.sample_grid(scene), THIN_GRID))
    share = view.multiple_parts(scene, spec, shaped, grid=grid).max(axis=0, initial=0.0)
    return [o.name for o, v in zip(shaped, share) if v > predict.THIN_SHARE * target]


def choose(scene, spec, lights, materials, methods):
    """(method name, reason) for ``scene``: Auto's choice (module docstring).  ``lights``: the lights taking
    part; ``materials``: the fogged materials; ``methods``: {name: ``base.Method``}, whose compositor's ``check``
    and node groups' ``budget`` it asks."""
    engine = scene.render.engine
    if spec.anisotropy < rungs.MIN_TABLE_ANISOTROPY:
        if engine == "CYCLES":
            return "osl", f"anisotropy {spec.anisotropy:g} is below the node groups' tables: OSL serves it"
        return "nodes", "no method serves this anisotropy in EEVEE"   # (the node groups' check says why)
    hard = methods["compositor"].check(scene, spec)
    n, m = light_load(lights), len(materials)
    px, spp = pixels_of(scene), samples_of(scene)
    shafted = (len(shadow_maps.shafted_split(scene, lights, spec.beta_per_unit, shafts.shaft_lights(spec.quality))[0])
               if spec.shafts and lights else 0)
    cost = {name: predicted_ratio(name, engine, n, m, px, spp, shafted) for name in ("nodes", "compositor")}
    costs = f"predicted {cost['nodes']:.2f}x with node groups, {cost['compositor']:.2f}x with the compositor"
    if hard is not None:
        why = hard.split(":")[0].replace("the Compositor method", "the compositor")
        return "nodes", why
    if engine == budgets.EEVEE_ENGINE and lights:
        if not methods["nodes"].budget(scene, spec, lights).fits([0] * len(lights)):
            return "compositor", (f"EEVEE's uniform block can't hold the node groups of {len(lights)} lights at full "
                                  "models; "
                                  f"{costs}")
    soft = _soft_needs(scene, materials)
    caveat = f"; it is approximate with {' and '.join(soft)}" if soft else ""
    for feature, phrase in _needs(scene, spec, lights):
        name = capabilities.only(feature, engine)
        if name is not None:
            what = capabilities.BY_KEY[feature].label
            return name, f"{phrase}: only the {capabilities.LABELS[name]} method models {what}{caveat}; {costs}"
    if soft and cost["nodes"] <= SOFT_COST_LIMIT:
        return "nodes", f"the compositor would get these wrong: {' and '.join(soft)}; {costs}"
    if cost["compositor"] < cost["nodes"]:
        if soft:
            return "compositor", (f"{costs}; the compositor is approximate with {' and '.join(soft)}")
        return "compositor", costs
    return "nodes", costs
