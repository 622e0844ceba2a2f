"""A fog layer's daylight in the compositor, per pixel: what the fog group takes of it (``Day``; its terms:
``daylight_terms.pixel_terms``, composed by ``compose.compose``) and the lit shares of the sun's shafts from its map
(``sun_shares``)."""
import hashlib
from typing import Any, NamedTuple

from ..precompute.physics.daylight import sun_shafts, sunlight
from ..precompute.physics.shafts import shafts
from ..shadow_maps import SUN_IMAGE
from . import comp_shafts
from .comp_shafts import SHAFT_EDGE, SHAFT_GROUP, SHAFT_TAPS, SURFACE_EDGE, SURFACE_TAPS

LAYER_OPEN = 1.0e9   # units: a fog layer's span end beyond this is open (``sunlight.lamp_glow_span``'s UNBOUNDED)


class Day(NamedTuple):
    """``comp_fog.build_fog_group``'s ``day``: what the compositor takes of a fog layer's daylight."""
    build: Any             # ``surface_group.build_surface``'s ``day``: (m, beta, albedo) -> ``sunlight.Daylight``
    table: Any             # the fog light's TableSpec (``sunsky.fog_light_table``)
    dims: bool             # whether surfaces take the sun's and the sky's dimming (``sunsky.dims_surfaces``)
    sun_shadow: Any = None   # the sun's map (``sun_maps.SunShadow``), or None: no shafts from the sun
    sun_nodes: int = 0       # the sun's lit share's nodes a pixel (``shafts.Samples.view_nodes``)


SUN_SHAFT_NODE = f"{SHAFT_GROUP} Sun Node"   # one group per quadrature node of the sun's lit share


def sun_shares(m, sun_shadow, nodes, day, camera, direction, layer, length, beta, point, normal, offsets,
               shaft_length):
    """(the lit share of the layer's sun glow at a pixel, the lit share of the sun's part of the fog light on its
    surface) from the sun's map ``sun_shadow`` (``sun_maps.SunShadow``: an animation's atlas gives the frame's map,
    ``comp_shafts.atlas_tile``, read under the map's table name from then on in this tree).  The glow's
    (``sun_shafts.sun_lit_share``) over the part of the pixel's ray in the layer (``sunlight.lamp_glow_span`` below its lamps' glow top), to the
    pixel's surface or, past ``length``, the sky, at most SUN_REACH mean free paths, ``nodes`` a pixel interleaved
    over 2 x 2 pixels; the surface's (``sun_shafts.sun_surface_share``) interleaved over 4 x 4 (``offsets``: the pixel's
    ``shafts.offset`` and ``surface_offset``).  Each is averaged over its pattern depth-aware
    (``comp_shafts.interleave_mean_group``, by ``shaft_length``)."""
    spec, frame = sun_shadow.spec, sun_shadow.frame
    if sun_shadow.atlas is not None and spec.name not in m.images:   # the frame's map, cut from the atlas
        m.images = dict(m.images, **{spec.name: comp_shafts.atlas_tile(m, m.images[SUN_IMAGE], "Sun Shadow")})
    top_z = sunlight.lamp_glow_top(*layer)
    t0, t1 = sunlight.lamp_glow_span(m, top_z, camera, direction)
    meets = m.less(t0, LAYER_OPEN)
    start = m.minimum(t0, LAYER_OPEN)
    span = m.maximum(m.minimum(m.minimum(t1, length) - start, sun_shafts.SUN_REACH / m.maximum(beta, 1e-9)), 0.0)
    rate = sun_shafts.sun_attenuation_rate(m, beta, m.dot(direction, (0.0, 0.0, 1.0)), sunlight.sun_elevation(m, day))
    name = f"{SUN_SHAFT_NODE} {hashlib.sha1(repr((spec, tuple(frame))).encode()).hexdigest()[:12]}"
    lit = sun_shafts.sun_lit_share(m, spec, frame, camera + m.scale(direction, start), direction, span, rate, nodes,
                               offsets[0], name=name)
    share = comp_shafts.interleave_mean_group(m, m.select(meets, lit, 1.0), shaft_length, SHAFT_TAPS, SHAFT_EDGE)
    lit, total = sun_shafts.sun_surface_share(m, spec, frame, point, normal, camera, beta, day.sun, float(day.g), top_z,
                                          float(layer[2]), offsets[1], name=name)
    parts = comp_shafts.interleave_mean_group(m, m.combine(lit, total, 1.0), shaft_length, SURFACE_TAPS,
                                              SURFACE_EDGE)
    return share, shafts.share_of(m.dot(parts, (1.0, 0.0, 0.0)), m.dot(parts, (0.0, 1.0, 0.0)))
