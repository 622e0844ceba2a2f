"""Light shafts in the viewport's preview (Cycles): a shafted light's lit shares evaluated in the materials and the
World, by the compositor's own kernels (``shafts.lit_share``, ``shafts.surface_share``) from the same shadow map.

The compositor interleaves its quadrature nodes over a fixed pattern of pixels and filters them
(``comp_shafts.py``): a shader sees one sample of one pixel and no neighbour.  What it has instead is the viewport's
accumulation of samples: each sample turns the nodes by a random shift (a White Noise of the shading point, which a
pixel filter moves at every sample), so the nodes of successive samples interleave in time and the viewport's mean
converges to the shares of a finer quadrature, as the compositor's does over its pattern.  Few nodes a sample
(``PREVIEW_SAMPLES``) keep the viewport quick; a still picture is noisy at first and settles as samples accumulate.
"""
import hashlib

from ..precompute.physics.area import area
from ..precompute.physics.shafts import shafts
from . import comp_shafts, groups, owned
from .groups import F, V
from .sockets import NodeOps

PREVIEW_SAMPLES = shafts.Samples(view_nodes=4, surface_directions=2, surface_nodes=4)   # a sample's nodes
# the segments past glass in final renders (``glass_tails.build_tail_bundle``): fewer nodes a sample, a final render
# has many samples (the shop window's pane: 5.9 % with PREVIEW_SAMPLES, the fog's cost with glass 5.9x the fog-free)
FINAL_SAMPLES = shafts.Samples(view_nodes=4, surface_directions=1, surface_nodes=4)
# the surfaces past glass (``surface_group.build_surface``'s segment bundles): their glow is the tails', so the share
# along their ray (of length 0 there) needs no more than a node; the shadows' share of their fog light keeps its own
SEGMENT_SAMPLES = FINAL_SAMPLES._replace(view_nodes=1)
PREVIEW_SHAFT = groups.PREVIEW_SHAFT   # "<PREVIEW_SHAFT> <light name>"
SKY_LENGTH = 1.0e6   # m: a ray to the sky's length (its far nodes weigh e^{-beta t})
INPUTS = (("Beta", F), ("Camera", V), ("Direction", V), ("Length", F), ("Light", V), ("Position", V), ("Normal", V),
          ("Jitter", F))
OUTPUTS = (("Share", F), ("Visible", F))
KEY = "analytic_fog_shaft_key"   # on a group: what it was built for (the map, a spot's frame, g, an area's normal)


def group_name(light, samples=PREVIEW_SAMPLES):
    tag = "" if samples == PREVIEW_SAMPLES else " K{}.{}.{}".format(*samples)   # (a group per set of samples)
    return f"{PREVIEW_SHAFT} {light.name}{tag}"


def build_group(light, shadow, images, g, samples=PREVIEW_SAMPLES):
    """``light``'s preview shares (shader group): Share, the lit share of its glow along the ray from Camera along
    Direction over Length m (``shafts.lit_share``); Visible, the share of the fog light a surface at Position with
    Normal reflects that the shadows leave (``shafts.surface_share``); both with their nodes turned by Jitter in
    [0, 1).  ``shadow``: the light's still map (``shadow_maps.ShadowMap``; its image is in ``images``), a spot's
    frame and cone built in as the compositor's shaft group builds them (``comp_shafts.build_shaft_group``).
    ``samples``: the nodes a sample evaluates (``shafts.Samples``).  Built once per rebuild of the fog (a group of
    this code's, ``groups.up_to_date``, is taken as it is)."""
    name = group_name(light, samples)
    normal = _area_normal(light)
    built_for = repr((shadow.spec.name, shadow.spot, g) + ((normal,) if normal else ()))
    if (ng := groups.up_to_date(name)) is not None and ng.get(KEY) == built_for:
        return ng
    falloff, clip, kind = None, None, f"point {shadow.spec.name}"
    if normal:   # an area light: its map a point light's, its fog weighed by Lambert's cosine (its pose now)
        falloff = (lambda m_, u, d: area.shaft_falloff(m_, u, d, *(0.0,) * 6, *normal))
        kind = f"area {shadow.spec.name} " + hashlib.sha1(repr(normal).encode()).hexdigest()[:12]
    elif shadow.spot is not None:
        falloff, key = comp_shafts.still_spot_falloff(light, shadow.spot)
        clip = comp_shafts.still_spot_clip(light, shadow.spot)
        kind = "spot " + hashlib.sha1(repr((shadow.spec.name, shadow.spec.width, *key)).encode()).hexdigest()[:12]
    ng, gin, gout = groups.new_group(name, list(INPUTS), list(OUTPUTS))
    m = NodeOps(ng, dict(images))
    v = {s.name: m.wrap(s, vector=s.type == "VECTOR") for s in gin.outputs if s.name}
    node = f"Preview Shaft Node {kind} g {g:.6g}"   # one group for every quadrature node of this light
    share = shafts.lit_share(m, v["Camera"], v["Direction"], v["Length"], v["Light"], v["Beta"],
                             (shadow.spec, shadow.spot), samples.view_nodes, shift=v["Jitter"], g=g,
                             falloff=falloff, name=node, clip=clip)
    m.feed(gout.inputs["Share"], share)
    visible = shafts.surface_share(m, v["Position"], v["Normal"], v["Camera"], v["Light"], v["Beta"],
                                   (shadow.spec, shadow.spot), shift=v["Jitter"], g=g, falloff=falloff, name=node,
                                   directions=samples.surface_directions, nodes=samples.surface_nodes, clip=clip)
    m.feed(gout.inputs["Visible"], visible)
    ng[owned.BUILT] = groups.code_fingerprint()
    ng[KEY] = built_for
    m.place()
    return groups.install(ng, name)


def _area_normal(light):
    """An area light's emitting side as its world normal's opposite, the third row of its inverse 3x3 world matrix
    (``area.shaft_falloff``), rounded; None for other lights."""
    if not comp_shafts.is_area(light):
        return None
    return tuple(round(float(c), 6) for c in light.matrix_world.to_3x3().inverted_safe()[2])


def jitter(ng, position):
    """A value in [0, 1) that changes at every sample: a White Noise of ``position`` (an output socket), which the
    pixel filter moves a little at each sample (the noise hashes every bit of it)."""
    noise = ng.nodes.new("ShaderNodeTexWhiteNoise")
    noise.noise_dimensions = "3D"
    noise.name = noise.label = "Preview Shaft Jitter"
    ng.links.new(position, noise.inputs["Vector"])
    return noise.outputs["Value"]


def shares(ng, light, shadow, images, g, inputs, samples=PREVIEW_SAMPLES):
    """A node in ``ng`` of ``light``'s shares (``build_group`` of its ``shadow`` map, fog of anisotropy ``g``,
    ``samples`` nodes a sample), its inputs from ``inputs`` (name: an output socket to link, or a number: Length
    SKY_LENGTH on a ray to the sky; Light is left for the caller where it is not given yet)."""
    node = ng.nodes.new("ShaderNodeGroup")
    node.node_tree = build_group(light, shadow, images, g, samples)
    node.name = node.label = f"Preview Shaft: {light.name}"
    for name, value in inputs.items():
        if isinstance(value, (int, float)):
            node.inputs[name].default_value = value
        else:
            ng.links.new(value, node.inputs[name])
    return node
