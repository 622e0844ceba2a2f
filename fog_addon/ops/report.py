"""What the fog tells the user about a scene (the panel, the operators' reports, ``render --explain``): the choice
of models and what it is predicted to err (``explain``), settings that make the picture useless (``scene_notes``),
and what the fog can't model there (``not_modelled``, kept on the Surface group for the panel: ``stored_caveats``).
"""
import json
import math

import bpy

from .. import caveats, methods, shadow_maps, sunsky, view
from ..nodes import groups
from ..precompute.core import presets
from ..precompute.model import capabilities, rungs
from ..precompute.physics.daylight import sun_shafts
from ..precompute.physics.shafts import shafts
from .plan import stored_choice

CAVEATS_KEY = "analytic_fog_caveats"   # on the Surface group: what the fog can't model in the scene (notes)


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
    if target is None and not choice.get("limited") and not choice["error"] > 0.0:
        return "Quality Exact: every light fully modelled"
    if target is None:
        return f"Quality Exact: predicted error {choice['error']:.2%}"
    return f"Quality {target:.3g}: predicted error {choice['error']:.2%} (target {target:.2%})"


def dense_line(choice):
    """One line: the multiply scattered light the picture lacks where Dense Fog is off or the method does not model
    it (``left_out.dense_fog``), with its predicted share; None where nothing is left out."""
    dense = choice.get("dense") or {}
    left = dense.get("left_out") or {}
    if not left:
        return None
    names = sorted(left, key=left.get, reverse=True)
    why = "Dense Fog is off" if dense.get("why") == "off" else f"Method {methods.get(dense['why']).label} lacks it"
    return (f"multiple scattering left out of {len(left)} light(s) ({', '.join(names[:3])}"
            f"{' and more' if len(names) > 3 else ''}; {why}): up to {dense.get('missing', 0.0):.2%} of a pixel's "
            "fog, in the predicted error")


def shadows_line(choice):
    """One line: the shadows the fog lacks where it has no shafts (``left_out.shadow_fog``), and what the shadow maps
    shrunk to the Quality's budget may move, with their predicted share; None where neither is."""
    shadows = choice.get("shadows") or {}
    left = shadows.get("left_out") or {}
    maps = (f"; the shadow maps shrunk to the Quality's budget: up to {shadows['maps']:.2%}"
            if shadows.get("maps") else "")
    if not left:
        return (f"shadows in the fog drawn from shadow maps shrunk to the Quality's budget: up to "
                f"{shadows['maps']:.2%} of a pixel's fog, in the predicted error") if maps else None
    why = shadows.get("why")
    why = ("Light Shafts is off" if why == "off" else "beyond the lights the Quality shafts" if why == "cap"
           else f"Method {methods.get(why).label} has none")
    names = sorted(left, key=left.get, reverse=True)
    return (f"shadows in the fog left out of {len(left)} light(s) ({', '.join(names[:3])}"
            f"{' and more' if len(names) > 3 else ''}; {why}{maps}): up to {shadows.get('missing', 0.0):.2%} of "
            "a pixel's fog, in the predicted error")


def surplus_line(choice):
    """One line: what Dense Fog's field may still miss beside surfaces after its scale (``left_out.scale_error``),
    with its predicted share; None where nothing stops a light's power."""
    dense = choice.get("dense") or {}
    surplus = dense.get("surplus") or {}
    if not surplus or not dense.get("surplus_missing", 0.0) > 0.0:
        return None
    names = sorted(surplus, key=surplus.get, reverse=True)
    scales = dense.get("scales") or {}
    shown = ", ".join(f"{n} x{scales.get(n, 1.0):.2f}" for n in names[:3])
    return (f"multiple scattering scaled for the surfaces near {len(surplus)} light(s) ({shown}"
            f"{' and more' if len(names) > 3 else ''}): the scale may miss up to "
            f"{dense['surplus_missing']:.2%} of a pixel's fog, in the predicted error")


def left_out_lines(choice):
    """The lines of what the picture lacks or overstates and the predicted error counts (``dense_line``,
    ``surplus_line``, ``shadows_line``), the largest share first (the panel lists them above the lights)."""
    left_out = [(choice.get(key, {}).get(share, 0.0), line) for key, share, line in
                (("dense", "missing", dense_line(choice)), ("dense", "surplus_missing", surplus_line(choice)),
                 ("shadows", "missing", shadows_line(choice))) if line is not None]
    return [line for _, line in sorted(left_out, key=lambda x: -x[0])]


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
    lines += ["  " + line for line in left_out_lines(choice)]
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
        atlas = sun_map.get(shadow_maps.ATLAS)
        grid = (f"an atlas of {int(atlas[2])} map(s) of {int(atlas[5])} x {int(atlas[6])} over "
                f"{len(sun_map[shadow_maps.TILE_KEYS])} frames" if atlas is not None
                else f"a {sun_map.size[0]} x {sun_map.size[1]} map")
        lines.append(f"  The sun's shafts: {grid}, "
                     f"{shafts.samples_for(choice.get('quality')).view_nodes} nodes a ray, "
                     f"{sun_shafts.SUN_SURFACE_SAMPLES[0]} directions x {sun_shafts.SUN_SURFACE_SAMPLES[1]} nodes "
                     "over surfaces")
    return lines


# what the shafts' quadrature adds to a Quality's error, measured (docs/measurements/2026-11-26-light-shafts.md)
SHAFT_ERROR_NOTE = "at Final up to 1.5 % from Exact's 48 nodes, boulevard"


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


_generation = [0]   # bumped by every depsgraph update (``scene_changed``)
_notes_memo = {}    # scene name -> (spec JSON, generation, notes): ``panel_notes``


def scene_changed():
    """Something in the scenes changed (the depsgraph handler): ``panel_notes`` computes its notes again."""
    _generation[0] += 1


def panel_notes(scene, spec):
    """``scene_notes`` as the panel draws them on every redraw: computed again only after the scene or the settings
    changed (they walk every object: a redraw of a big scene must not)."""
    key = (spec.to_json(), _generation[0])
    kept = _notes_memo.get(scene.name)
    if kept is None or kept[:2] != key:
        kept = _notes_memo[scene.name] = (*key, scene_notes(scene, spec))
    return kept[2]


def scene_notes(scene, spec):
    """Notes on settings that make the picture useless in ``scene`` (the operator, the panel and ``render`` say
    them): a fog invisible at the scene's size, a fog opaque before the nearest object, a fog layer whose ground
    is above everything."""
    notes = []
    note = presets.invisible_fog_note(spec.beta_per_unit, view.scene_size(scene))
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


def not_modelled(scene, spec, lights, materials, method=None):
    """What the fog can't model in ``scene`` (``caveats.py``: light shafts where ``method`` (a method name)
    has none or they are off, their limits where it has them; glass and mirrors), as notes."""
    name, engine = getattr(method, "name", method), scene.render.engine
    casting = bool(spec.shafts and capabilities.can(name, "shafts", engine))
    choice = stored_choice() or {}
    notes = [*caveats.shadow_notes(scene, lights, spec.beta_per_unit, max(view.scene_size(scene), 1e-6), casting,
                                   None if spec.shafts else "Light Shafts is off", choice.get("shadows")),
             caveats.glass_note(materials, scene.objects),
             caveats.clip_note(scene, name),
             *caveats.multiple_notes(choice.get("dense"), name, view.has_shape, lights, engine),
             *caveats.glow_notes(methods.compositor.glowing_objects(scene), name, engine),
             *(f"{what}: {why}" for what, why in daylight_notes(scene, spec, name, lights))]
    return [n for n in notes if n]


def stored_caveats():
    """The notes of ``not_modelled`` from the last Add/Update Fog (the panel shows them), [] if none."""
    surface = bpy.data.node_groups.get(groups.SURFACE)
    return json.loads(surface[CAVEATS_KEY]) if surface is not None and CAVEATS_KEY in surface else []


def daylight_notes(scene, spec, method_name, lamps=()):
    """[(name, why)]: what the daylight leaves out in ``scene`` with ``method_name``; ``lamps``: the fog's lights."""
    out = []
    suns = sunsky.scene_suns(scene)
    if not spec.layered:
        for sun in suns:
            out.append((sun.name, "a fog that fills all space swallows the sun: set a Fog Top (Daylight) for its "
                                  "light, glow and dimming through the fog"))
        return out
    for sun in suns[1:]:
        out.append((sun.name, f"only the brightest sun ({suns[0].name}) shines through the fog layer: this one "
                              "is neither dimmed nor glows"))
    if sunsky.sun_discs(scene.world) and not suns:
        out.append((scene.world.name, "its Sky Texture's sun disc is not a sun to the fog (no glow, no dimming of its "
                                      "light): add a Sun light along it"))
    if scene.world is not None and not sunsky.sky_colour(scene.world)[1]:
        out.append((scene.world.name, "the fog layer's sky glow takes this World as uniform, of its mean colour over "
                                      "the upper hemisphere (where seen, the World itself is dimmed exactly)"))
    if spec.air_per_unit() is not None and sunsky.is_daylit(scene, spec) and sunsky.holds_air(scene.world):
        out.append(("Air", f"the World {scene.world.name!r} is a Sky Texture, a sky seen through its own air: the "
                           "air's glow fades to it (a pixel of sky shows it as it is, dimmed only by the fog layer), "
                           "and the Sun light is taken as the sun at the ground, already through the air; a haze layer "
                           "adds its own glow on top (a Sky Texture's aerosol density is haze of its own)"))
    engine = scene.render.engine
    daylit = sunsky.is_daylit(scene, spec)
    if spec.air_per_unit() is not None and not capabilities.can(method_name, "air_colour", engine) and daylit:
        out.append(("Air", f"with {method_name} the air dims surfaces by the mean of its colour (a shader's factor "
                           f"is one number): the distance greys but does not blue; "
                           f"{capabilities.suggestion('air_colour', engine)} gives its colour"))
    if not capabilities.can(method_name, "daylight_once", engine) and daylit:
        out.append(("Daylight", f"with {method_name} the sun's and the sky's glow and fog light are evaluated on "
                                "every sample (3-8x the fog-free render in a city); "
                                f"{capabilities.suggestion('daylight_once', engine)} does them once per pixel"))
    if (not capabilities.can(method_name, "animated_sky", engine) and sunsky.uses_glow_table(scene, spec)
            and sunsky.background_animated(scene.world)):
        out.append((scene.world.name, "its Background is animated: the sky's glow where the sky is seen keeps its "
                                      "colour of the last fog update on every frame (on surfaces it follows); the "
                                      f"{capabilities.suggestion('animated_sky', engine)} follows it everywhere"))
    if suns:
        sun = suns[0]
        out.append((sun.name, "its light on surfaces and the sky's are dimmed by one factor weighted by the two "
                              "(lamps' light on the same surfaces is dimmed by it too)"))
        out.append((sun.name, _sun_shaft_note(scene, spec, method_name)))
        if caveats.is_animated(sun):
            out.append((sun.name, "is animated: its fog light on surfaces is baked for the sun's direction when "
                                  "the fog was last updated (its glow and dimming follow every frame)"))
    if lamps and not suns and any(c > 0.0 for c in sunsky.sky_colour(scene.world)[0]):
        out.append(("Fog Top", "with lamps and no sun the sky's light on surfaces is not dimmed by the layer "
                               "(one factor would dim the lamps' light too)"))
    if lamps and capabilities.can(method_name, "layer_ends", engine):
        out.append(("Fog Top", f"the lamps' glows ({len(lamps)}) end at the layer's top (with a falloff, one falloff "
                               "length above it); their fog light on surfaces is that of fog everywhere"))
    elif lamps:
        out.append(("Fog Top", f"with {method_name} the lamps' glows ({len(lamps)}) take the layer's density "
                               "everywhere, also above its top: a lamp within a few of its heights of the top glows "
                               "too bright on rays that pass above it (tens of per cent to several times); "
                               f"{capabilities.suggestion('layer_ends', engine)} ends them at the top"))
    return out


def _sun_shaft_note(scene, spec, method_name):
    """What the sun's shadows do in the fog with ``method_name``."""
    if not spec.shafts:
        return "Light Shafts are off: no shafts in the fog"
    if sunsky.sun_casts_shafts(scene, spec) is None:
        return "it casts no shadows: no shafts in the fog"
    casters = caveats.shadow_casters(scene)
    if not casters:
        return "nothing casts a shadow: no shafts in the fog"
    if not capabilities.can(method_name, "shafts", scene.render.engine):
        return (f"with {method_name} its shadows fall on surfaces but cast no shafts into the fog: "
                f"{capabilities.suggestion('shafts', scene.render.engine)} casts them")
    said = ("its shafts in the fog come from a map of the scene's shadows baked at Update Fog around the camera's "
            "view; the sky's light in the fog and on surfaces is not shadowed by the buildings, nor the air's glow")
    if caveats.is_animated(sunsky.sun_casts_shafts(scene, spec)):
        said += "; the sun moves: its shadow map is that of the frame the fog was last updated at"
    return said
