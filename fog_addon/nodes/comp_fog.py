"""The Compositor method: the fog's light computed once per pixel in Blender's compositor.

With the node-group methods every fogged material evaluates every light's fog on every sample: the
cost grows with lights x samples x materials (issue 8's overhead: 4x the fog-free render at one light,
29x at 16).  Here the materials keep only what depends on the surface's depth along each sample:

* each light dims its own direct light through the fog (``light.py``: O(1) in the number of lights);
* every fogged material is scaled by e^{-beta D_vp} (the Surface group built without lights), and the
  Surface group writes the pixel's inputs as shader AOVs (``AOVS``): coverage, position, normal and the
  Principled inputs, each averaged over the pixel's samples;
* the World is black (the fog hides it);
* the compositor's ``AnalyticFog Compositor Fog`` group adds, per pixel, ``shading.shade_point`` at the
  pixel's mean surface point and the glows along the pixel's ray to it and to the sky
  (``shading.glow_pair``) over the lights, built by ``CompOps`` (the same formulas and tables as the
  materials' groups, each node once), plus the peak factor of ``pixel.py`` where a light is seen in the
  picture; each light in two groups, its glows (``build_glow_group``) and the fog light its surface
  reflects (``build_scatter_group``), each evaluated only in its window (``precompute/footprint.py``: a
  spot's cone, the picture's surfaces) through Crop nodes, and put back in place by Translate nodes.

Everything the graph reads from the scene reaches it by simple-expression drivers (the camera's matrix,
lens, sensor and shift, the render's size, each light's position, power, colour and cone, the fog's
density and colour in the params group; the windows' crops from ID properties that hold every frame of an
animation): a saved file renders any frame on a farm without the add-on.

In EEVEE, which writes AOVs as half floats accumulated with a loss and clamps negatives, the surface point
is the Depth pass's (float32) on the pixel's ray (``EEVEE_AOVS``), and the materials keep the lights' shared
dimming of direct light (EEVEE has no light node trees: ``methods.compositor.dimming_lights``).

Limits (README "The Compositor method"): one surface point per pixel, so a pixel that sees two surfaces
gets the fog light of one point (Cycles: their mean position; EEVEE: the one its centre sees); perspective
cameras; no fog passes (the fog's light is the compositor's).
"""
import dataclasses
import functools
import hashlib
import math
from typing import Any, NamedTuple

import bpy

from ..precompute import (emitter_glow, footprint, model, pixel, rungs, shading, shafts, spot as spot_, sunlight,
                          surface)
from . import compositor, groups, images as images_, owned
from .sockets import KERNEL_GROUP, NodeOps, Val

FOG_GROUP = f"{owned.PREFIX} Compositor Fog"     # the compositor group that adds the fog's light
LIGHT_GROUP = f"{owned.PREFIX} Compositor Light"  # per-light compositor groups: "<LIGHT_GROUP> [models]"
BUNDLE = f"{owned.PREFIX} Compositor Bundle"     # the scene's lights by BUNDLE_SIZE: "<BUNDLE> 1-8", ...
BUNDLE_SIZE = 8   # lights a bundle: Blender's node and link editing grows with a tree's size (one tree of 256
#                   lights with their drivers took over 15 min to build; ``build_fog_group``)
KERNEL_PREFIX = f"{KERNEL_GROUP} Compositor"   # the kernels' compositor groups (``sockets.NodeOps.group``)
AOVS = (("Fog Coverage", "VALUE"), ("Fog Position", "COLOR"), ("Fog Normal", "COLOR"),
        ("Fog Base Color", "COLOR"), ("Fog Metallic", "VALUE"), ("Fog Roughness", "VALUE"),
        ("Fog Specular IOR Level", "VALUE"))
# EEVEE writes AOVs as half floats accumulated with a loss (a constant 37.123 read back 37.03-37.09 at 16
# samples, README "The Compositor method") and clamps negatives: its surface point is the Depth pass's (float32,
# the sample nearest the pixel's centre) along the pixel's ray, with the mean View Z Depth where they disagree
EEVEE_AOVS = tuple(("Fog Depth", "VALUE") if name == "Fog Position" else (name, kind) for name, kind in AOVS)
DEPTH_AGREE = 0.02     # the Depth pass is the pixel's surface where within 2 % of the mean View Z Depth
AOV_ROLE = "Compositor AOV"   # the Surface group's AOV Output nodes: "<AOV_ROLE> <AOV name>"
PRINCIPLED = ("Base Color", "Metallic", "Roughness", "Specular IOR Level")
V, C, F = "NodeSocketVector", "NodeSocketColor", "NodeSocketFloat"
# what a light's glow group reads of the pixel (the same for all lights), and what its scatter group reads
GLOW_SHARED = (("Beta", F), ("Camera", V), ("Incoming", V), ("View Distance", F), ("Direction", V), ("Pixel", V),
               ("Corner", V), ("Across", V), ("Up", V), ("Size", V), ("Glow Origin", V), ("Glow Length", F))
SURFACE_SHARED = (("Beta", F), ("Camera", V), ("Position", V), ("Incoming", V), ("Normal", V), ("Diffuse", V),
                  ("Specular", V), ("Level", F))
SURFACE_IMAGES = tuple(name for name, _ in SURFACE_SHARED[2:])   # per pixel: cropped to the surfaces' window
SURFACE = "Surface "   # a bundle's inputs of SURFACE_IMAGES: "Surface Position", ...
# what a light's shaft group reads (``build_shaft_group``): the ray's length to its surface (or far beyond the
# world where the pixel sees only the sky)
SHAFT_SHARED = (("Beta", F), ("Camera", V), ("Direction", V), ("Shaft Length", F), ("Shaft Offset", F))
SHAFT_PER_PIXEL = ("Direction", "Shaft Length", "Shaft Offset")
SHAFT_TAPS = (1, 2, 1)   # the separable filter that averages the 2 x 2 interleaved shares (``_interleave_mean``)
SHAFT_EDGE = 0.05     # its threshold on log distance: neighbours 5 % nearer or farther are not mixed
SKY_LENGTH = 1.0e6   # m: a ray to the sky's length for the shafts (its far nodes weigh e^{-beta t})
LAYER_OPEN = 1.0e9   # units: a fog layer's span end beyond this is open (``sunlight.lamp_glow_span``'s UNBOUNDED)
SHAFT_GROUP = f"{LIGHT_GROUP} Shaft"      # a spot's "<SHAFT_GROUP> <light name>", point lights' shared
SHAFT_MAP = "Map"   # a shaft group's input: the light's shadow map (``build_shaft_group``)
SURFACE_OFFSET = SURFACE + "Offset"   # a surface's interleaving offset (``shafts.surface_offset``)
# the filter over the 4 x 4 interleaved surface shares (``shafts.surface_offset``): (1, 2, 2, 2, 1)
SURFACE_TAPS = (1,) + (2,) * (2 ** shafts.SURFACE_PATTERN_LEVELS - 1) + (1,)
SURFACE_EDGE = 0.3    # its threshold on log distance (a floor seen at a grazing angle changes faster than 5 % a row)
HALF = "Half "   # a bundle's inputs for the surface share at a coarser resolution (``_halved``)
HALF_SHARED = ((HALF + "Position", V), (HALF + "Normal", V), (HALF + "Offset", F), (HALF + "Length", F),
               (HALF + "Step", F), (HALF + "Shaft Offset", F))
HALF_SHAFT = {"Direction": "Direction", "Shaft Length": "Shaft Length", "Shaft Offset": HALF + "Shaft Offset"}
#             a shaft group's per-pixel inputs at half resolution: from these bundle inputs (``_half_view``)
HALF_FROM = 144   # px: a picture whose shorter side has this many pixels or more takes the shafts' shares at half
#                   its resolution (``_halved``: twice the render tests' 72, whose pattern it then matches in the scene)
QUARTER_FROM = 2 * HALF_FROM   # px: from this many, at a quarter (never coarser: 72 samples or more a side)
UPSAMPLE_EDGE = 0.1   # ``_upsampled``'s threshold on log distance: a coarse sample of another surface is not taken
HALO_STEP = "Halo Step"   # px between the samples of the multiply scattered halos (``build_bundle``): 1, 2 or 4
SHARED = (GLOW_SHARED + tuple((SURFACE + name, kind) for name, kind in SURFACE_SHARED[2:])
          + ((SURFACE_OFFSET, F),) + SHAFT_SHARED[3:] + HALF_SHARED + ((HALO_STEP, F),))   # a bundle's inputs
# the quantities the compositor sums per pixel (``rungs.COMPOSITOR_OUTPUTS``, by their compositor sockets): a light's
# glows (rungs.GLOW) in its glow group, over the picture or the light's window; the light its surface reflects
# (the rest) in its scatter group, over the surfaces' window
GLOW_OUTPUTS = tuple(o for o in rungs.COMPOSITOR_OUTPUTS if o.kind == rungs.GLOW)
SCATTER_OUTPUTS = tuple(o for o in rungs.COMPOSITOR_OUTPUTS if o.kind != rungs.GLOW)
GLOW_TERMS = tuple((o.compositor, V) for o in GLOW_OUTPUTS)            # Airlight, Background
SCATTER_TERMS = tuple((o.compositor, V) for o in SCATTER_OUTPUTS)      # Scattered
TERMS = tuple((o.compositor, V) for o in rungs.COMPOSITOR_OUTPUTS)     # a bundle's: Airlight, Scattered, Background
WINDOW = "Fog Window"   # ID properties (u0, u1, v0, v1) of the windows (``footprint.py``): a bundle's "<WINDOW> <k>"
#                         for its k-th light's glow, the fog group's "<WINDOW> Surface" for the fog light on surfaces


class CompOps(NodeOps):
    """NodeOps building into a compositor tree: compositor groups, tables read by Map UV, no EEVEE flags.

    Each node is built once per tree (``NodeOps``): Blender's compositor evaluates every node it is given,
    over every pixel."""

    GROUP_NODE = "CompositorNodeGroup"
    GROUP_TREE = "CompositorNodeTree"
    SEPARATE_COLOR = "CompositorNodeSeparateColor"
    KERNEL_PREFIX = KERNEL_PREFIX
    inline = staticmethod(lambda node: None)

    def select(self, cond, if_true, if_false):
        """One Mix node (Float) for the four Math nodes of ``NodeOps.select``: (1 - cond) if_false + cond if_true,
        exact for cond in {0, 1} as theirs (a Mix node's unused inputs cost EEVEE uniforms, not the compositor)."""
        vals = [self.wrap(v) for v in (cond, if_false, if_true)]
        if any(v.vector for v in vals) or vals[0].const is not None:
            return super().select(cond, if_true, if_false)
        return self._once(("select", self._ids(vals)), lambda: self._new_select(*vals))

    def _new_select(self, cond, if_false, if_true):
        col = 1 + max(v.col for v in (cond, if_false, if_true))
        n = self.node("ShaderNodeMix", col, data_type="FLOAT", clamp_factor=False)
        for name, v in (("Factor_Float", cond), ("A_Float", if_false), ("B_Float", if_true)):
            self.feed(next(s for s in n.inputs if s.identifier == name), v)
        return Val(self, sock=next(s for s in n.outputs if s.identifier == "Result_Float"), col=col)

    def _table(self, spec, x, y, row0=0, rows=None, channel=0):
        """``channel`` of one bilinear Map UV (the compositor's interpolation is exact bilinear between texel
        centres; the channels of a texel share it): x, y in [0, 1] span the texel centres of rows row0 ..
        row0 + rows - 1."""
        mu, col = self._once(("map uv", spec.name, row0, rows, self._ids((x, y))),
                             lambda: self._map_uv(spec, x, y, row0, rows))
        return self.texel(spec, mu, col, channel)

    def _map_uv(self, spec, x, y, row0, rows):
        rows = spec.height if rows is None else rows
        u = self.clamp(x) * ((spec.width - 1.0) / spec.width) + 0.5 / spec.width
        v = self.clamp(y) * ((rows - 1.0) / spec.height) + (row0 + 0.5) / spec.height
        uv = self.combine(u, v, 1.0)   # Map UV takes the third component as the UV's alpha: 0 gives black
        mu = self.node("CompositorNodeMapUV", uv.col + 1)
        mu.inputs["Interpolation"].default_value = "Bilinear"
        source = self.images[spec.name]   # an image of the file, or a group's image input (``_socket_images``)
        if isinstance(source, Val):
            self.tree.links.new(source.sock, mu.inputs["Image"])
        else:
            im = self.node("CompositorNodeImage", uv.col + 1)
            im.image = source
            self.tree.links.new(im.outputs["Image"], mu.inputs["Image"])
        self.tree.links.new(uv.sock, mu.inputs["UV"])
        return mu, uv.col + 1


def glow_group_name(models, peak):
    """``peak``: the pixel filter's table (``pixel.filter_table``) or None."""
    suffix = "" if peak is None else " Peak" + (" EEVEE" if peak is pixel.EEVEE_FILTER else "")
    return f"{LIGHT_GROUP} Glow [{models.airlight.name}, {models.background.name}]" + suffix


def pixel_filter(scene):
    """(the pixel filter's type for ``pixel.filter_scale``, the data path of its width) where a peak factor
    applies, else None: Cycles' Blackman-Harris filter, EEVEE's film filter (not at 1 sample, where EEVEE
    takes each pixel's centre), a width above 0."""
    if scene.render.engine == "CYCLES":
        kind, path = scene.cycles.pixel_filter_type, "cycles.filter_width"
    elif scene.render.engine == groups.EEVEE_ENGINE and scene.eevee.taa_render_samples > 1:
        kind, path = "EEVEE", "render.filter_size"
    else:
        return None
    return (kind, path) if pixel.filter_scale(kind, scene.path_resolve(path)) is not None else None


def scatter_group_name(models):
    return f"{LIGHT_GROUP} Scatter [{models.scatter.name}]"


def all_group_names():
    """The compositor groups the fog can make in this file, users first: the fog group, the bundles, the
    per-light groups (their kernels are among ``groups.all_group_names``, which must come after these)."""
    names = {owned.base_name(ng.name) for ng in bpy.data.node_groups
             if ng.get(groups.FOG_PROP) and ng.name.startswith((LIGHT_GROUP, BUNDLE))}
    return [FOG_GROUP] + sorted(names, key=lambda name: (not name.startswith(BUNDLE), name))


def _light_group(name, shared, terms, models, images):
    """(group, CompOps, its inputs by name, its output node, its light) of a new per-light group ``name``."""
    ng, gin, gout = groups._new_group(name, [*shared, ("Light", V), ("Intensity", V), *groups._spot_inputs(models)],
                                      terms, tree_type="CompositorNodeTree")
    m = CompOps(ng, images)
    g = {s.name: m.wrap(s, vector=s.type in ("VECTOR", "RGBA")) for s in gin.outputs if s.name}
    return ng, m, g, gout, groups._light(g, models)


def build_glow_group(models, images, peak):
    """One light's glows at a pixel (compositor group), shared by every light with these models: Airlight
    (the glow along the pixel's ray up to the surface, Sun et al. 2005 Eq. 11) and Background (the glow of
    the ray to the sky, Eq. 12), from ``shading.glow_pair``.  ``peak``: the pixel filter's table or None;
    with one, times the peak factor (``pixel.peak_factor``) where the ray passes the light, seen in the picture at
    ``pixel.picture_position`` (Corner, Across, Up: the image plane, Size: the picture's, ``camera_frame``
    and ``_picture_scale``).  The glows are the kernels' from Glow Origin over Glow Length (the camera and the
    view distance, or in a fog layer the part of the ray in it: ``sunlight.lamp_glow_span``); the peak takes the
    camera's.  Reads GLOW_SHARED (Incoming and Pixel only with ``peak``)."""
    name = glow_group_name(models, peak)
    if (ng := groups._up_to_date(name)) is not None:
        return ng
    ng, m, g, gout, light = _light_group(name, GLOW_SHARED, GLOW_TERMS, models, images)
    glows = shading.light_glows(m, g["Glow Origin"], g["Direction"], g["Glow Length"], light,
                                groups._medium(m, g["Beta"]), models)
    if peak is not None:   # the sky's rays pass every light before the end of the world: its factor is 1 + excess
        to_light = g["Light"] - g["Camera"]
        seen_at = pixel.picture_position(m, to_light, g["Corner"], g["Across"], g["Up"], g["Size"])
        excess = pixel.peak_excess(m, g["Pixel"], seen_at, peak)
        along = m.dot(to_light, -1.0 * g["Incoming"])
        factors = {rungs.SURFACE_POINT: pixel.peak_factor(m, excess, along, g["View Distance"]),
                   rungs.SKY: 1.0 + excess}
        glows = {o: m.scale(v, factors[o.at]) for o, v in glows.items()}
    for o in GLOW_OUTPUTS:
        m.feed(gout.inputs[o.compositor], glows[o])
    ng[owned.BUILT] = groups.code_fingerprint()
    m.place()
    return groups._install(ng, name)


def build_scatter_group(models, images):
    """One light's fog light reflected by the pixel's surface (compositor group: Scattered, Sun et al. 2005
    Eq. 17-18 through ``shading.shade_point``), shared by every light with these models.  Reads
    SURFACE_SHARED."""
    name = scatter_group_name(models)
    if (ng := groups._up_to_date(name)) is not None:
        return ng
    ng, m, g, gout, light = _light_group(name, SURFACE_SHARED, SCATTER_TERMS, models, images)
    geo = shading.Geometry(g["Camera"], g["Position"], g["Incoming"], m.wrap(0.0), g["Normal"])
    material = shading.Material(g["Diffuse"], g["Specular"], g["Level"])
    terms = shading.shade_point(m, geo, material, light, groups._medium(m, g["Beta"]), models, air=m.wrap(0.0))
    for o in SCATTER_OUTPUTS:
        m.feed(gout.inputs[o.compositor], m.wrap(getattr(terms, o.field)))
    ng[owned.BUILT] = groups.code_fingerprint()
    m.place()
    return groups._install(ng, name)


def shaft_group_name(light, shadow, samples, g):
    """The shaft group of ``light``: one for every point light of the same map size, samples and g (their maps
    differ only in what the group's Map input reads), one per spot (its frame and cone are built in; a moving
    spot's map frame, its cone being inputs)."""
    if shadow.spot is not None or shadow.cone:
        return f"{SHAFT_GROUP} {light.name}"
    return (f"{SHAFT_GROUP} Point {shadow.spec.width}x{shadow.spec.height} g {g:.6g} "
            f"K {samples.view_nodes} {samples.surface_directions}x{samples.surface_nodes}")


def build_shaft_group(light, shadow, images, samples, g):
    """``light``'s lit share of its glow along the pixel's ray (compositor group: Share, ``shafts.lit_share``)
    from its shadow map ``shadow`` (``shadow_maps.ShadowMap``), and the share of the fog light the pixel's
    surface reflects that the shadows leave (Visible, ``shafts.surface_share``).
    ``samples``: ``shafts.Samples`` (the Quality's); ``g``: the Henyey-Greenstein anisotropy.  The spot's frame
    and cone are the map's (baked at its pose); a moving spot's (``shadow.cone``) cone is the group's spot inputs
    (``groups._spot_inputs``, fed by its glow's drivers in the bundle) and its map's frame the one of all its
    poses.  The map is the group's Map input (its Image node is the bundle's, an animation's map cut from its atlas
    there: ``_atlas_tile``), so point lights share one group (``shaft_group_name``), built once."""
    name = shaft_group_name(light, shadow, samples, g)
    if shadow.spot is None and not shadow.cone and (ng := groups._up_to_date(name)) is not None:
        return ng
    cone = [(n, V) for n in groups.SPOT_ROWS] + [(groups.SPOT_COS, F), (groups.SPOT_BLEND, F)] if shadow.cone else []
    ng, gin, gout = groups._new_group(name, [*SHAFT_SHARED, ("Light", V), ("Surface Position", V),
                                             ("Surface Normal", V), ("Surface Offset", F), (SHAFT_MAP, C), *cone],
                                      [("Share", F), ("Share Far", F), ("Visible", V)],
                                      tree_type="CompositorNodeTree")
    falloff, kind = None, f"point {shadow.spec.width}x{shadow.spec.height}"
    if shadow.cone:   # the cone of the light's pose at the frame (in its space: ``spot_.light_space``)
        kind = f"moving {shadow.spec.width}x{shadow.spec.height} " + hashlib.sha1(
            repr(shadow.spot).encode()).hexdigest()[:12]
    elif shadow.spot is not None:
        frame, half = shadow.spot
        forward = frame[2]
        cos_half = math.cos(0.5 * light.data.spot_size)
        blend = float(light.data.spot_blend)
        falloff = lambda m, u, d: spot_.spot_falloff(m, m.dot(u, forward) / d, cos_half, blend)
        kind = "spot " + hashlib.sha1(repr((shadow.spec.width, frame, half, cos_half, blend)).encode()).hexdigest()[:12]
    spec = dataclasses.replace(shadow.spec, name=f"{SHAFT_MAP} {kind}")   # read from the Map input
    m = CompOps(ng, dict(images))
    m.images[spec.name] = m.wrap(gin.outputs[SHAFT_MAP], vector=True)
    g_ = {s.name: m.wrap(s, vector=s.type in ("VECTOR", "RGBA")) for s in gin.outputs if s.name}
    cone_args = ()
    if shadow.cone:   # the rows' 9 components, cos(size / 2) and blend: scalar inputs of the node groups
        axes = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
        cone_args = tuple(m.dot(g_[n], a) for n in groups.SPOT_ROWS for a in axes) + (g_[groups.SPOT_COS],
                                                                                        g_[groups.SPOT_BLEND])

        def driven_falloff(mm, u, d, *cone_):   # (inside the node groups: their own inputs, ``cone_args``)
            rows = [mm.combine(*cone_[3 * i:3 * i + 3]) for i in range(3)]
            x, y, z = spot_.light_space(mm, rows, u)
            return spot_.spot_falloff(mm, -1.0 * z / mm.maximum(mm.sqrt(x * x + y * y + z * z), 1e-30), cone_[9],
                                      cone_[10])
        falloff = driven_falloff
    node = f"Shaft Node {kind} g {g:.6g}"   # one group for every quadrature node
    share, far = shafts.lit_share(m, g_["Camera"], g_["Direction"], g_["Shaft Length"], g_["Light"], g_["Beta"],
                                  (spec, shadow.spot), samples.view_nodes, shift=g_["Shaft Offset"], g=g,
                                  falloff=falloff, name=node,
                                  tail_nodes=max(samples.view_nodes // shafts.TAIL_SHARE, 2), far=SKY_LENGTH,
                                  cone=cone_args)
    m.feed(gout.inputs["Share"], share)
    m.feed(gout.inputs["Share Far"], far)
    lit_sum, total = shafts.surface_share(m, g_["Surface Position"], g_["Surface Normal"], g_["Camera"],
                                          g_["Light"], g_["Beta"], (spec, shadow.spot),
                                          shift=g_["Surface Offset"], g=g, falloff=falloff, name=node, parts=True,
                                          directions=samples.surface_directions, nodes=samples.surface_nodes,
                                          cone=cone_args)
    m.feed(gout.inputs["Visible"], m.combine(lit_sum, total, 1.0))   # their ratio after the mean (``build_bundle``)
    ng[owned.BUILT] = groups.code_fingerprint()
    m.place()
    return groups._install(ng, name)


def _atlas_tile(m, image, label):
    """The map of the frame being rendered, cut from ``image``, a light's atlas of an animation's maps
    (``shadow_maps.Atlas``): its tile t (``shafts.ATLAS_TILE``, a simple-expression driver of the frame and the
    atlas's first frame, stride and tile count, read from the image's ``shadow_maps.ATLAS`` property, so an atlas
    baked again for another range needs no new nodes) in slot t // 4 (a Crop node at its column and row: the
    atlas's columns and its maps' grid read from the image too) and channel t % 4 (selected by weights 0 or 1:
    exact, a NO_HIT of 1e30 times 0 is 0), in all four channels of an image of one map, as the shaft group's Map
    input reads a still map (the compositor's Crop, Separate and Combine Color and Map UV read it bit-exactly)."""
    from .. import shadow_maps
    prop = f'["{shadow_maps.ATLAS}"]'
    tile = _value(m, f"{label} Tile", shafts.ATLAS_TILE,
                  [("s", image, f"{prop}[0]"), ("k", image, f"{prop}[1]"), ("n", image, f"{prop}[2]")])
    columns, width, height = (_value(m, f"{label} {part}", "v", [("v", image, f"{prop}[{i}]")])
                              for i, part in ((3, "Columns"), (5, "Width"), (6, "Height")))
    slot = m.floor(tile * (1.0 / shafts.ATLAS_CHANNELS))
    channel = tile - slot * float(shafts.ATLAS_CHANNELS)
    row = m.floor(slot / columns)
    column = slot - row * columns
    source = m.node("CompositorNodeImage", 4)
    source.image = image
    crop = m.node("CompositorNodeCrop", 5)
    m.tree.links.new(source.outputs["Image"], crop.inputs["Image"])
    for socket, v in (("X", column * width), ("Y", row * height), ("Width", width), ("Height", height)):
        m.feed(crop.inputs[socket], v)
    split = m.node("CompositorNodeSeparateColor", 6)
    m.tree.links.new(crop.outputs[0], split.inputs[0])
    depth = None
    for c in range(shafts.ATLAS_CHANNELS):
        weight = m.less(m.abs(channel - float(c)), 0.5)
        term = m.wrap(split.outputs[c]) * weight
        depth = term if depth is None else depth + term
    joined = m.node("CompositorNodeCombineColor", 8)
    for c in range(4):
        m.feed(joined.inputs[c], depth)
    return m.wrap(joined.outputs[0], vector=True)


def _shared_group(m, name, inputs, output, build):
    """A group node in ``m``'s tree of the compositor group ``name``, built once for every light and bundle (a
    tree's node creation slows as it grows): ``inputs`` its ((name, socket type, value) ...), fed here;
    ``output`` (name, socket type) of its one output, ``build(sub, ins)`` its value from its inputs' Vals by
    name.  Returns the output's Val."""
    if (ng := groups._up_to_date(name)) is None:
        ng, gin, gout = groups._new_group(name, [(n, t) for n, t, _ in inputs], [output],
                                          tree_type="CompositorNodeTree")
        sub = CompOps(ng, {})
        ins = {s.name: sub.wrap(s, vector=s.type in ("VECTOR", "RGBA")) for s in gin.outputs if s.name}
        sub.feed(gout.inputs[output[0]], sub.wrap(build(sub, ins)))
        ng[owned.BUILT] = groups.code_fingerprint()
        sub.place()
        ng = groups._install(ng, name)
    vals = [m.wrap(v) for _, _, v in inputs]
    node = m.node("CompositorNodeGroup", max(v.col for v in vals) + 1)
    node.node_tree = ng
    for (socket, _, _), v in zip(inputs, vals):
        m.feed(node.inputs[socket], v)
    return m.wrap(node.outputs[output[0]], vector=output[1] == V)


def _interleave_mean_group(m, value, length, taps, edge):
    """``_interleave_mean`` as one compositor group shared by every light (``_shared_group``)."""
    kind = V if value.vector else F
    name = f"{LIGHT_GROUP} Interleave Mean {'-'.join(map(str, taps))} {edge:g}" + (" Vector" if value.vector else "")
    return _shared_group(m, name, [("Value", kind, value), ("Length", F, _first(m, length))],
                         ("Mean", kind), lambda sub, g_: _interleave_mean(sub, g_["Value"], g_["Length"], taps, edge))


def _first(m, value):
    """A scalar image: ``value`` itself, or an image's first channel (a cropped or scaled scalar comes back an
    image)."""
    return m.dot(value, (1.0, 0.0, 0.0)) if value.vector else value


def _interleave_mean(m, value, length, taps, edge):
    """``value`` (an image: a share, or the vector (lit, total, 1) of ``shafts.surface_share``) averaged over
    an interleaving pattern exactly: a separable filter of the weights ``taps`` (SHAFT_TAPS over the 2 x 2
    pattern of ``shafts.offset``: (1, 2, 1) gives each of its 4 ranks a quarter; SURFACE_TAPS over the
    4 x 4 of ``shafts.surface_offset``: (1, 2, 2, 2, 1), a sixteenth each), by pixels shifted with
    Translate nodes.  A neighbour whose ray is more than ``edge`` longer or shorter in log (``length``)
    counts for nothing: no mixing across a silhouette.  A scalar ``value`` comes back a scalar, the mean;
    a vector's third channel carries the weights, so (lit, total) come back as sums over the same pixels.
    ``length``: a scalar image (``_interleave_mean_group`` takes a cropped one's first channel)."""
    log = m.math("LOGARITHM", m.maximum(length, 1e-3), math.e)
    packed = value if value.vector else m.combine(value, 0.0, 1.0)
    half = len(taps) // 2
    for axis in (0, 1):
        total = m.scale(packed, float(taps[half]))
        for k, w in enumerate(taps):
            if k == half:
                continue
            near = [_translated(m, img, (k - half) * (axis == 0), (k - half) * (axis == 1)) for img in (packed, log)]
            same = m.less(m.abs(m.dot(near[1], (1.0, 0.0, 0.0)) - log), edge)
            total = _accumulate(m, total, m.scale(near[0], same * float(w)))
        packed = total
    if value.vector:
        return packed
    return m.dot(packed, (1.0, 0.0, 0.0)) / m.maximum(m.dot(packed, (0.0, 0.0, 1.0)), 1e-6)


def _scaled(m, value, factor):
    """``value`` (an image) at ``factor`` (a number or a Val) times its resolution (Scale, relative, nearest): the
    compositor evaluates what reads it over that many pixels.  A scalar comes back in every channel of an image."""
    node = m.node("CompositorNodeScale", value.col + 1)
    node.inputs["Type"].default_value = "Relative"
    node.inputs["Interpolation"].default_value = "Nearest"
    for axis in ("X", "Y"):   # a size not a multiple of the factor: the edge pixels take the nearest, not zero
        node.inputs[f"Extension {axis}"].default_value = "Extend"
    m.feed(node.inputs["Image"], value if value.vector else m.combine(value, value, value))
    for axis in ("X", "Y"):
        m.feed(node.inputs[axis], m.wrap(factor))
    return m.wrap(node.outputs[0], vector=True)


def _halved(m, scene, position, normal, pixel_x, pixel_y, camera, picture_xy):
    """The bundle's HALF_SHARED inputs for the shafts' shares at half the picture's resolution where its shorter
    side has HALF_FROM pixels or more (a sample every 2 x 2 pixels), at a quarter from QUARTER_FROM (4 x 4; a
    driver reads the render's size, so the choice follows it): never fewer than 72 samples a side.  For the share
    of the fog light a surface gets that the shadows leave (``shafts.surface_share``): the surfaces' ``position``
    and ``normal`` (images over the surfaces' window, whose pixels are ``pixel_x``, ``pixel_y``) at that
    resolution, the interleaving offsets of those samples (``shafts.surface_offset``: its 4 x 4 pattern over 8 x 8
    pixels), the distance from the camera of the sample each pixel of the picture takes, and the Step between
    samples (px: ``_upsampled``).  For the lit share of the glows (``shafts.lit_share``, ``_half_view``): the
    interleaving offsets (``shafts.offset``) of the samples of the picture's pixels ``picture_xy``.

    Why: the shares vary slowly over the picture (a shaft's edge is blurred by the interleaving's mean either way),
    and their map reads are most of a shafted light's cost; at half the resolution a quarter of the pixels take
    them.  A picture two or four times the size of another, sampled so, has its shares from as many samples over
    the same patch of the scene as the smaller one at its full resolution (docs/measurements: no worse than the
    render tests' 128 x 72 against path tracing)."""
    size = "min(rx,ry)*p/100"
    variables = [("rx", scene, "render.resolution_x"), ("ry", scene, "render.resolution_y"),
                 ("p", scene, "render.resolution_percentage")]
    factor = _value(m, "Surface Share Scale", f"1-0.5*min(floor({size}/{HALF_FROM}),1)-0.25*min(floor({size}/"
                                              f"{QUARTER_FROM}),1)", variables)   # 1, 1/2, 1/4 exactly
    pos = _scaled(m, position, factor)
    whole = shafts.surface_offset(m, m.floor(pixel_x * factor), m.floor(pixel_y * factor))   # a sample's, in each
    step = 1.0 / factor
    px, py = picture_xy
    return {HALF + "Position": pos, HALF + "Normal": _scaled(m, normal, factor),
            HALF + "Offset": m.dot(_scaled(m, whole, factor), (1.0, 0.0, 0.0)),
            HALF + "Length": m.dot(_scaled(m, m.length(pos - camera), step), (1.0, 0.0, 0.0)), HALF + "Step": step,
            HALF + "Shaft Offset": shafts.offset(m, m.floor(px * factor), m.floor(py * factor))}


def _coarse_step(m, scene):
    """The step (px) between coarse samples: 1 below HALF_FROM pixels on the picture's shorter side, 2 from it, 4
    from QUARTER_FROM (a driver on the render's size, so a resolution changed later is followed)."""
    size = "min(rx,ry)*p/100"
    variables = [("rx", scene, "render.resolution_x"), ("ry", scene, "render.resolution_y"),
                 ("p", scene, "render.resolution_percentage")]
    return _value(m, "Halo Step", f"1+min(floor({size}/{HALF_FROM}),1)+2*min(floor({size}/{QUARTER_FROM}),1)",
                  variables)


def _half_view(m, per_pixel, step):
    """A shaft group's per-pixel inputs (Direction, Shaft Length, Shaft Offset: images, ``per_pixel``'s of
    HALF_SHAFT) at 1 / ``step`` of their resolution (``_halved``), and the half-resolution ray lengths."""
    half = {k: _scaled(m, per_pixel[k], 1.0 / step) for k in HALF_SHAFT}
    half["Shaft Length"], half["Shaft Offset"] = (_first(m, half[k]) for k in ("Shaft Length", "Shaft Offset"))
    return half, half["Shaft Length"]


def _full_view(m, shares, half_length, length, step):
    """The lit shares (S, S_far) of a shaft group at half resolution (``_half_view``), each its interleaving's mean
    there, back at the picture's resolution by the depth-aware upsampling (``_upsampled``) and its weights."""
    means = [_interleave_mean_group(m, v, half_length, SHAFT_TAPS, SHAFT_EDGE) for v in shares]
    packed = _upsampled_group(m, m.combine(means[0], means[1], 1.0), _first(m, _scaled(m, half_length, step)),
                              length, step)
    weight = m.maximum(m.dot(packed, (0.0, 0.0, 1.0)), 1e-6)
    return [m.dot(packed, axis) / weight for axis in ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0))]


def _upsampled_group(m, value, sample_length, length, step):
    """``_upsampled`` as one compositor group shared by every light (``_shared_group``)."""
    inputs = [("Value", V, value), ("Sample Length", F, sample_length), ("Length", F, length), ("Step", F, step)]
    return _shared_group(m, f"{LIGHT_GROUP} Upsample {UPSAMPLE_EDGE:g}", inputs, ("Value", V),
                         lambda sub, g_: _upsampled(sub, *(g_[k] for k, _, _ in inputs)))


def _upsampled(m, value, sample_length, length, step):
    """``value`` (the sums (lit, total, weight) of a coarse image, ``_halved``) at the picture's resolution,
    ``step`` (px) times its own, depth-aware: a pixel takes its own sample where that sample's distance from the
    camera (``sample_length``) is within UPSAMPLE_EDGE in log of the pixel's own ``length``, else the sum of the
    four next to it (``step`` pixels away) that are.  Its own sample always counts a little (a thousandth), so a
    pixel no sample matches (an object thinner than a sample) takes the nearest one's share.  With ``step`` 1 it is
    ``value``."""
    up = _scaled(m, value, step)
    log = m.math("LOGARITHM", m.maximum(length, 1e-3), math.e)
    log_sample = m.math("LOGARITHM", m.maximum(sample_length, 1e-3), math.e)
    own = m.less(m.abs(log_sample - log), UPSAMPLE_EDGE)
    others = m.wrap((0.0, 0.0, 0.0))
    for dx, dy in ((1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0)):
        near_log = m.dot(_translated(m, log_sample, step * dx, step * dy), (1.0, 0.0, 0.0))
        same = m.less(m.abs(near_log - log), UPSAMPLE_EDGE)
        others = _accumulate(m, others, m.scale(_translated(m, up, step * dx, step * dy), same))
    return m.scale(up, own + 1e-3) + m.scale(others, 1.0 - own)


def _halo(m, coarse, g, models, images, label, position):
    """(group node, {rungs.SURFACE_POINT: glow to the surface, rungs.SKY: to the sky}) of a light's multiply
    scattered halo (``rungs.split_halo``'s second models) per unit intensity, at the coarse resolution of
    ``coarse`` (``_coarse_inputs``): the halo varies over many pixels (it is the field of light scattered more
    than once), so coarse samples hold it, and its quadrature along each ray costs the compositor a sixteenth at
    a quarter of the resolution.  ``_fine`` brings the bundle's sum back."""
    node = m.node("CompositorNodeGroup", 6)
    node.node_tree, node.label = build_glow_group(models, images, None), label
    for socket, _ in GLOW_SHARED:
        m.feed(node.inputs[socket], coarse.get(socket, g[socket]))
    m.feed(node.inputs["Light"], position)
    m.feed(node.inputs["Intensity"], m.wrap((1.0, 1.0, 1.0)))
    return node, {o.at: m.dot(m.wrap(node.outputs[o.compositor], vector=True), (1.0, 0.0, 0.0))
                  for o in GLOW_OUTPUTS}


def _coarse_inputs(m, g, per_pixel):
    """A glow group's per-pixel inputs (``per_pixel``, over the whole picture) at 1 / HALO_STEP of the
    resolution, shared by the bundle's halos."""
    kinds = dict(GLOW_SHARED)
    out = {}
    for socket in per_pixel:
        value = _scaled(m, g[socket], 1.0 / g[HALO_STEP])
        out[socket] = value if kinds[socket] == V else _first(m, value)
    return out


def _fine(m, g, coarse, sums):
    """The bundle's coarse halo sums (RGB images, by rungs.SURFACE_POINT / rungs.SKY) at the picture's
    resolution: the depth-aware upsampling (``_upsampled``) of each, divided by its weights."""
    step = g[HALO_STEP]
    args = (_first(m, _scaled(m, coarse["View Distance"], step)), g["View Distance"], step)
    ones = m.less(-1.0, coarse["View Distance"])   # 1 at every coarse sample (an image, not a folded constant)
    weight = _first(m, _upsampled_group(m, m.combine(ones, ones, ones), *args))
    inverse = 1.0 / m.maximum(weight, 1e-6)
    return {at: m.scale(_upsampled_group(m, v, *args), inverse) for at, v in sums.items()}


def _translated(m, value, dx, dy):
    """``value`` (an image) moved by (dx, dy) whole pixels, numbers or Vals (Translate, nearest); a scalar comes
    back in every channel of an image."""
    node = m.node("CompositorNodeTranslate", value.col + 1)
    node.inputs["Interpolation"].default_value = "Nearest"
    m.feed(node.inputs["Image"], value if value.vector else m.combine(value, value, value))
    m.feed(node.inputs["X"], m.wrap(dx))
    m.feed(node.inputs["Y"], m.wrap(dy))
    return m.wrap(node.outputs[0], vector=True)


def _window(m, scene, label, win):
    """The crop of the window ``win`` (u0, u1, v0, v1: ``footprint.py``) as nodes, ((start, extent, shift) in x,
    the same in y) px: Value nodes driven by ``footprint.START``, ``EXTENT`` and ``SIZE`` of the tree's ID
    property "<WINDOW> <label>" (the window: ``set_windows`` sets it) and of the render's size."""
    key = f"{WINDOW} {label}"
    m.tree[key] = list(win)
    crops = []
    for axis, name in enumerate("xy"):
        variables = [("l", m.tree, f'["{key}"][{2 * axis}]'), ("h", m.tree, f'["{key}"][{2 * axis + 1}]'),
                     ("r", scene, f"render.resolution_{name}"), ("p", scene, "render.resolution_percentage")]
        start, extent, size = (_value(m, f"{key} {part} {name}", expression, variables) for part, expression in
                               (("start", footprint.START), ("extent", footprint.EXTENT), ("size", footprint.SIZE)))
        crops.append((start, extent, start + 0.5 * (extent - size)))
    return crops


def _crop(m, value, window):
    """``value`` (an image) cropped to ``window`` (``_window``): the compositor evaluates what reads it over
    those pixels only."""
    node = m.node("CompositorNodeCrop", value.col + 1)
    m.feed(node.inputs["Image"], value)
    (x, w, _), (y, h, _) = window
    for sock, v in (("X", x), ("Width", w), ("Y", y), ("Height", h)):
        m.feed(node.inputs[sock], v)
    return m.wrap(node.outputs[0], vector=True)


def _uncrop(m, value, window):
    """An image cropped by ``_crop`` moved back to its place in the picture (the compositor centres it)."""
    node = m.node("CompositorNodeTranslate", value.col + 1)
    node.inputs["Interpolation"].default_value = "Nearest"   # whole pixels
    m.feed(node.inputs["Image"], value)
    m.feed(node.inputs["X"], window[0][2])
    m.feed(node.inputs["Y"], window[1][2])
    return m.wrap(node.outputs[0], vector=True)


def _accumulate(m, total, term):
    """total + term, the result on ``total``'s domain (the compositor takes a node's domain from its first
    image input and places the others on it; the hash-consing's sorted operands could swap them)."""
    return m._new_vmath("ADD", total, term)


def aovs(engine):
    """The AOVs (name, kind) the Compositor method reads in ``engine`` (a ``render.engine``)."""
    return EEVEE_AOVS if engine == groups.EEVEE_ENGINE else AOVS


def add_surface_aovs(surface_group, engine="CYCLES"):
    """AOV Output nodes in the Surface group: the compositor's inputs per sample (``aovs(engine)``), the
    normal as (1 + n) / 2 (EEVEE clamps negatives), the Principled inputs as the fog reads them
    (``surface.principled_to_phong`` runs in the compositor)."""
    m = NodeOps(surface_group)
    gin = next(n for n in surface_group.nodes if n.bl_idname == "NodeGroupInput")
    geo = surface_group.nodes.new("ShaderNodeNewGeometry")
    cam = surface_group.nodes.new("ShaderNodeCameraData")
    normal = m.wrap(geo.outputs["Normal"], vector=True)
    values = {"Fog Coverage": m.wrap(1.0), "Fog Position": m.wrap(geo.outputs["Position"], vector=True),
              "Fog Depth": m.wrap(cam.outputs["View Z Depth"]), "Fog Normal": m.scale(normal, 0.5) + (0.5, 0.5, 0.5),
              **{f"Fog {k}": m.wrap(gin.outputs[k], vector=k == "Base Color") for k in PRINCIPLED}}
    for k, (name, kind) in enumerate(aovs(engine)):
        node = owned.add(surface_group, "ShaderNodeOutputAOV", f"{AOV_ROLE} {name}", (4000, -300 - 150 * k))
        node.aov_name = name
        m.feed(node.inputs["Color" if kind == "COLOR" else "Value"], values[name])
    m.place()


def _value(m, label, expression, variables):
    """A Value node driven by ``expression`` (``groups._drive_expression``)."""
    node = m.node("ShaderNodeValue", 0)
    node.label = label
    groups._drive_expression(node.outputs[0], expression, variables)
    return m.wrap(node.outputs[0])


def _vector(m, label, expressions, variables, col=0):
    """A vector whose components are driven by ``expressions`` (one per axis; ``variables`` may be a
    function of the axis)."""
    node = m.node("ShaderNodeCombineXYZ", col)
    node.label = label
    for i, expression in enumerate(expressions):
        groups._drive_expression(node.inputs[i], expression, variables(i) if callable(variables) else variables)
    return m.wrap(node.outputs[0], vector=True)


def horizontal_fit(scene):
    """True if the camera's sensor spans the picture's width (Blender's Auto fit on a landscape picture,
    or Horizontal), False if its height."""
    fit, r = scene.camera.data.sensor_fit, scene.render
    wide = r.resolution_x * r.pixel_aspect_x >= r.resolution_y * r.pixel_aspect_y
    return fit == "HORIZONTAL" or (fit == "AUTO" and wide)


def camera_frame(m, scene):
    """(corner, across, up) of the perspective camera's image plane at unit distance, in world space (m):
    the bottom-left corner's direction and the vectors to the bottom-right and top-left corners (a pixel at
    normalised (u, v) looks along corner + u across + v up), as Blender's ``Camera.view_frame``, driven by
    the camera's matrix, lens, sensor and shift and the render's size (square pixels)."""
    cam = scene.camera
    data = cam.data
    sensor = "sensor_height" if data.sensor_fit == "VERTICAL" else "sensor_width"
    common = [("l", data, "lens"), ("s", data, sensor), ("x", data, "shift_x"), ("y", data, "shift_y"),
              ("rx", scene, "render.resolution_x"), ("ry", scene, "render.resolution_y")]
    # w, h: the frame's width and height at unit distance; the shifts are in units of the fitted side
    w, h = ("s/l", "s*ry/(l*rx)") if horizontal_fit(scene) else ("s*rx/(l*ry)", "s/l")
    axes = lambda i: common + [(n, cam, f"matrix_world[{col}][{i}]") for n, col in (("a", 0), ("b", 1), ("c", 2))]
    corner = f"(x*s/l - {w}/2)*a + (y*s/l - {h}/2)*b - c"
    return [_vector(m, f"Camera {label}", [e] * 3, axes)
            for label, e in (("corner", corner), ("across", f"{w}*a"), ("up", f"{h}*b"))]


def _location(m, label, obj, col=0):
    """``obj``'s world location, driven as the shader groups drive theirs (``groups._drive_location``)."""
    node = m.node("ShaderNodeCombineXYZ", col)
    node.label = label
    groups._drive_location(node, obj)
    return m.wrap(node.outputs[0], vector=True)


def _picture_scale(m, scene, filter_path):
    """(w, h, 0): the picture's size in the filter table's pixels (``pixel.filter_scale``), driven by the
    render's resolution and percentage and the filter's width (``filter_path``: ``pixel_filter``'s; None: 0)."""
    r = [("rx", scene, "render.resolution_x"), ("ry", scene, "render.resolution_y"),
         ("pc", scene, "render.resolution_percentage"), ("fw", scene, filter_path or "cycles.filter_width")]
    k = f"pc/100*{pixel.DEFAULT_FILTER_WIDTH!r}/fw" if filter_path else "0"
    return _vector(m, "Picture Size", [f"rx*{k}", f"ry*{k}", "0"], r)


def _zero(m, image):
    """Black on ``image``'s domain (a sum's first operand: ``_accumulate``)."""
    return m._new_vmath("MULTIPLY", image, (0.0, 0.0, 0.0))


def bundle_name(first, count):
    """The bundle group of the scene's lights ``first`` + 1 .. ``first`` + ``count``."""
    return f"{BUNDLE} {first + 1}-{first + count}"


def build_bundle(scene, first, lights, models, images, peak, windows, shafted=None, layered=False):
    """The compositor group of the scene's lights ``first`` + 1 .. ``first`` + len(lights) (at most
    BUNDLE_SIZE): SHARED in, each light's glow and scatter groups (``build_glow_group``,
    ``build_scatter_group``) with its position, intensity and cone driven by the light
    (``groups._drive_intensity``, ``_drive_spot``), TERMS summed out: Airlight and Background over the
    picture, Scattered over the Surface inputs' window.  ``windows``: each light's glow window
    (``footprint.py``), or None for none (the whole picture): a light with one gets its glow group's
    inputs cropped to it (``_window``).  ``shafted``: (shadow maps by light name, K, g) of the lights whose
    glows are shadowed (``build_shaft_group``), or None.  ``layered``: the glows' origin is per pixel (a fog
    layer's span, ``build_fog_group``)."""
    name = bundle_name(first, len(lights))
    maps, samples, g_ = shafted or ({}, None, 0.0)
    ng, gin, gout = groups._new_group(name, SHARED, TERMS, tree_type="CompositorNodeTree")
    m = CompOps(ng, images)
    g = {s.name: m.wrap(s, vector=s.type in ("VECTOR", "RGBA")) for s in gin.outputs if s.name}
    # what a glow group reads per pixel: cropped to its light's window
    per_pixel = (("Direction", "View Distance", "Glow Length") + (("Incoming", "Pixel") if peak is not None else ())
                 + (("Glow Origin",) if layered else ()))
    # each sum starts black over its domain: the picture for the glows, the surfaces' window for the rest
    sums = {o: _zero(m, g["Direction"] if o in GLOW_OUTPUTS else g[SURFACE + "Position"])
            for o in rungs.COMPOSITOR_OUTPUTS}
    coarse, halos = None, {}   # the halos' coarse inputs and sums (``_halo``)
    for k, (light, mod) in enumerate(zip(lights, models), start=first):
        position = _location(m, f"Light {k} Location", light, col=4)
        intensity = m.node("ShaderNodeCombineXYZ", 4)
        groups._drive_intensity(intensity, light.data)
        built = []   # a term the light's step leaves out (rungs.STEPS) gets no group at all
        # the light's glow window, made only where a glow or a shaft group reads it (a window no group reads
        # would still grow with the frames and mark the windows partial, ``set_windows``)
        has_window = windows is not None and windows[k - first] is not None
        win = (_window(m, scene, k, windows[k - first]) if has_window and (
            light.name in maps or any(o.computed(mod) for o in GLOW_OUTPUTS)) else None)
        crop = lambda socket: _crop(m, g[socket], win) if win else g[socket]
        shaft = None
        if light.name in maps:   # its glows times the lit share, its surfaces' fog light times their visibility
            shaft = m.node("CompositorNodeGroup", 6)
            shaft.node_tree = build_shaft_group(light, maps[light.name], images, samples, g_)
            shaft.label = f"Light {k} Shaft: {light.name}"
            half, half_length = _half_view(m, {s: crop(v) for s, v in HALF_SHAFT.items()}, g[HALF + "Step"])
            for socket, _ in SHAFT_SHARED:
                m.feed(shaft.inputs[socket], half[socket] if socket in SHAFT_PER_PIXEL else g[socket])
            shadow = maps[light.name]
            if shadow.atlas is None:
                source = m.node("CompositorNodeImage", 5)
                source.image = images[shadow.spec.name]
                ng.links.new(source.outputs["Image"], shaft.inputs[SHAFT_MAP])
            else:   # the frame's map, cut from the light's atlas of the animation's
                m.feed(shaft.inputs[SHAFT_MAP], _atlas_tile(m, images[shadow.spec.name], f"Light {k} Shadow"))
            for socket in ("Position", "Normal", "Offset"):   # the surface share at half resolution
                m.feed(shaft.inputs["Surface " + socket], g[HALF + socket])
            m.feed(shaft.inputs["Light"], position)
            near, far = _full_view(m, [m.wrap(shaft.outputs[s]) for s in ("Share", "Share Far")], half_length,
                                   _first(m, crop("Shaft Length")), g[HALF + "Step"])
            share = {o: near if o.at == rungs.SURFACE_POINT else far for o in GLOW_OUTPUTS}
        split = rungs.split_halo(mod)
        halo = None
        if split is not None:   # the multiply scattered halo at a coarser resolution (not shadowed by the shafts)
            coarse = coarse or _coarse_inputs(m, g, per_pixel)
            halo = _halo(m, coarse, g, split[1], images, f"Light {k} Halo: {light.name}", position)
            for at, v in halo[1].items():
                lit = m.scale(m.wrap(intensity.outputs[0], vector=True), v)
                halos[at] = lit if halos.get(at) is None else _accumulate(m, halos[at], lit)
        if any(o.computed(mod) for o in GLOW_OUTPUTS):
            glow = m.node("CompositorNodeGroup", 6)
            glow.node_tree = build_glow_group(mod if split is None else split[0], images, peak)
            glow.label = f"Light {k}: {light.name}"
            for socket, _ in GLOW_SHARED:
                m.feed(glow.inputs[socket], crop(socket) if socket in per_pixel else g[socket])
            for o in GLOW_OUTPUTS:
                v = m.wrap(glow.outputs[o.compositor], vector=True)
                if shaft is not None:
                    v = m.scale(v, share[o])
                sums[o] = _accumulate(m, sums[o], v if win is None else _uncrop(m, v, win))
            built.append(glow)
        if any(o.computed(mod) for o in SCATTER_OUTPUTS):
            if shaft is not None:   # its directions interleave as the glow's nodes do (``shafts.surface_share``)
                parts = _interleave_mean_group(m, m.wrap(shaft.outputs["Visible"], vector=True),
                                               m.length(g[HALF + "Position"] - g["Camera"]), SURFACE_TAPS,
                                               SURFACE_EDGE)
                parts = _upsampled_group(m, parts, g[HALF + "Length"], m.length(g[SURFACE + "Position"] - g["Camera"]),
                                         g[HALF + "Step"])
                visible = shafts.share_of(m.dot(parts, (1.0, 0.0, 0.0)), m.dot(parts, (0.0, 1.0, 0.0)))
            scatter = m.node("CompositorNodeGroup", 6)
            scatter.node_tree = build_scatter_group(mod, images)
            scatter.label = f"Light {k} Scatter: {light.name}"
            for socket, _ in SURFACE_SHARED:
                m.feed(scatter.inputs[socket], g[socket if socket not in SURFACE_IMAGES else SURFACE + socket])
            for o in SCATTER_OUTPUTS:
                v = m.wrap(scatter.outputs[o.compositor], vector=True)
                if shaft is not None:
                    v = m.scale(v, visible)
                sums[o] = _accumulate(m, sums[o], v)
            built.append(scatter)
        for node in built:
            m.feed(node.inputs["Light"], position)
            ng.links.new(intensity.outputs[0], node.inputs["Intensity"])
        if built and groups.SPOT_ROWS[0] in built[0].inputs:   # the cone's drivers once, for both groups
            groups._drive_spot(ng, k, light, built[0])
            for node in built[1:] + ([halo[0]] if halo is not None else []):
                for socket, _ in groups._spot_inputs(mod):
                    ng.links.new(built[0].inputs[socket].links[0].from_socket, node.inputs[socket])
        if shaft is not None and groups.SPOT_ROWS[0] in shaft.inputs:   # a moving spot's shafts: its cone now
            if built and groups.SPOT_ROWS[0] in built[0].inputs:
                for socket in (*groups.SPOT_ROWS, groups.SPOT_COS, groups.SPOT_BLEND):
                    ng.links.new(built[0].inputs[socket].links[0].from_socket, shaft.inputs[socket])
            else:
                groups._drive_spot(ng, k, light, shaft)
    if halos:
        fine = _fine(m, g, coarse, halos)
        for o in GLOW_OUTPUTS:
            sums[o] = _accumulate(m, sums[o], fine[o.at])
    for o, v in sums.items():
        m.feed(gout.inputs[o.compositor], v)
    m.place()
    return groups._install(ng, name)


PARTIAL = "Fog Windows Partial"   # on the fog group: its windows were grown by single frames (or built full)
#                                    since they were last computed over an animation's range


def windows_partial():
    """True if the windows should be computed over the range again before the file is saved (``PARTIAL``)."""
    ng = bpy.data.node_groups.get(FOG_GROUP)
    return bool(ng is not None and ng.get(PARTIAL))


def set_windows(lights, windows, grow=False):
    """Set the windows (``footprint.py``) the fog's compositor groups crop to: ``windows`` = (the surfaces'
    window, [each light's glow window or None]), ``lights`` in the order of ``build_fog_group``'s; ``grow``:
    each the union of the one it had and the new one.  Only values change: a light built without a window
    keeps none (the whole picture)."""
    surface_window, glows = windows
    fog = bpy.data.node_groups.get(FOG_GROUP)
    changed = _set(fog, "Surface", surface_window, grow)
    for first in range(0, len(lights), BUNDLE_SIZE):
        bundle = bpy.data.node_groups.get(bundle_name(first, min(BUNDLE_SIZE, len(lights) - first)))
        for k, win in enumerate(glows[first:first + BUNDLE_SIZE], start=first):
            if win is not None:
                changed = _set(bundle, k, win, grow) or changed
    if fog is not None and (not grow or changed) and bool(fog.get(PARTIAL)) != grow:
        fog[PARTIAL] = grow


def _set(ng, label, win, grow):
    """Set the window "<WINDOW> <label>" of ``ng`` (the union with the one it has if ``grow``); True if it changed."""
    key = f"{WINDOW} {label}"
    if ng is None or key not in ng:
        return False
    if grow:
        win = footprint.union(tuple(ng[key]), win)
    if tuple(ng[key]) == tuple(win):   # no needless update of the tree
        return False
    ng[key] = list(win)
    return True


def _params(m):
    """(beta 1/m, albedo) of the params group, driven (a density or colour change needs no rebuild)."""
    params = bpy.data.node_groups[groups.PARAMS]
    beta = _value(m, "Beta", "b", [("b", params, 'nodes["Beta"].outputs[0].default_value')])
    albedo = _vector(m, "Albedo", ["a"] * 3,
                     lambda i: [("a", params, f'nodes["Albedo"].outputs[0].default_value[{i}]')])
    return beta, albedo


EMITTERS = "Emission"   # the fog group's input of the emitters' light: the Render Layers' Emission pass


def emitter_pixel_angle(scene):
    """rad a pixel at the picture's centre (the emitters' glow kernels are baked for it)."""
    from .. import view
    left, right, _, _ = view.frame_extent(scene, scene.camera)
    return math.atan(float(right - left) / max(view.render_size(scene)[0], 1))


def emitter_table(g, pixel_angle, multiple_albedo=None):
    """{name: image} of the emitters' glow weights for anisotropy ``g``, ``pixel_angle`` and Dense Fog's albedo
    (baked once, cached)."""
    spec, facing = emitter_glow.table_spec(g, pixel_angle, multiple_albedo), emitter_glow.facing_spec(g)
    return {spec.name: images_.table_image(spec, functools.partial(emitter_glow.bake_table, g, pixel_angle,
                                                                   multiple_albedo)),
            facing.name: images_.table_image(facing, functools.partial(emitter_glow.bake_facing, g))}


def _emitter_glow(m, p, beta, d_vp, g, pixel_angle, multiple_albedo=None, cover=None, facing=None, lean=None):
    """The glows of the glowing objects the camera sees (``precompute/emitter_glow.py``): the Emission pass made
    undimmed (times e^{beta D_vp}) and weighted by its glow's total weight N(T) (``emitter_glow.source_weight``)
    and, with ``facing`` (the |cos| of each pixel's surface to the camera), taken as the two-sided Lambertian
    source its surface is (``emitter_glow.facing_factor``: a flat sign sends less light sideways than towards the
    camera); then weighted per pixel by each rung's share a_j(T) / N(T), blurred by each Blur node of the ladder
    and summed (per unit albedo).  Each rung's glow stops at the surfaces in front of its sources
    (``emitter_glow.segment_share`` at the rung's angle, the sources' optical depth taken as the mean over what the
    rung blurs in: a second blur of the weights times T); where the pixel sees the sky (``cover`` 0) or a glowing
    surface it is whole.  With ``lean`` (the picture's unit direction (x, y, 0) of each pixel's normal, taken facing
    the camera) a flat emitter glows more on the side its normal leans to: each rung from DIPOLE_MIN_SIZE up adds
    the cos(phi) term of ``emitter_glow.facing_dipole``, -(sigma^2 / rho) div(B * (D / c) L u) (``dipole_scale``;
    the gradient by +-1 px differences; grey, in the glow's colour where it lands)."""
    spec = emitter_glow.table_spec(g, pixel_angle, multiple_albedo)
    t = beta * d_vp
    x = emitter_glow.table_x(m, t)
    light = m.scale(p[EMITTERS], emitter_glow.source_weight(m, spec, t))
    leaning = None
    if facing is not None and multiple_albedo is None:   # (Dense Fog's kernel keeps the isotropic sources)
        c = m.clamp(facing)
        if lean is not None:
            dipole = emitter_glow.facing_factor(m, facing, m.table(emitter_glow.facing_spec(g), c, 1.0))
            leaning = m.scale(lean, m.dot(light, (1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0)) * dipole)
        light = m.scale(light, emitter_glow.facing_factor(m, facing, m.table(emitter_glow.facing_spec(g), c, 0.0)))
    grey = m.dot(light, (1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0))
    t_surface = t if cover is None else m.select(m.less(1e-3, cover), t, 1.0e6)
    # a glowing pixel's own surface is no surface in front of the glow: it takes the whole of it (the light its
    # neighbours send through the fog towards it, single and multiply scattered, lies in front of it)
    glowing = m.less(1e-30, m.dot(p[EMITTERS], (1.0, 1.0, 1.0)))
    t_surface = m.select(glowing, 1.0e6, t_surface)
    total = None
    for j, size in enumerate(emitter_glow.SIZES):
        a = emitter_glow.rung_share(m, spec, x, j)
        sources = [m.scale(light, a), m.combine(grey * a * t, grey * a, 0.0)]
        dipole = leaning is not None and size >= emitter_glow.DIPOLE_MIN_SIZE
        if dipole:
            sources.append(m.scale(leaning, a))
        blurred = []
        for source in sources:
            blur = m.node("CompositorNodeBlur", 5)
            blur.inputs["Size"].default_value = (float(size), float(size))
            blur.inputs["Extend Bounds"].default_value = True   # off, Blender extends the picture's edge pixels
            m.feed(blur.inputs["Image"], source)                # outwards: a sign cut by the frame glows on
            blurred.append(m.wrap(blur.outputs["Image"], vector=True))
        glow, moments = blurred[:2]
        if dipole:   # -(sigma^2 / rho) (d/dx of the x channel + d/dy of the y channel), in the glow's colour
            dx = m.dot(_translated(m, blurred[2], -1.0, 0.0) - _translated(m, blurred[2], 1.0, 0.0), (1.0, 0.0, 0.0))
            dy = m.dot(_translated(m, blurred[2], 0.0, -1.0) - _translated(m, blurred[2], 0.0, 1.0), (0.0, 1.0, 0.0))
            lean_grey = (dx + dy) * (-0.5 * emitter_glow.dipole_scale(size))
            glow_grey = m.dot(glow, (1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0))
            glow = glow + m.scale(glow, lean_grey / m.maximum(glow_grey, 1e-30))
        t_source = m.dot(moments, (1.0, 0.0, 0.0)) / m.maximum(m.dot(moments, (0.0, 1.0, 0.0)), 1e-30)
        share = emitter_glow.segment_share(m, t_surface, t_source, emitter_glow.rung_angle(size, pixel_angle))
        v = m.scale(glow, share)
        total = v if total is None else _accumulate(m, total, v)
    return total


def _daylight(m, day, table, camera, direction, position, normal, reflectance, d_vp, t_vp, cover, sun_share=None,
              surface_share=None):
    """The sun's and the sky's light in a fog layer at a pixel (albedos included): ``groups.daylight_light`` where the
    pixel sees a surface, the glow to the sky (``sunlight.ray_glow``) where it does not.  With air the glow is
    evaluated once, to the surface where it covers most of the pixel and to the sky elsewhere (without the glow's
    table its kernel is the costliest part of the picture: a pixel on a silhouette takes one side's glow).
    ``sun_share``, ``surface_share``: the lit shares of the layer's sun glow and of the sun's part of the fog light on
    the pixel's surface (``_sun_shares``), or None."""
    if day.air is None:
        to_surface = groups.daylight_light(m, day, table, camera, direction, position, normal, reflectance, d_vp,
                                           t_vp, sun_share, surface_share)
        to_sky = sunlight.ray_glow(m, day, camera, direction, model.FAR, sun_share)
        return m.scale(to_surface, cover) + m.scale(to_sky, 1.0 - cover)
    surface = m.less(0.5, cover)
    glow = sunlight.ray_glow(m, day, camera, direction, m.select(surface, d_vp, model.FAR), sun_share)
    reflected = sunlight.times(m, reflectance * sunlight.fog_light(m, table, day, position, normal, surface_share),
                               t_vp)
    return glow + m.scale(reflected, cover)


class Day(NamedTuple):
    """``build_fog_group``'s ``day``: what the compositor takes of a fog layer's daylight."""
    build: Any             # ``build_surface``'s ``day``: (m, beta, albedo) -> ``sunlight.Daylight`` in the tree
    table: Any             # the fog light's TableSpec (``sunsky.fog_light_table``)
    dims: bool             # whether surfaces take the sun's and the sky's dimming (``sunsky.dims_surfaces``)
    sun_shadow: Any = None   # the sun's map (``shadow_maps.SunShadow``), or None: no shafts from the sun
    sun_nodes: int = 0       # the sun's lit share's nodes a pixel (``shafts.Samples.view_nodes``)


SUN_SHAFT_NODE = f"{SHAFT_GROUP} Sun Node"   # one group per quadrature node of the sun's lit share


def _sun_shares(m, sun_shadow, nodes, day, camera, direction, layer, length, beta, point, normal, offsets,
                shaft_length):
    """(the lit share of the layer's sun glow at a pixel, the lit share of the sun's part of the fog light on its
    surface) from the sun's map ``sun_shadow`` (``shadow_maps.SunShadow``).  The glow's (``shafts.sun_lit_share``)
    over the part of the pixel's ray in the layer (``sunlight.lamp_glow_span`` below its lamps' glow top), to the
    pixel's surface or, past ``length``, the sky, at most SUN_REACH mean free paths, ``nodes`` a pixel interleaved
    over 2 x 2 pixels; the surface's (``shafts.sun_surface_share``) interleaved over 4 x 4 (``offsets``: the pixel's
    ``shafts.offset`` and ``surface_offset``).  Each is averaged over its pattern depth-aware (``_interleave_mean``,
    by ``shaft_length``)."""
    spec, frame = sun_shadow
    top_z = sunlight.lamp_glow_top(*layer)
    t0, t1 = sunlight.lamp_glow_span(m, top_z, camera, direction)
    meets = m.less(t0, LAYER_OPEN)
    start = m.minimum(t0, LAYER_OPEN)
    span = m.maximum(m.minimum(m.minimum(t1, length) - start, shafts.SUN_REACH / m.maximum(beta, 1e-9)), 0.0)
    rate = shafts.sun_attenuation_rate(m, beta, m.dot(direction, (0.0, 0.0, 1.0)), sunlight.sun_elevation(m, day))
    name = f"{SUN_SHAFT_NODE} {hashlib.sha1(repr((spec, tuple(frame))).encode()).hexdigest()[:12]}"
    lit = shafts.sun_lit_share(m, spec, frame, camera + m.scale(direction, start), direction, span, rate, nodes,
                               offsets[0], name=name)
    share = _interleave_mean_group(m, m.select(meets, lit, 1.0), shaft_length, SHAFT_TAPS, SHAFT_EDGE)
    lit, total = shafts.sun_surface_share(m, spec, frame, point, normal, camera, beta, day.sun, float(day.g), top_z,
                                          float(layer[2]), offsets[1], name=name)
    parts = _interleave_mean_group(m, m.combine(lit, total, 1.0), shaft_length, SURFACE_TAPS, SURFACE_EDGE)
    return share, shafts.share_of(m.dot(parts, (1.0, 0.0, 0.0)), m.dot(parts, (0.0, 1.0, 0.0)))


def build_fog_group(scene, lights, models, images, windows=None, partial=False, shafted=None, emitters=None,
                    day=None, layer=None):
    """(Re)build the compositor group ``FOG_GROUP``: Image (the render) and the AOVs in; Image (the render
    plus the fog's light) and Fog Light out.  ``lights``: the fog's lights, ``models``: each light's
    rungs.LightModels; ``windows``: (the surfaces' window, [each light's glow window or None]) of
    ``footprint.py`` (``view.windows``), or None to evaluate every term over the whole picture; ``partial``:
    they do not hold the animation's range (``PARTIAL``); ``shafted``: ``build_bundle``'s; ``emitters``: (the fog's
    g, Dense Fog's albedo or None) if glowing objects get their glows (``_emitter_glow``: an Emission input), else
    None; ``day``: a ``Day`` for a fog layer with a sun or a sky
    (``_daylight``; the render's surfaces take the sun's and the sky's dimming here, once per pixel, and the sky seen
    its transmittance), else None; ``layer``: a fog layer's (top, falloff, ground) in units (``FogSpec.layer_per_unit``),
    where the lights' glows end (``sunlight.lamp_glow_span``), or None for fog that fills all space.  Rebuilt in
    place, so the
    scene's compositor keeps its group node.  Returns the table images it reads (``images`` and the pixel
    filter's and the emitters' weights)."""
    filt, peak = pixel_filter(scene), None
    if filt is not None:
        peak, baker = pixel.filter_table(filt[0])
        images = dict(images, **{peak.name: images_.table_image(peak, baker)})
    if emitters is not None:
        images = dict(images, **emitter_table(*emitters[:1], emitter_pixel_angle(scene), emitters[1]))
    eevee = scene.render.engine == groups.EEVEE_ENGINE
    inputs = ((("Image", "COLOR"),) + aovs(scene.render.engine) + (((compositor.DEPTH, "VALUE"),) if eevee else ())
              + (((EMITTERS, "COLOR"),) if emitters is not None else ()))
    ng = bpy.data.node_groups.get(FOG_GROUP)
    if ng is None:
        ng = bpy.data.node_groups.new(FOG_GROUP, "CompositorNodeTree")
        ng[groups.FOG_PROP] = True
    have = [(i.name, i.in_out) for i in ng.interface.items_tree if i.item_type == "SOCKET"]
    if ([s for s in have if s[1] == "INPUT"] != [(n, "INPUT") for n, _ in inputs]   # (Blender lists outputs first)
            or [s for s in have if s[1] == "OUTPUT"] != [("Image", "OUTPUT"), ("Fog Light", "OUTPUT")]):
        # new, or another engine's: its group nodes lose their links, and the chain links them anew
        ng.interface.clear()
        for name, kind in inputs:
            ng.interface.new_socket(name, in_out="INPUT", socket_type=C if kind == "COLOR" else F)
        for name in ("Image", "Fog Light"):
            ng.interface.new_socket(name, in_out="OUTPUT", socket_type=C)
    ng.animation_data_clear()
    ng.nodes.clear()
    gin, gout = ng.nodes.new("NodeGroupInput"), ng.nodes.new("NodeGroupOutput")
    gout.location = (6000, 0)
    m = CompOps(ng, images)
    p = {s.name: m.wrap(s, vector=s.type == "RGBA") for s in gin.outputs if s.name}
    cover = p["Fog Coverage"]
    inv = 1.0 / m.maximum(cover, 1e-6)
    cam = _location(m, "Camera", scene.camera)
    beta, albedo = _params(m)
    coords = m.node("CompositorNodeImageCoordinates", 0)
    ng.links.new(gin.outputs["Image"], coords.inputs[0])
    uv = m.wrap(coords.outputs["Normalized"], vector=True)
    corner, across, up = camera_frame(m, scene)
    ray = corner + m.scale(across, m.dot(uv, (1.0, 0.0, 0.0))) + m.scale(up, m.dot(uv, (0.0, 1.0, 0.0)))
    direction = m.scale(ray, 1.0 / m.length(ray))
    if eevee:   # ray is the pixel's ray at unit view depth
        mean_depth, depth = p["Fog Depth"] * inv, p[compositor.DEPTH]
        agree = m.less(m.abs(depth - mean_depth), DEPTH_AGREE * mean_depth)
        pos = cam + m.scale(ray, m.select(agree, depth, mean_depth))
    else:
        pos = m.scale(p["Fog Position"], inv)
    to_cam = cam - pos
    d_vp = m.length(to_cam)
    incoming = m.scale(to_cam, 1.0 / m.maximum(d_vp, 1e-9))
    summed = m.scale(p["Fog Normal"], 2.0) - m.scale(m.wrap((1.0, 1.0, 1.0)), cover)   # written as (1 + n) / 2
    normal = m.scale(summed, 1.0 / m.maximum(m.length(summed), 1e-9))
    size = _picture_scale(m, scene, filt and filt[1])
    pix = uv * size if peak is not None else m.wrap((0.0, 0.0, 0.0))
    diffuse, specular, level = surface.principled_to_phong(
        m, m.scale(p["Fog Base Color"], inv), p["Fog Metallic"] * inv, p["Fog Roughness"] * inv,
        p["Fog Specular IOR Level"] * inv, m.dot(incoming, normal))
    shared = {"Beta": beta, "Camera": cam, "Incoming": incoming, "View Distance": d_vp, "Direction": direction,
              "Pixel": pix, "Corner": corner, "Across": across, "Up": up, "Size": size, "Glow Origin": cam,
              "Glow Length": d_vp}
    if layer is not None:   # the lights' glows over the part of the ray in the layer: from where it enters, to where it
        # leaves or meets the surface; a pixel that sees mostly sky takes the sky's (one evaluation a pixel)
        t0, t1 = sunlight.lamp_glow_span(m, sunlight.lamp_glow_top(*layer), cam, direction)
        bounded, meets = m.less(t1, LAYER_OPEN), m.less(t0, LAYER_OPEN)
        shared["Glow Origin"] = cam + m.scale(direction, m.minimum(t0, LAYER_OPEN))
        to_surface = m.maximum(m.minimum(t1, d_vp) - t0, 0.0)
        shared["Glow Length"] = m.select(m.less(0.5, cover), to_surface, m.select(bounded, t1 - t0, model.FAR))
    surface_in = {"Position": pos, "Incoming": incoming, "Normal": normal, "Diffuse": diffuse, "Specular": specular,
                  "Level": level}
    pixel_xy = m.wrap(coords.outputs["Pixel"], vector=True)
    px, py = m.dot(pixel_xy, (1.0, 0.0, 0.0)), m.dot(pixel_xy, (0.0, 1.0, 0.0))
    surface_offset = surface_in["Offset"] = shafts.surface_offset(m, px, py)
    win = None if windows is None else _window(m, scene, "Surface", windows[0])
    if win is not None:   # the fog light on surfaces: only where the picture has surfaces
        surface_in = {k: _crop(m, v, win) for k, v in surface_in.items()}
    shared.update({SURFACE + k: v for k, v in surface_in.items()})
    if shafted:   # the surface share at a coarser resolution
        xy = (px, py) if win is None else (m.dot(_crop(m, pixel_xy, win), axis) for axis in ((1.0, 0.0, 0.0),
                                                                                              (0.0, 1.0, 0.0)))
        shared.update(_halved(m, scene, shared[SURFACE + "Position"], shared[SURFACE + "Normal"], *xy, cam,
                              (px, py)))
    shared[HALO_STEP] = (_coarse_step(m, scene) if any(rungs.split_halo(mod) is not None for mod in models)
                         else m.wrap(1.0))
    shared["Shaft Length"] = m.select(m.less(1e-3, cover), d_vp, SKY_LENGTH)
    shared["Shaft Offset"] = shafts.offset(m, px, py)
    sums = {}   # Output -> the sum over the bundles
    for first in range(0, len(lights), BUNDLE_SIZE):
        node = m.node("CompositorNodeGroup", 5)
        node.node_tree = build_bundle(scene, first, lights[first:first + BUNDLE_SIZE],
                                      models[first:first + BUNDLE_SIZE], images, peak,
                                      None if windows is None else windows[1][first:first + BUNDLE_SIZE], shafted,
                                      layered=layer is not None)
        for name, v in shared.items():
            m.feed(node.inputs[name], v)
        for o in rungs.COMPOSITOR_OUTPUTS:
            v = m.wrap(node.outputs[o.compositor], vector=True)
            sums[o] = v if o not in sums else _accumulate(m, sums[o], v)
    if win is not None:   # the sums over the surfaces' window back in place, on the picture's domain
        sums.update({o: _accumulate(m, _zero(m, direction), _uncrop(m, sums[o], win))
                     for o in SCATTER_OUTPUTS if o in sums})
    if layer is not None and rungs.BACKGROUND_OUT in sums:   # a ray that leaves the layer: its glow ends at the top
        sky = sums[rungs.BACKGROUND_OUT]
        if rungs.AIRLIGHT_OUT in sums:
            sky = m.scale(sums[rungs.AIRLIGHT_OUT], bounded) + m.scale(sky, 1.0 - bounded)
        sums[rungs.BACKGROUND_OUT] = m.scale(sky, meets)
    daylight = None if day is None else day.build(m, beta, albedo)
    t_day = None if daylight is None else sunlight.view_transmittance(m, daylight, pos, incoming, d_vp)
    t_vp = model.transmittance(m, beta, d_vp) if daylight is None else sunlight.grey(m, t_day)
    if not sums:
        fog = m.wrap((0.0, 0.0, 0.0))
    else:   # Eq. 19 where the pixel sees its surface, Eq. 12 where it sees the sky
        fog = albedo * shading.pixel_light(m, sums, t_vp, cover)
    if daylight is not None:
        sun_share = surface_share = None
        if day.sun_shadow is not None and layer is not None:   # the sun's shafts
            sun_share, surface_share = _sun_shares(m, day.sun_shadow, day.sun_nodes, daylight, cam, direction, layer,
                                                   m.select(m.less(0.5, cover), d_vp, model.FAR), beta, pos, normal,
                                                   (shared["Shaft Offset"], surface_offset), shared["Shaft Length"])
        fog = fog + _daylight(m, daylight, day.table, cam, direction, pos, normal, diffuse + specular, d_vp, t_day,
                              cover, sun_share, surface_share)
    if emitters is not None:
        facing_normal = m.scale(normal, m.select(m.less(m.dot(normal, incoming), 0.0), -1.0, 1.0))
        image_x, image_y = (m.scale(v, 1.0 / m.length(v)) for v in (across, up))
        lean = m.combine(m.dot(facing_normal, image_x), m.dot(facing_normal, image_y), 0.0)
        lean = m.scale(lean, 1.0 / m.maximum(m.length(lean), 1e-6))
        fog = fog + albedo * _emitter_glow(m, p, beta, d_vp, emitters[0], emitter_pixel_angle(scene), emitters[1],
                                           cover, m.abs(m.dot(normal, incoming)), lean)
    image = p["Image"]
    if daylight is not None:   # the dimming of the pixel's surface by the fog above it and of the sky seen through
        one = 1.0 if daylight.air is None else m.wrap((1.0, 1.0, 1.0))   # (with air the dimming is RGB)
        sun_visible = (None if sun_share is None else   # the sun's map: a surface in its shadow takes the sky's factor
                       shafts.sun_surface_lit(m, day.sun_shadow.spec, day.sun_shadow.frame, pos, normal))
        dims = (m.select(m.less(0.0, cover), sunlight.direct_dimming(m, daylight, pos, normal, sun_visible), one)
                if day.dims else m.const(1.0))   # the layer's
        seen = sunlight.sky_seen(m, daylight, cam, direction)
        # the materials dimmed their samples by a grey stand-in (``sunlight.proxy_transmittance``): the camera
        # segment's exact transmittance (with air its colour) comes here, per pixel
        inv = 1.0 / m.maximum(sunlight.proxy_transmittance(m, daylight, d_vp), 1e-30)
        tint = t_day * inv if daylight.air is None else m.scale(t_day, inv)
        if daylight.air is None:
            image = m.scale(image, cover * (tint * dims) + (1.0 - cover) * seen)
        else:
            image = image * (m.scale(sunlight.times(m, tint, dims), cover) + m.scale(seen, 1.0 - cover))
    m.feed(gout.inputs["Fog Light"], fog)
    m.place()
    m.feed(gout.inputs["Image"], fog + image)
    ng[PARTIAL] = partial
    ng[owned.BUILT] = groups.code_fingerprint()
    return images
