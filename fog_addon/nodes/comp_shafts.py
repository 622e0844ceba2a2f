"""Light shafts in the compositor: a shafted light's lit shares from its shadow map (``build_shaft_group``; an
animation's map cut from its atlas, ``atlas_tile``), their means over the interleaving patterns
(``interleave_mean_group``), and the shares evaluated at a coarser resolution and brought back by a depth-aware
upsampling (``halved``, ``half_view``, ``full_view``, ``upsampled_group``)."""
import dataclasses
import hashlib
import math

from ..precompute.physics.area import area
from ..precompute.physics.shafts import shaft_maps, shafts
from ..precompute.physics.spot import spot as spot_
from . import comp_ops, groups, light_groups, owned
from .comp_lights import LIGHT_GROUP, SURFACE
from .comp_ops import CompOps
from .groups import C, F, V

# what a light's shaft group reads (``build_shaft_group``): the ray's length to its surface (or far beyond the
# world where the pixel sees only the sky)
SHAFT_SHARED = (("Beta", F), ("Camera", V), ("Direction", V), ("Shaft Length", F), ("Shaft Offset", F))
SHAFT_PER_PIXEL = ("Direction", "Shaft Length", "Shaft Offset")
SHAFT_TAPS = (1, 2, 1)   # the separable filter that averages the 2 x 2 interleaved shares (``_interleave_mean``)
SHAFT_EDGE = 0.05     # its threshold on log distance: neighbours 5 % nearer or farther are not mixed
SKY_LENGTH = 1.0e6   # m: a ray to the sky's length for the shafts (its far nodes weigh e^{-beta t})
SHAFT_GROUP = f"{LIGHT_GROUP} Shaft"      # a spot's "<SHAFT_GROUP> <light name>", point lights' shared
SHAFT_MAP = "Map"   # a shaft group's input: the light's shadow map (``build_shaft_group``)
SURFACE_OFFSET = SURFACE + "Offset"   # a surface's interleaving offset (``shafts.surface_offset``)
# the filter over the 4 x 4 interleaved surface shares (``shafts.surface_offset``): (1, 2, 2, 2, 1)
SURFACE_TAPS = (1,) + (2,) * (2 ** shafts.SURFACE_PATTERN_LEVELS - 1) + (1,)
SURFACE_EDGE = 0.3    # its threshold on log distance (a floor seen at a grazing angle changes faster than 5 % a row)
HALF = "Half "   # a bundle's inputs for the surface share at a coarser resolution (``halved``)
HALF_SHARED = ((HALF + "Position", V), (HALF + "Normal", V), (HALF + "Offset", F), (HALF + "Length", F),
               (HALF + "Step", F), (HALF + "Shaft Offset", F))
HALF_SHAFT = {"Direction": "Direction", "Shaft Length": "Shaft Length", "Shaft Offset": HALF + "Shaft Offset"}
#             a shaft group's per-pixel inputs at half resolution: from these bundle inputs (``half_view``)
HALF_FROM = 144   # px: a picture whose shorter side has this many pixels or more takes the shafts' shares at half
#                   its resolution (``halved``: twice the render tests' 72, whose pattern it then matches in the scene)
QUARTER_FROM = 2 * HALF_FROM   # px: from this many, at a quarter (never coarser: 72 samples or more a side)
UPSAMPLE_EDGE = 0.1   # ``_upsampled``'s threshold on log distance: a coarse sample of another surface is not taken


def is_area(light):
    """True for an area light: its shafts take a point light's map from its centre and weigh its fog by Lambert's
    cosine about its normal (``area.shaft_falloff``)."""
    return light.data.type == "AREA"


def shaft_group_name(light, shadow, samples, g):
    """The shaft group of ``light``: one for every point light of the same map size, samples and g (their maps
    differ only in what the group's Map input reads), one per spot (its frame and cone are built in; a moving
    spot's map frame, its cone being inputs) and per area light (its normal an input)."""
    if shadow.spot is not None or shadow.cone or is_area(light):
        return f"{SHAFT_GROUP} {light.name}"
    return (f"{SHAFT_GROUP} Point {shadow.spec.width}x{shadow.spec.height} g {g:.6g} "
            f"K {samples.view_nodes} {samples.surface_directions}x{samples.surface_nodes}")


def build_shaft_group(light, shadow, images, samples, g):
    """``light``'s lit share of its glow along the pixel's ray (compositor group: Share, ``shafts.lit_share``)
    from its shadow map ``shadow`` (``shadow_maps.ShadowMap``), and the share of the fog light the pixel's
    surface reflects that the shadows leave (Visible, ``shafts.surface_share``).
    ``samples``: ``shafts.Samples`` (the Quality's); ``g``: the Henyey-Greenstein anisotropy.  The spot's frame
    and cone are the map's (baked at its pose); a moving spot's (``shadow.cone``) cone is the group's spot inputs
    (``light_groups.spot_inputs``, fed by its glow's drivers in the bundle) and its map's frame the one of all its
    poses.  The map is the group's Map input (its Image node is the bundle's, an animation's map cut from its atlas
    there: ``atlas_tile``), so point lights share one group (``shaft_group_name``), built once."""
    name = shaft_group_name(light, shadow, samples, g)
    emitter = is_area(light)   # an area light
    if shadow.spot is None and not shadow.cone and not emitter and (ng := groups.up_to_date(name)) is not None:
        return ng
    cone = ([(n, V) for n in light_groups.SPOT_ROWS] + [(light_groups.SPOT_COS, F), (light_groups.SPOT_BLEND, F)]
            if shadow.cone else [(n, V) for n in light_groups.SPOT_ROWS] if emitter else [])
    ng, gin, gout = groups.new_group(name, [*SHAFT_SHARED, ("Light", V), ("Surface Position", V),
                                            ("Surface Normal", V), ("Surface Offset", F), (SHAFT_MAP, C), *cone],
                                     [("Share", F), ("Share Far", F), ("Visible", V)],
                                     tree_type="CompositorNodeTree")
    falloff, clip, kind = None, None, f"point {shadow.spec.width}x{shadow.spec.height}"
    if shadow.cone:   # the cone of the light's pose at the frame (in its space: ``spot_.light_space``)
        kind = f"moving {shadow.spec.width}x{shadow.spec.height} " + hashlib.sha1(
            repr(shadow.spot).encode()).hexdigest()[:12]
    elif shadow.spot is not None:
        falloff, key = still_spot_falloff(light, shadow.spot)
        clip = still_spot_clip(light, shadow.spot)
        kind = "spot " + hashlib.sha1(repr((shadow.spec.width, *key)).encode()).hexdigest()[:12]
    spec = dataclasses.replace(shadow.spec, name=f"{SHAFT_MAP} {kind}")   # read from the Map input
    m = CompOps(ng, dict(images))
    m.images[spec.name] = m.wrap(gin.outputs[SHAFT_MAP], vector=True)
    g_ = {s.name: m.wrap(s, vector=s.type in ("VECTOR", "RGBA")) for s in gin.outputs if s.name}
    cone_args = ()
    if shadow.cone or emitter:   # the driven rows' 9 components: scalar inputs of the node groups
        axes = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
        cone_args = tuple(m.dot(g_[n], a) for n in light_groups.SPOT_ROWS for a in axes)
    if emitter:   # an area light: its pose now
        kind = f"area {shadow.spec.width}x{shadow.spec.height}"
        falloff = area.shaft_falloff
    if shadow.cone:   # a moving spot: its rows, cos(size / 2) and blend
        cone_args += (g_[light_groups.SPOT_COS], g_[light_groups.SPOT_BLEND])

        def driven_falloff(mm, u, d, *cone_):   # (inside the node groups: their own inputs, ``cone_args``)
            rows = [mm.combine(*cone_[3 * i:3 * i + 3]) for i in range(3)]
            x, y, z = spot_.light_space(mm, rows, u)
            return spot_.spot_falloff(mm, -1.0 * z / mm.maximum(mm.sqrt(x * x + y * y + z * z), 1e-30), cone_[9],
                                      cone_[10])
        falloff = driven_falloff
        clip = driven_clip
    node = f"Shaft Node {kind} g {g:.6g}"   # one group for every quadrature node
    share, far = shafts.lit_share(m, g_["Camera"], g_["Direction"], g_["Shaft Length"], g_["Light"], g_["Beta"],
                                  (spec, shadow.spot), samples.view_nodes, shift=g_["Shaft Offset"], g=g,
                                  falloff=falloff, name=node,
                                  tail_nodes=max(samples.view_nodes // shafts.TAIL_SHARE, 2), far=SKY_LENGTH,
                                  cone=cone_args, clip=clip)
    m.feed(gout.inputs["Share"], share)
    m.feed(gout.inputs["Share Far"], far)
    lit_sum, total = shafts.surface_share(m, g_["Surface Position"], g_["Surface Normal"], g_["Camera"],
                                          g_["Light"], g_["Beta"], (spec, shadow.spot),
                                          shift=g_["Surface Offset"], g=g, falloff=falloff, name=node, parts=True,
                                          directions=samples.surface_directions, nodes=samples.surface_nodes,
                                          cone=cone_args, clip=clip)
    # their ratio after the mean (``comp_bundles.build_bundle``)
    m.feed(gout.inputs["Visible"], m.combine(lit_sum, total, 1.0))
    ng[owned.BUILT] = groups.code_fingerprint()
    m.place()
    return groups.install(ng, name)


def still_spot_falloff(light, spot):
    """(falloff(m, u, d), key) of a spot whose map is baked at its pose (``spot``: the map's (frame, half_width)):
    its cone's factor at the ray point light + u, d = |u| (``spot_.spot_falloff``), and what it is built from."""
    frame, half = spot
    forward = frame[2]
    cos_half = math.cos(0.5 * light.data.spot_size)
    blend = float(light.data.spot_blend)
    return (lambda m, u, d: spot_.spot_falloff(m, m.dot(u, forward) / d, cos_half, blend)), (frame, half, cos_half,
                                                                                              blend)


def still_spot_clip(light, spot):
    """``shafts.lit_share``'s clip of a spot whose map is baked at its pose: the light's space of its map's frame
    (right, up, -forward) and cos(size / 2), constants."""
    (right, up, forward), _ = spot
    rows = (tuple(right), tuple(up), tuple(-c for c in forward))
    cos_half = math.cos(0.5 * light.data.spot_size)
    return lambda m, *cone: (rows, cos_half)


def driven_clip(m, *cone):
    """``shafts.lit_share``'s clip of a moving spot: its driven rows and cos(size / 2) (``build_shaft_group``'s
    cone arguments, inside the node groups their inputs)."""
    return [m.combine(*cone[3 * i:3 * i + 3]) for i in range(3)], cone[9]


def atlas_tile(m, image, label):
    """The map of the frame being rendered, cut from ``image``, a light's atlas of an animation's maps
    (``shadow_maps.Atlas``): its tile t (``shaft_maps.ATLAS_TILE``, a simple-expression driver of the frame and the
    atlas's first frame, stride and tile count, read from the image's ``shadow_maps.ATLAS`` property, so an atlas
    baked again for another range needs no new nodes) in slot t // 4 (a Crop node at its column and row: the
    atlas's columns and its maps' grid read from the image too) and channel t % 4 (selected by weights 0 or 1:
    exact, a NO_HIT of 1e30 times 0 is 0), in all four channels of an image of one map, as the shaft group's Map
    input reads a still map (the compositor's Crop, Separate and Combine Color and Map UV read it bit-exactly)."""
    from .. import shadow_maps
    prop = f'["{shadow_maps.ATLAS}"]'
    tile = comp_ops.driven_value(m, f"{label} Tile", shaft_maps.ATLAS_TILE,
                                 [("s", image, f"{prop}[0]"), ("k", image, f"{prop}[1]"), ("n", image, f"{prop}[2]")])
    columns, width, height = (comp_ops.driven_value(m, f"{label} {part}", "v", [("v", image, f"{prop}[{i}]")])
                              for i, part in ((3, "Columns"), (5, "Width"), (6, "Height")))
    slot = m.floor(tile * (1.0 / shaft_maps.ATLAS_CHANNELS))
    channel = tile - slot * float(shaft_maps.ATLAS_CHANNELS)
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
    for c in range(shaft_maps.ATLAS_CHANNELS):
        weight = m.less(m.abs(channel - float(c)), 0.5)
        term = m.wrap(split.outputs[c]) * weight
        depth = term if depth is None else depth + term
    joined = m.node("CompositorNodeCombineColor", 8)
    for c in range(4):
        m.feed(joined.inputs[c], depth)
    return m.wrap(joined.outputs[0], vector=True)


def interleave_mean_group(m, value, length, taps, edge):
    """``_interleave_mean`` as one compositor group shared by every light (``comp_ops.shared_group``)."""
    kind = V if value.vector else F
    name = (f"{LIGHT_GROUP} Interleave Mean {'-'.join(map(str, taps))} {edge:g}"
            + (" Vector" if value.vector else ""))
    return comp_ops.shared_group(m, name, [("Value", kind, value), ("Length", F, comp_ops.first(m, length))],
                                 ("Mean", kind),
                                 lambda sub, g_: _interleave_mean(sub, g_["Value"], g_["Length"], taps, edge))


def _interleave_mean(m, value, length, taps, edge):
    """``value`` (an image: a share, or the vector (lit, total, 1) of ``shafts.surface_share``) averaged over
    an interleaving pattern exactly: a separable filter of the weights ``taps`` (SHAFT_TAPS over the 2 x 2
    pattern of ``shafts.offset``: (1, 2, 1) gives each of its 4 ranks a quarter; SURFACE_TAPS over the
    4 x 4 of ``shafts.surface_offset``: (1, 2, 2, 2, 1), a sixteenth each), by pixels shifted with
    Translate nodes.  A neighbour whose ray is more than ``edge`` longer or shorter in log (``length``)
    counts for nothing: no mixing across a silhouette.  A scalar ``value`` comes back a scalar, the mean;
    a vector's third channel carries the weights, so (lit, total) come back as sums over the same pixels.
    ``length``: a scalar image (``interleave_mean_group`` takes a cropped one's first channel)."""
    log = m.math("LOGARITHM", m.maximum(length, 1e-3), math.e)
    packed = value if value.vector else m.combine(value, 0.0, 1.0)
    half = len(taps) // 2
    for axis in (0, 1):
        total = m.scale(packed, float(taps[half]))
        for k, w in enumerate(taps):
            if k == half:
                continue
            near = [comp_ops.translated(m, img, (k - half) * (axis == 0), (k - half) * (axis == 1))
                    for img in (packed, log)]
            same = m.less(m.abs(m.dot(near[1], (1.0, 0.0, 0.0)) - log), edge)
            total = comp_ops.accumulate(m, total, m.scale(near[0], same * float(w)))
        packed = total
    if value.vector:
        return packed
    return m.dot(packed, (1.0, 0.0, 0.0)) / m.maximum(m.dot(packed, (0.0, 0.0, 1.0)), 1e-6)


def halved(m, scene, position, normal, pixel_x, pixel_y, camera, picture_xy):
    """The bundle's HALF_SHARED inputs for the shafts' shares at half the picture's resolution where its shorter
    side has HALF_FROM pixels or more (a sample every 2 x 2 pixels), at a quarter from QUARTER_FROM (4 x 4; a
    driver reads the render's size, so the choice follows it): never fewer than 72 samples a side.  For the share
    of the fog light a surface gets that the shadows leave (``shafts.surface_share``): the surfaces' ``position``
    and ``normal`` (images over the surfaces' window, whose pixels are ``pixel_x``, ``pixel_y``) at that
    resolution, the interleaving offsets of those samples (``shafts.surface_offset``: its 4 x 4 pattern over 8 x 8
    pixels), the distance from the camera of the sample each pixel of the picture takes, and the Step between
    samples (px: ``_upsampled``).  For the lit share of the glows (``shafts.lit_share``, ``half_view``): the
    interleaving offsets (``shafts.offset``) of the samples of the picture's pixels ``picture_xy``.

    Why: the shares vary slowly over the picture (a shaft's edge is blurred by the interleaving's mean either way),
    and their map reads are most of a shafted light's cost; at half the resolution a quarter of the pixels take
    them.  A picture two or four times the size of another, sampled so, has its shares from as many samples over
    the same patch of the scene as the smaller one at its full resolution (docs/measurements: no worse than the
    render tests' 128 x 72 against path tracing)."""
    size = "min(rx,ry)*p/100"
    variables = [("rx", scene, "render.resolution_x"), ("ry", scene, "render.resolution_y"),
                 ("p", scene, "render.resolution_percentage")]
    factor = comp_ops.driven_value(m, "Surface Share Scale",
                                   f"1-0.5*min(floor({size}/{HALF_FROM}),1)-0.25*min(floor({size}/"
                                   f"{QUARTER_FROM}),1)", variables)   # 1, 1/2, 1/4 exactly
    pos = comp_ops.scaled(m, position, factor)
    whole = shafts.surface_offset(m, m.floor(pixel_x * factor), m.floor(pixel_y * factor))   # a sample's, in each
    step = 1.0 / factor
    px, py = picture_xy
    return {HALF + "Position": pos, HALF + "Normal": comp_ops.scaled(m, normal, factor),
            HALF + "Offset": m.dot(comp_ops.scaled(m, whole, factor), (1.0, 0.0, 0.0)),
            HALF + "Length": m.dot(comp_ops.scaled(m, m.length(pos - camera), step), (1.0, 0.0, 0.0)),
            HALF + "Step": step,
            HALF + "Shaft Offset": shafts.offset(m, m.floor(px * factor), m.floor(py * factor))}


def half_view(m, per_pixel, step):
    """A shaft group's per-pixel inputs (Direction, Shaft Length, Shaft Offset: images, ``per_pixel``'s of
    HALF_SHAFT) at 1 / ``step`` of their resolution (``halved``), and the half-resolution ray lengths."""
    half = {k: comp_ops.scaled(m, per_pixel[k], 1.0 / step) for k in HALF_SHAFT}
    half["Shaft Length"], half["Shaft Offset"] = (comp_ops.first(m, half[k])
                                                  for k in ("Shaft Length", "Shaft Offset"))
    return half, half["Shaft Length"]


def full_view(m, shares, half_length, length, step):
    """The lit shares (S, S_far) of a shaft group at half resolution (``half_view``), each its interleaving's mean
    there, back at the picture's resolution by the depth-aware upsampling (``_upsampled``) and its weights."""
    means = [interleave_mean_group(m, v, half_length, SHAFT_TAPS, SHAFT_EDGE) for v in shares]
    packed = upsampled_group(m, m.combine(means[0], means[1], 1.0),
                             comp_ops.first(m, comp_ops.scaled(m, half_length, step)), length, step)
    weight = m.maximum(m.dot(packed, (0.0, 0.0, 1.0)), 1e-6)
    return [m.dot(packed, axis) / weight for axis in ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0))]


def upsampled_group(m, value, sample_length, length, step):
    """``_upsampled`` as one compositor group shared by every light (``comp_ops.shared_group``)."""
    inputs = [("Value", V, value), ("Sample Length", F, sample_length), ("Length", F, length), ("Step", F, step)]
    return comp_ops.shared_group(m, f"{LIGHT_GROUP} Upsample {UPSAMPLE_EDGE:g}", inputs, ("Value", V),
                                 lambda sub, g_: _upsampled(sub, *(g_[k] for k, _, _ in inputs)))


def _upsampled(m, value, sample_length, length, step):
    """``value`` (the sums (lit, total, weight) of a coarse image, ``halved``) at the picture's resolution,
    ``step`` (px) times its own, depth-aware: a pixel takes its own sample where that sample's distance from the
    camera (``sample_length``) is within UPSAMPLE_EDGE in log of the pixel's own ``length``, else the sum of the
    four next to it (``step`` pixels away) that are.  Its own sample always counts a little (a thousandth), so a
    pixel no sample matches (an object thinner than a sample) takes the nearest one's share.  With ``step`` 1 it is
    ``value``."""
    up = comp_ops.scaled(m, value, step)
    log = m.math("LOGARITHM", m.maximum(length, 1e-3), math.e)
    log_sample = m.math("LOGARITHM", m.maximum(sample_length, 1e-3), math.e)
    own = m.less(m.abs(log_sample - log), UPSAMPLE_EDGE)
    others = m.wrap((0.0, 0.0, 0.0))
    for dx, dy in ((1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0)):
        near_log = m.dot(comp_ops.translated(m, log_sample, step * dx, step * dy), (1.0, 0.0, 0.0))
        same = m.less(m.abs(near_log - log), UPSAMPLE_EDGE)
        others = comp_ops.accumulate(m, others, m.scale(comp_ops.translated(m, up, step * dx, step * dy), same))
    return m.scale(up, own + 1e-3) + m.scale(others, 1.0 - own)
