"""The Surface group's See Through shader (Cycles): the fog's glows along the segments past a glass pane or a
sharp mirror, by differences of tails to infinity (``place_tails``), built only where the scene has them
(``caveats.specular_paths``).  The Surface group's Glass Color and Glass IOR inputs (fed by ``material.py``)
weight them."""
from typing import Any, NamedTuple

from ..precompute.model import compose, rungs, shading
from . import closures, groups, light_bundles, light_groups, passes, preview_shafts
from .groups import C, F, V
from .sockets import NodeOps

GLASS_COLOR, GLASS_IOR = "Glass Color", "Glass IOR"   # the Surface group's inputs for glass (material.py)
GLASS_WEIGHT = "Glass Weight"       # the share that passes (a Principled BSDF's Transmission Weight; 1 for a Glass BSDF)
GLASS_MIRRORED = "Glass Mirrored"   # 1: the tails take the mirrored segment (a Glass BSDF); 0: the material's own
#                                     glossy fog light is its reflection (a Principled BSDF)
SEE_THROUGH = "See Through"   # its output: the glows past glass and mirrors (Cycles; ``place_tails``)


def specular_segment(m, path):
    """1 on a ray that leaves a glass pane or a mirror on a path of sharp bounces from the camera, or that a rough
    glass let through (Cycles' Light Path: not a camera ray, Is Singular Ray or Is Transmission Ray, Diffuse Depth
    0), else 0.  Such a ray is a segment of its own: it starts at P + Incoming x Ray Length (Ray Length is the
    segment's length on every ray but the camera's, which Cycles measures from the near clip plane).  A rough
    glass's vertex adds the tail straight through it (``place_tails``): the rays its lobe spreads take away their
    own tails, so the segments' glows are right on average and their ends blurred by the lobe's spread of
    directions about the straight one (frosted glass: roughness 0.1, a few degrees).  EEVEE traces no such rays
    (its Is Singular Ray is 0): what it refracts or reflects is its picture or its probes."""
    singular = m.wrap(path.outputs["Is Singular Ray"])
    through = m.maximum(singular, m.wrap(path.outputs["Is Transmission Ray"]))
    first = m.less(m.wrap(path.outputs["Diffuse Depth"]), 0.5)
    return (1.0 - m.wrap(path.outputs["Is Camera Ray"])) * through * first


class Tails(NamedTuple):
    """The lights whose fog past glass and mirrors the Surface group shades, where they are not its own lights
    (the Compositor method's: ``methods.compositor._tails``)."""
    lights: list
    models: list
    shadows: Any = None   # {light name: ShadowMap} of those whose glows and fog light there take their shadows
    g: float = 0.0        # the fog's anisotropy (the shares' phase weight)
    chances: Any = None   # each light's probability of being the one whose glows a sample takes (``sampling.picked``), or
    #                       None: every light on every sample
    cycles: bool = False  # built for Cycles alone: the light groups' tables read by its filter (``NodeOps.cycles``)


def place_tails(m, ng, lights, models, images, geo, g, segment, is_camera, t_vp, shared, below, extra=(),
                shadows=None, g_=0.0, chances=None, pick=None, cycles=False, mirror=None):
    """The Surface group's See Through shader (Cycles only: ``material.py`` adds it to the Cycles output):
    the glows of the segments past a glass pane or a mirror, by differences of tails.

    The glow of a light along a segment from a to b is G_inf(a) - e^{-beta |ab|} G_inf(b) (Sun et al. 2005
    Eq. 12's glow to infinity, ``shading.background_point``, from each end in the segment's direction; the
    sum of differences of one primitive, Biri 2006 §III.D).  So each vertex of a sharp path adds what it
    can compute without knowing where the next segment ends, the glow to infinity of the segments leaving
    it, weighted as Cycles weights them; and each vertex a sharp segment reaches takes away the tail past
    itself, dimmed by its own segment, e^{-beta Ray Length}.  A segment that escapes to the sky keeps its
    whole tail: the World, which knows no ray origin, adds nothing on those rays
    (``world_group.build_world``).  Cycles multiplies by the path's throughput, so each segment's glow and
    extinction compose along the path (Eq. 19 applied at every vertex).  The leaving segments' weights:

    * a Glass BSDF (``GLASS_COLOR``, ``GLASS_IOR`` fed by ``material.py``): colour x (1 - F) straight on
      (the segment's direction through a thin pane, exact for IOR 1 and for a parallel slab up to its
      thickness) and colour x F about the mirrored direction, F the dielectric Fresnel factor (Fresnel
      node, as Cycles' glass);
    * a Principled BSDF with transmission (Blender's usual glass, sharp or frosted; ``GLASS_WEIGHT`` its
      Transmission Weight, ``GLASS_MIRRORED`` 0), a Refraction BSDF (IOR 1: no Fresnel, no reflection): colour x
      weight x (1 - F) straight on, its reflection that of its specular layer (next);
    * a sharp mirror (a specular layer Cycles reflects as singular, ``surface.sharp_share``; ``mirror``: its colour,
      the layer's albedo, an output socket's value): ``mirror`` about the mirrored direction, its glossy fog light
      then left to this (``surface_group.build_surface``);
    * glass in a Mix or Add Shader: ``GLASS_WEIGHT`` times its share there (``material._build``); what the vertex
      of a segment lets straight through beside it (1 - the Opacity input) takes the straight tail too;
    * a glossy surface Cycles does not reflect as singular, or a sharp mirror whose tails do not hold every light
      (the Compositor's beyond its 8): its glossy fog light (``shading.shade_point``'s Phong lobe, at most the
      highest exponent's, a tail to infinity blurred by about 2 degrees) stands for the tail.

    ``below``: the Surface group's light bundles placed (their rows).  ``extra``: more shader outputs summed into See
    Through (the fog light the surfaces past glass reflect, where the materials hold no lights: the Compositor
    method's, ``surface_group.build_surface``).  ``shadows``, ``g_``: the lights' shadow maps and the fog's
    anisotropy (``build_tail_bundle``).  ``chances``: each light's probability of being a sample's one (``sampling.picked``),
    drawn by ``pick`` (an output socket: ``pick_noise``), or None.  ``cycles``: the light groups for Cycles alone
    (``light_groups.build_light``).  Returns the bundle groups built.
    """
    kept = [(light, mod, p) for light, mod, p in zip(lights, models, chances or [None] * len(lights))
            if any(o.computed(mod) for o in rungs.SKY_OUTPUTS if o.colour)]
    if chances is not None and kept:
        total = sum(p for _, _, p in kept)
        chances = [p / total for _, _, p in kept]
    kept = [(light, mod) for light, mod, _ in kept]
    if not kept:
        return []
    fresnel = ng.nodes.new("ShaderNodeFresnel")
    fresnel.location = (-600, 600)
    ng.links.new(g[GLASS_IOR], fresnel.inputs["IOR"])
    f = m.wrap(fresnel.outputs[0])
    glass = m.scale(m.wrap(g[GLASS_COLOR], vector=True), m.wrap(g[GLASS_WEIGHT]))
    incoming = m.wrap(geo.outputs["Incoming"], vector=True)
    seg3 = m.combine(segment, segment, segment)
    # what a specular segment's vertex lets straight through (a Transparent BSDF, Alpha, beside glass in a mix): its
    # ray goes on as the same kind of segment, which the next vertex ends by taking away the tail past itself
    through = m.scale(m.maximum(m.combine(1.0, 1.0, 1.0) - m.wrap(g[passes.OPACITY], vector=True),
                                m.combine(0.0, 0.0, 0.0)), segment)
    # the tails' own copy of Position (the same value): the light groups' nodes that read Position would
    # otherwise be one node in Cycles' graph (its deduplication) with the Surface bundles' and, read by both
    # sides of the closure tree, stay on SVM's stack for both: 4 floats a light (199 floats at 24 lights)
    position = m.wrap(shared["Position"], vector=True) + closures.exact_zero(m, incoming)
    mirrored = m.scale(glass, f * m.wrap(g[GLASS_MIRRORED]))
    if mirror is not None:
        mirrored = mirrored + mirror
    inputs = dict(shared, **{"Position": position.sock, "Straight": m.scale(incoming, -1.0).sock,
                             "Mirrored": shading.mirror(m, incoming, m.wrap(geo.outputs["Normal"], vector=True)).sock,
                             "Straight Weight": (m.scale(glass, 1.0 - f) - seg3 + through).sock,
                             "Mirrored Weight": mirrored.sock,
                             "Transmittance": t_vp.sock})
    if chances is not None:
        inputs["Pick"] = pick
    fogs, trees = [], []
    for first, some, mods in light_bundles.split([light for light, _ in kept], [mod for _, mod in kept]):
        tree = build_tail_bundle(images, first, some, mods, shadows, g_, chances, cycles)
        trees.append(tree)
        node = light_bundles.group_node(ng, tree, tree.name.removesuffix(groups.BUILDING), -300,
                                        -300 * (below + len(fogs)), [(src, n) for n, src in inputs.items()])
        fogs.append(node.outputs["Fog"])
    out = next(n for n in ng.nodes if n.bl_idname == "NodeGroupOutput").inputs[SEE_THROUGH]
    closures.shader_tree(ng, out, fogs + list(extra))
    # only on a specular segment, or on a camera ray that meets glass: a factor of exactly 0 elsewhere, where
    # Cycles' SVM jumps over the tails (``closures.camera_rays_only``)
    has_glass = m.less(0.0, m.dot(glass if mirror is None else glass + mirror, m.combine(1.0, 1.0, 1.0)))
    gate = m.clamp(segment + is_camera * has_glass)
    closures.camera_rays_only(ng, out, gate.sock, "Specular Paths Only")
    return trees


def build_tail_bundle(images, first, lights, models, shadows=None, g_=0.0, chances=None, cycles=False):
    """One bundle of the Surface group's See Through shader (``place_tails``): for each light, its glow to infinity
    from Position along Straight times Straight Weight, and the same along Mirrored times Mirrored Weight, composed
    (``shading.segment_terms``: times the albedo and Transmittance), from two instances of its World group
    (``light_groups.build_background_light``), each tail an Emission closure of its own (its colour may be
    negative: Cycles passes negative emission through).

    ``shadows``: {light name: ShadowMap} of the lights whose tails take their lit shares (fog of anisotropy
    ``g_``).  A tail to infinity times its own lit share is the glow of that ray's lit part (``shafts.lit_share``,
    Dobashi et al. 2002 Eq. 2), so the difference of two such tails is still the segment's lit glow: each vertex
    needs only its own ray.  The shares' quadrature is turned at every sample (``preview_shafts.py``).

    ``chances`` (every tail light's, in the order of the bundles): a sample takes one light's tails, drawn by the
    Pick input (``sampling.picked``), or None: every light's."""
    name = light_bundles.bundle_name(groups.SURFACE_TAILS, first, lights)
    ng, gin, gout = groups.new_group(name, [("Beta", F), ("Albedo", C), ("Position", V), ("Straight", V),
                                            ("Mirrored", V), ("Straight Weight", C), ("Mirrored Weight", C),
                                            ("Transmittance", F)] + ([("Pick", F)] if chances is not None else []),
                                     [("Fog", "NodeSocketShader")])
    m = NodeOps(ng, {})
    g = {s.name: s for s in gin.outputs if s.name}
    pixel = compose.Pixel(1.0, m.wrap(g["Albedo"], vector=True))
    colours, jitter = [], None
    mirrored_gate = m.less(0.0, m.dot(m.wrap(g["Mirrored Weight"], vector=True), m.combine(1.0, 1.0, 1.0)))
    for k, (light, mod) in enumerate(zip(lights, models)):
        shares = []
        if shadows and light.name in shadows:   # first: SVM compiles them before the light's kernels
            jitter = jitter or preview_shafts.jitter(ng, g["Position"])
            shares = [preview_shafts.shares(ng, light, shadows[light.name], images, g_, {
                "Beta": g["Beta"], "Camera": g["Position"], "Direction": g[way], "Length": preview_shafts.SKY_LENGTH,
                "Position": g["Position"], "Normal": g[way], "Jitter": jitter}, preview_shafts.FINAL_SAMPLES)
                for way in ("Straight", "Mirrored")]
        group = light_groups.build_background_light(mod, images, cycles).name
        straight = light_groups.light_instance(ng, first + k, light, group, [
            (g["Beta"], "Beta"), (g["Position"], "Camera"), (g["Straight"], "Direction")])
        for node in shares:
            ng.links.new(straight.inputs["Light"].links[0].from_socket, node.inputs["Light"])
        mirrored = ng.nodes.new("ShaderNodeGroup")
        mirrored.node_tree = straight.node_tree
        mirrored.name = mirrored.label = f"{straight.name} (mirrored)"
        mirrored.location = (straight.location.x, straight.location.y - 150)
        for sock in straight.inputs:
            src = g["Mirrored"] if sock.name == "Direction" else (sock.links[0].from_socket if sock.is_linked
                                                                  else None)
            if src is not None:
                ng.links.new(src, mirrored.inputs[sock.name])
        # two closures, never one of their sum (``closures.closure_sum`` says why): SVM compiles a closure's
        # inputs' nodes together, so one Emission of straight + mirrored had both tails' kernels on its stack
        # at once (a spot at the full step: 255 floats, out of SVM stack space, the glass black; 178 as two)
        for j, (node, weight) in enumerate(((straight, g["Straight Weight"]), (mirrored, g["Mirrored Weight"]))):
            colour = compose.compose(m, pixel, shading.segment_terms(
                m, m.wrap(node.outputs[rungs.BACKGROUND_OUT.name], vector=True), m.wrap(weight, vector=True),
                m.wrap(g["Transmittance"]),
                m.wrap(shares[j].outputs["Share"]) if shares else None)).light
            # the mirrored tail behind a gate: 0 where nothing is mirrored (a Principled glass, whose reflection is
            # its own glossy fog light), where SVM jumps over its kernels and its share
            colour = shading.Gated(mirrored_gate, colour, None) if j else colour
            if chances is not None:   # only on the samples that take this light (``sampling.picked``)
                colour = closures.drawn(m, colour, m.wrap(g["Pick"]), chances, first + k)
            colours.append(colour)
    closures.closure_sum(m, gout.inputs["Fog"], "ShaderNodeEmission", colours)
    m.place()
    return ng
