"""What the fog does not model in a scene yet, said plainly (the panel, the operator's report, ``render``).

* **Light shafts.** The Compositor method casts objects' shadows into the fog from shadow maps
  (``precompute/physics/shafts/shafts.py``); the node groups and OSL integrate every camera ray as if nothing stood
  between the light and the fog (Dobashi et al. 2002 Eq. 2's H = 1).  ``shadowing_lights`` finds the lights with an
  object in their glow (an object whose bounding box comes within the distance at which the light's glow
  has fallen by e^-3: ``GLOW_OPTICAL_DEPTH`` / beta, at most the scene's size): only they get shadow maps,
  and ``shadow_notes`` says what their shafts don't do (or that there are none).
* **Glass and mirrors.** In Cycles the node groups shade the fog along a ray's segments after a Glass BSDF or a
  sharp mirror (``glass_tails.specular_segment``); elsewhere a camera ray gets the fog of its first segment only
  (``see_through`` names the materials, ``glass_note`` says which cases hold).
"""
import numpy as np

from .precompute.model import capabilities, footprint
from .precompute.physics.shafts import shaft_maps

GLOW_OPTICAL_DEPTH = 3.0   # beta x distance within which a light's glow is worth a shadow (e^-3 = 5 %)
_SEE_THROUGH = ("ShaderNodeBsdfTransparent", "ShaderNodeBsdfGlass", "ShaderNodeBsdfRefraction",
                "ShaderNodeBsdfTranslucent", "ShaderNodeBsdfHairPrincipled", "ShaderNodeBsdfHair")


def see_through(materials, objects, served=None, target="CYCLES"):
    """Names of ``materials`` that let the camera see through them (Transparent, Glass, Refraction,
    Translucent or hair BSDFs, a Principled BSDF with transmission or alpha below 1, connected to the output
    ``target``'s engine renders: ``surface_nodes``) on ``objects`` the camera sees, each once; ``served(node)``:
    True for a node left out (what lies past it is shaded: glass in Cycles, ``served_glass``)."""
    seen = {slot.material for obj in objects if obj.visible_camera
            for slot in getattr(obj, "material_slots", ()) if slot.material is not None}
    names = []
    for mat in materials:
        if mat not in seen or mat.node_tree is None:
            continue
        if any(not node.mute and not (served and served(node)) and (
                node.bl_idname in _SEE_THROUGH or (node.bl_idname == "ShaderNodeBsdfPrincipled"
                                                   and _principled_see_through(node)))
               for node in surface_nodes(mat.node_tree, target)):
            names.append(mat.name)
    return names


OUTPUT_TYPES = ("ShaderNodeOutputMaterial", "ShaderNodeOutputWorld")


def effective_output(tree, target, skip=None):
    """The output node of ``tree`` that ``target``'s engine (CYCLES or EEVEE) renders, as Blender chooses it: one
    for ``target`` before one for ALL engines, then the active one, then the first in the tree's order; None if
    there is none.  ``skip(node)``: True for an output left out of the choice (the fog's own)."""
    best = None
    for n in tree.nodes:
        if n.bl_idname not in OUTPUT_TYPES or n.target not in ("ALL", target) or (skip and skip(n)):
            continue
        if best is None or (best.target == "ALL" and n.target == target) or (
                best.target == n.target and n.is_active_output and not best.is_active_output):
            best = n
    return best


def surface_nodes(tree, target="CYCLES"):
    """The nodes of a material's ``tree`` whose outputs reach the Surface of the output ``target``'s engine
    renders (``effective_output``), following the enabled links upstream (not into node groups), in the tree's
    order: a shader left unconnected is not part of the picture."""
    out = effective_output(tree, target)
    if out is None or "Surface" not in out.inputs:
        return []
    seen, todo = set(), [out.inputs["Surface"]]
    while todo:
        for link in todo.pop().links:
            node = link.from_node
            if link.is_valid and not link.is_muted and node.name not in seen:
                seen.add(node.name)
                todo.extend(i for i in node.inputs if i.is_linked)
    return [n for n in tree.nodes if n.name in seen]


SHARP = 1e-3   # a roughness at or below which a glossy or metallic surface is a mirror (``specular_paths``)


def specular_paths(materials):
    """True if some of ``materials`` starts a path the fog shades segment by segment in Cycles
    (``glass_tails.place_tails``): glass (``is_glass``), or a mirror (a Glossy BSDF, or a Principled BSDF with
    metallic above 0, of roughness at most SHARP, unlinked).  Without one the Surface group holds no tails:
    they cost SVM stack in every material (out of stack space with 16 spots)."""
    for mat in materials:
        if mat.node_tree is None:
            continue
        for node in mat.node_tree.nodes:
            if node.mute:
                continue
            if is_glass(node):
                return True
            rough = node.inputs.get("Roughness")
            if rough is None or rough.is_linked or rough.default_value > SHARP:
                continue
            metal = node.inputs.get("Metallic")
            if node.bl_idname in ("ShaderNodeBsdfGlossy", "ShaderNodeBsdfAnisotropic") or (
                    node.bl_idname == "ShaderNodeBsdfPrincipled" and metal is not None
                    and (metal.is_linked or metal.default_value > 0.0)):
                return True
    return False


GLASS_NODES = ("ShaderNodeBsdfGlass", "ShaderNodeBsdfRefraction")


def served_glass(node):
    """True for glass whose far side both methods shade in Cycles (``is_glass``; a Principled BSDF fully opaque in
    its Alpha, which the compositor's one surface a pixel would not see through)."""
    alpha = node.inputs.get("Alpha") if node.bl_idname == "ShaderNodeBsdfPrincipled" else None
    return is_glass(node) and (alpha is None or (not alpha.is_linked and alpha.default_value >= 1.0))


def is_glass(node):
    """True for a shader whose transmitted rays the fog shades as segments past it in Cycles (``glass_tails.py``): a
    Glass or Refraction BSDF, or a Principled BSDF that lets light through (Transmission Weight linked or above 0),
    at any roughness (a rough one's segments are blurred by its lobe: ``glass_tails.specular_segment``)."""
    if node.bl_idname in GLASS_NODES:
        return True
    weight = node.inputs.get("Transmission Weight") if node.bl_idname == "ShaderNodeBsdfPrincipled" else None
    return weight is not None and (weight.is_linked or weight.default_value > 0.0)


def _principled_see_through(node):
    for name, clear in (("Transmission Weight", 0.0), ("Alpha", 1.0)):
        sock = node.inputs.get(name)
        if sock is not None and (sock.is_linked or sock.default_value != clear):
            return True
    return False


def _flat_side(obj):
    """(centre, unit normal) in world space of a flat object (its bounding box has no thickness along one local
    axis: a plane, a wall of one face), else None."""
    local = np.asarray(obj.bound_box, float)
    size = local.max(axis=0) - local.min(axis=0)
    k = int(np.argmin(size))
    if size[k] > 1e-6 * max(float(size.max()), 1e-30):
        return None
    m = np.asarray(obj.matrix_world, float)
    normal = np.linalg.inv(m[:3, :3]).T[:, k]
    return m[:3, :3] @ local.mean(axis=0) + m[:3, 3], normal / max(np.linalg.norm(normal), 1e-30)


def shadowing_lights(scene, lights, beta, reach_m):
    """{light name: number of objects} for the ``lights`` with a shadow-casting object (a mesh, curve or the
    like, visible to shadow rays) within their glow's reach: GLOW_OPTICAL_DEPTH / ``beta`` (1/unit), at most
    ``reach_m`` (scene units).  A flat object (a ground plane) counts only where the camera sees its far side
    from the light, where its shadow in the fog lies.  All lights against all objects at once (N x M)."""
    reach = min(GLOW_OPTICAL_DEPTH / beta, reach_m) if beta > 0.0 else reach_m
    casters = shadow_casters(scene)
    if not casters or not lights:
        return {}
    corners = np.array([footprint.box_points(o.bound_box, o.matrix_world) for o in casters]).reshape(-1, 8, 3)
    lo, hi = corners.min(axis=1), corners.max(axis=1)                                  # (M, 3) world boxes
    p = np.array([tuple(light.matrix_world.translation) for light in lights])          # (N, 3)
    gap = np.maximum(np.maximum(lo[None] - p[:, None], p[:, None] - hi[None]), 0.0)   # (N, M, 3)
    near = np.linalg.norm(gap, axis=2) < reach                                        # (N, M)
    eye = np.array(scene.camera.matrix_world.translation) if scene.camera is not None else None
    flats = [(k, f) for k, o in enumerate(casters) if (f := _flat_side(o)) is not None]
    if eye is not None and flats:
        k = np.array([k for k, _ in flats])
        centre = np.array([f[0] for _, f in flats])                                   # (F, 3)
        normal = np.array([f[1] for _, f in flats])
        eye_side = np.sign(np.einsum("fi,fi->f", normal, eye - centre))                # (F,)
        light_side = np.sign(np.einsum("fi,nfi->nf", normal, p[:, None] - centre))    # (N, F)
        near[:, k] &= light_side != eye_side   # light and camera on one side: its shadow is out of sight
    counts = near.sum(axis=1)
    return {light.name: int(n) for light, n in zip(lights, counts) if n}


def listed(names):
    names = sorted(names)
    return ", ".join(names[:3]) + (f" and {len(names) - 3} more" if len(names) > 3 else "")


def _effect(shares):
    """", up to X % of a pixel's fog (predicted)" for an account of what is left out (``ops/left_out.shadow_fog``,
    ``dense_fog``: its "missing" share), or "" without one."""
    missing = (shares or {}).get("missing")
    return "" if missing is None or not (shares or {}).get("left_out") else \
        f", up to {missing:.0%} of a pixel's fog (predicted)"


def shadow_notes(scene, lights, beta, reach_m, shafts, why_off=None, shares=None):
    """Notes on the shadows of ``lights`` in the fog: with ``shafts`` (the Compositor method casts them from
    shadow maps), what the maps don't do (soft shadows; moving lights or objects over more frames than an atlas
    holds, ``shadow_maps.ensure``); without, that the objects near the lights cast no shadow into the fog
    (``why_off``: why, else the method has none), with its predicted effect (``shares``: ``ops/left_out.shadow_fog``'s
    account, or None)."""
    found = shadowing_lights(scene, lights, beta, reach_m)
    if not found:
        return []
    if not shafts:
        why = why_off or (f"this method has none: {capabilities.suggestion('shafts', scene.render.engine)} "
                          "casts them")
        return [f"light shafts are not modelled ({why}): objects cast no shadow into the fog, so the glow of "
                f"{len(found)} light(s) ({listed(found)}) passes through the objects near them (a lamp's hood, "
                f"a wall, a window frame){_effect(shares)}"]
    notes = []
    over = set((shares or {}).get("left_out") or ()) if (shares or {}).get("why") == "cap" else set()
    if over:
        notes.append(f"light shafts for the {len(found) - len(over)} lights most important to the picture: the glow "
                     f"of {len(over)} more ({listed(over)}) passes through the objects near them"
                     f"{_effect(shares)} (Quality Exact shafts every light)")
    shafted = [o for o in lights if o.name in found and o.name not in over]
    areas = [o.name for o in shafted if o.data.type == "AREA"]
    if areas:
        notes.append(f"light shafts are sharp: the area lights {listed(areas)} cast theirs from their centres, so "
                     "their soft shadows are sharp in the fog")
    soft = [o.name for o in shafted if o.data.type != "AREA" and getattr(o.data, "shadow_soft_size", 0.0) > 0.0]
    if soft:
        notes.append(f"light shafts are sharp: the Radius of {listed(soft)} softens their shadows on surfaces "
                     "(Cycles) but not in the fog")
    moving = [o.name for o in [*shafted, *shadow_casters(scene)] if is_animated(o)]
    first, stride, count = shaft_maps.atlas_frames(scene.frame_start, scene.frame_end, scene.frame_step)
    if moving and stride > max(scene.frame_step, 1):   # (every rendered frame's map is baked and packed up to the cap)
        notes.append(f"{listed(moving)} move over more than {shaft_maps.ATLAS_MAX_FRAMES} rendered frames: the shafts' "
                     f"shadow maps are baked for every {stride}th frame from {first} ({count} maps a light, packed in "
                     "the file), and the frames between take the latest of them")
    return notes


NOTE_SHARE = 0.01   # the share of a pixel's fog from which what is left out gets a note of its own


def multiple_notes(dense, method_name, is_spot, lights, engine=capabilities.CYCLES):
    """Notes on the multiply scattered light (Dense Fog) the picture lacks or overstates, each with its predicted
    effect: ``dense`` is ``ops/left_out.dense_fog``'s account ({"left_out": {light name: share}, "missing": their
    share together, "why": "off" or the method's name, "surplus", "surplus_missing": ``surplus_notes``}; the
    largest share of a pixel's fog at the view's samples).  Dense
    Fog off: the lights whose glow then lacks its wide halo; on, with a method that does not model it: which
    method does (the OSL method: none of it; the node groups: spot and area lights').  No note under NOTE_SHARE.
    ``is_spot``: a spot or an area light; ``lights``: the lights taking part (their order)."""
    return surplus_notes(dense, lights) + _left_out_notes(dense, method_name, is_spot, lights, engine)


def surplus_notes(dense, lights):
    """The note on Dense Fog's field where surfaces stop part of a light's power before it scatters: scaled by the
    share they leave (``escape.field_scales``), with what the scale may miss (``ops/left_out.scale_error``);
    none under NOTE_SHARE."""
    surplus = (dense or {}).get("surplus") or {}
    share = (dense or {}).get("surplus_missing", 0.0)
    names = [o.name for o in lights if surplus.get(o.name, 0.0) > 0.0]
    if not names or not share >= NOTE_SHARE:
        return []
    return [f"Dense Fog near surfaces: a hood, a wall or the ground near {len(names)} light(s) ({listed(names)}) "
            f"stops part of their light before it scatters; their multiply scattered light is scaled down for it, "
            f"an estimate that may miss up to {share:.0%} of a pixel's fog (predicted)"]


def _left_out_notes(dense, method_name, is_spot, lights, engine):
    left = (dense or {}).get("left_out") or {}
    missing = (dense or {}).get("missing", 0.0)
    names = [o.name for o in lights if left.get(o.name, 0.0) > 0.0]
    if not names or not missing >= NOTE_SHARE:
        return []
    effect = f"up to {missing:.0%} of a pixel's fog (predicted)"
    if dense.get("why") == "off":
        return [f"multiple scattering is off (Dense Fog): the glows of {len(names)} light(s) ({listed(names)}) and "
                f"the fog light on surfaces lack their multiply scattered light, {effect}; turn on Dense Fog"]
    if not capabilities.can(method_name, "dense_point", engine):
        return [f"multiple scattering is not modelled by Method {capabilities.LABELS[method_name]} (its glow is "
                f"quadrature, the dense fog's a table), {effect}: use {capabilities.suggestion('dense_point', engine)}"]
    shaped = [o.name for o in lights if o.name in names and is_spot(o)]
    return [f"the multiply scattered light of {len(shaped)} spot or area light(s) ({listed(shaped)}) is modelled by "
            f"{capabilities.suggestion('dense_shaped', engine)}: with this method it is single scattering, {effect}"]


def glow_notes(glowing, method_name, engine="CYCLES"):
    """Notes on the glowing objects (emissive materials) the camera sees, ``glowing``: with a method other than
    the compositor they have no glow in the fog, and the light they scatter in the fog does not light other surfaces
    (a ground under a neon sign 0.78-0.82 of path tracing); the compositor's fog light of them on surfaces comes
    from points along each, without shadows (``comp_fog.emitter_fog_light``); in EEVEE their light on
    other surfaces is not dimmed by the fog (Cycles dims it in the materials: ``material._dim_emitted_light``)."""
    if not glowing:
        return []
    names = listed([o.name for o in glowing])
    notes = [f"glowing objects ({names}): their fog light on other surfaces is taken from points along each, "
             "without shadows" if capabilities.can(method_name, "emitters", engine) else
             f"glowing objects ({names}): the light they scatter in the fog does not light other surfaces"]
    if engine != "CYCLES":
        notes.append(f"glowing objects ({names}): in EEVEE their light on other surfaces is not dimmed by the fog")
    if not capabilities.can(method_name, "emitters", engine):
        notes.insert(0, f"glowing objects ({names}) have no glow in the fog with this method: "
                        f"{capabilities.suggestion('emitters', engine)} gives them one")
    return notes


CASTER_TYPES = ("MESH", "CURVE", "SURFACE", "META", "FONT")


def shadow_casters(scene):
    """The objects that cast shadows into the fog (rendered, visible to shadow rays)."""
    return [o for o in scene.objects if o.type in CASTER_TYPES and not o.hide_render and o.visible_shadow]


def is_animated(obj):
    """True if ``obj`` (or an object it hangs from) has an action, drivers or constraints."""
    while obj is not None:
        ad = obj.animation_data
        if (ad is not None and (ad.action is not None or len(ad.drivers))) or len(obj.constraints):
            return True
        obj = obj.parent
    return False


def glass_note(materials, objects):
    """A note if see-through materials are in view (the fog behind them is not seen through them), else None."""
    names = see_through(materials, objects)
    if not names:
        return None
    shown = ", ".join(names[:3]) + (f" and {len(names) - 3} more" if len(names) > 3 else "")
    return (f"see-through materials ({shown}): in Cycles with the Node Groups and Compositor methods, the fog "
            "behind glass (a Glass or Refraction BSDF, a Principled BSDF that lets light through; on its own or in a "
            "Mix or Add Shader) and in sharp mirrors is shaded along the path (taken straight through the pane: "
            "frosted glass does not blur a lamp's glow seen through it; with the Compositor, of the 8 brightest "
            "lights, and with more lights than that a sharp mirror shows them blurred by about 2 degrees); glass "
            "inside a node group, the OSL method and EEVEE show only the fog in front of the first surface")


EEVEE_CLIP_RATIO = 1e7   # EEVEE's depth loses its way beyond this clip end / clip start (blender-facts.md)


def clip_note(scene, method_name):
    """A note when EEVEE's camera clip range is too wide for its depth (clip end / clip start beyond
    EEVEE_CLIP_RATIO, with float32's rounding of Clip Start let through), None otherwise.  Measured on the haze
    valley (a 1 mm - 200 km camera, docs/measurements/2026-11-29-eevee-clip-range.md): from a ratio between 3e7
    and 4e7 on (about 2^25, where f - n rounds to f in float32), EEVEE drew none of the ground plane, which reaches
    behind the camera (1216 of 3600 pixels empty, in a render without the fog too), wrote +inf in its Depth
    pass there, and the World goes black (any node set-up, blender-facts.md).  The Compositor method, which
    takes the pixel's surface from the Depth pass, then sees no surface there: it adds the fog's light of a
    pixel that sees the sky (``pixel.depth_surface``)."""
    cam = scene.camera
    if scene.render.engine != "BLENDER_EEVEE" or cam is None or cam.type != "CAMERA":
        return None
    ratio = cam.data.clip_end / max(cam.data.clip_start, 1e-12)
    if ratio <= EEVEE_CLIP_RATIO * (1.0 + 1e-6):   # Clip Start is a float32: 0.02 is stored 0.0199999996
        return None
    depth = capabilities.can(method_name, "depth_pass", scene.render.engine)
    where = ", and the fog's light there is the sky's" if depth else ""
    return (f"{cam.name}: its clip end is {ratio:.2g} x its clip start, beyond the {EEVEE_CLIP_RATIO:.0e} that "
            f"EEVEE's depth holds: EEVEE may leave out surfaces that reach behind the camera (a ground plane) and "
            f"draw a black World{where}; raise Clip Start to {cam.data.clip_end / EEVEE_CLIP_RATIO:.3g} or more")
