"""The sun and the sky through a fog layer (issue 29): what a pixel gets from them.

The composer of ``daylight.py``'s kernels for a scene: a fog layer over the ground (``Daylight``: density beta up
to the top, an exponential falloff above it or a hard top), one sun (a unit vector towards it and its irradiance
on a surface facing it) and a uniform sky over the upper hemisphere (its radiance), the ground black to the fog.
Every length is in Blender units (the spec's ``layer_per_unit``), heights are measured from the ground.

A pixel gets, besides its surface's own shading:

* the camera segment's transmittance through the layer (``view_transmittance``, Koschmieder's law with a
  height-dependent medium): it replaces e^{-beta D} on surfaces, and the sky seen along a ray that meets no
  surface is the World times ``sky_seen``;
* the glow of the sun and of the sky along the camera segment (``ray_glow``: Dobashi et al. 2002 Eq. 11, one
  species, and the sky as a sum of suns);
* on a surface, the sun's and the sky's direct light dimmed by the fog above it (``direct_dimming``: the weights
  of the two by their fog-free irradiance on the surface, so one factor serves a user's shader that sums them);
* on a surface, the fog light the layer scatters onto it (``fog_light``): Sun et al. 2005 Sec. 4's reflected
  airlight, here an irradiance integral of ``ray_glow`` over the surface's hemisphere, read from an order-2
  spherical-harmonic irradiance map per height (``daylight_tables.bake_fog_light``).

The sun's and the sky's scattering take the fog's Henyey-Greenstein g (the sky's by its ring means,
``daylight.hg_ring_mean``).  ``model/daylight_terms.py`` hands a pixel's glow and fog light to the composer (``compose.py``),
which weighs them by the pixel's coverage with the other sources' light.
"""
import math
from typing import Any, NamedTuple

import numpy as np

from . import aerial, daylight
from .daylight_tables import GLOW_ELEVATIONS, SH_COUNT, TABLE_ROWS, glow_coordinates, sh_basis, table_height


class Daylight(NamedTuple):
    """A fog layer, its sun and its sky (Blender units; shader backends hold sockets, numpy floats or arrays)."""
    beta: Any            # 1/unit: the layer's extinction below its top
    top: float           # units above the ground: the top of the layer (Python float)
    falloff: float       # units: H of the density's fall above the top, 0 a hard top (Python float)
    ground: Any          # the ground's z (units)
    sun: Any             # unit vector towards the sun (world)
    sun_irradiance: Any  # RGB, W/m^2 on a surface facing the sun (a Blender Sun light's Strength x Color)
    sky_radiance: Any    # RGB, W/(m^2 sr): the World's radiance over the upper hemisphere
    g: float = 0.0       # Henyey-Greenstein anisotropy of the sun's scattering (Python float)
    albedo: Any = 1.0    # RGB (or grey): the layer's single-scattering albedo (the air's is 1)
    air: Any = None      # the clear air's Rayleigh extinction at the ground per colour channel, 1/unit (three
                         # scalars or an RGB value), or None without air
    air_height: float = 0.0   # units: the air's scale height (Python float)
    glow_table: Any = None    # ``GlowTable``: ``ray_glow`` reads the glow from a camera's baked table; None: the kernels
    world_sky: Any = None     # ``tables.TableSpec`` of the World's radiance over the upper hemisphere when the World is
                              # a sky seen through its own air (a Sky Texture): ``world_radiance``; None: the World is
                              # the light above the air
    grey_air: bool = False    # the tree dims by one grey factor (a shader's mix; the node groups): the air's opacity
                              # in ``ray_glow``'s World term is grey too, so a sky pixel stays the World


def _z(m, v):
    return m.dot(v, (0.0, 0.0, 1.0))


def _grey(m, colour):
    return m.dot(colour, (1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0))


def sun_elevation(m, day):
    """mu_s: the sine of the sun's elevation (the z-component of the unit vector towards it)."""
    return _z(m, day.sun)


AXES = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))


def air_channels(m, day):
    """The air's ground extinction per colour channel (three values, 1/unit), or None without air."""
    if day.air is None:
        return None
    if isinstance(day.air, (tuple, list)):
        return tuple(day.air)
    return tuple(m.dot(day.air, axis) for axis in AXES)


# --- a World that is a sky seen through its own air (a Sky Texture) -------------------------------------------
#
# Such a World already holds the air: its radiance in a direction is the sky through the whole atmosphere, its sun
# disc is dimmed by the air, and the user's Sun light matched to it is the sun at the ground.  So with Air on, the
# air's own terms are taken from the World instead of the kernels: along a ray of length L the air's glow is
# L_World(d) (1 - T_air(L)) (its limit far away is the World itself, so a sky pixel, L_World T_air + that, is the
# World exactly, and distant terrain fades to the sky right above it); the Sun light is the sun below the air, so
# the layer's sun glow and fog light take it divided by the air's transmittance to the ground
# (``sun_above_air``), and the air dims a surface's sun light only by the column it has above the ground's.
# docs/measurements/2026-11-27-sky-texture.md measured what counting the air twice did.

def world_radiance(m, day, direction):
    """The World's radiance in ``direction`` (RGB, W/(m^2 sr)) from its table ``day.world_sky`` (rows: the elevation
    from the horizon up at ``sky_row_elevations``; columns: the azimuth from +Y towards +X at the centres of
    ``sunsky.probe_sky``'s equirectangular probe's columns); a direction below the horizon reads the horizon."""
    spec = day.world_sky
    dx, dy = m.dot(direction, (1.0, 0.0, 0.0)), m.dot(direction, (0.0, 1.0, 0.0))
    horizontal = m.sqrt(dx * dx + dy * dy)
    x = m.atan2(dx, dy) * (0.5 / math.pi) + 0.5
    elevation = m.atan2(m.maximum(_z(m, direction), 0.0), horizontal) * (2.0 / math.pi)
    gx = (x * spec.width - 0.5) * (1.0 / (spec.width - 1.0))
    gy = (m.sqrt(elevation) * spec.height - 0.5) * (1.0 / (spec.height - 1.0))
    return m.combine(*(m.table(spec, gx, gy, channel=c) for c in range(3)))


def air_transmittance(m, day, origin, direction, length):
    """The air's transmittance per colour channel (a list of three) along the segment of ``length`` units from
    ``origin`` (unit ``direction``)."""
    shape = aerial.exponential_depth(m, _z(m, origin) - day.ground, _z(m, direction), length, 1.0, 0.0,
                                       day.air_height)
    return [daylight.exp_neg(m, b * shape) for b in air_channels(m, day)]


def sun_above_air(m, day):
    """Per colour channel (a list of three) the factor that takes the Sun light's irradiance at the ground to the
    sun above the air, e^{+b C_air(0) / mu_s} (``world_sky`` set; 1 otherwise)."""
    if day.world_sky is None or day.air is None:
        return [1.0, 1.0, 1.0]
    column = aerial.air_column_depth(m, 0.0, 1.0, day.air_height)
    mu = m.maximum(sun_elevation(m, day), 0.05)
    return [m.exp(m.minimum(b * column / mu, 20.0)) for b in air_channels(m, day)]


def _layer(day):
    return (day.beta, day.top, day.falloff)


def view_transmittance(m, day, point, incoming, length):
    """e^{-tau} of the segment from a surface ``point`` towards the camera (unit ``incoming``, ``length`` units):
    ``daylight.transmittance`` (the optical depth is the same read from either end); with air an RGB value,
    the layer's and the air's optical depths per channel."""
    z, vz = _z(m, point) - day.ground, _z(m, incoming)
    air = air_channels(m, day)
    if air is None:
        return daylight.transmittance(m, z, vz, length, *_layer(day))
    tau_l = daylight.optical_depth(m, z, vz, length, *_layer(day))
    shape = aerial.exponential_depth(m, z, vz, length, 1.0, 0.0, day.air_height)
    return m.combine(*(daylight.exp_neg(m, tau_l + b * shape) for b in air))


LAMP_FALLOFF_CUT = 1.0   # the lamps' glows end this many falloff lengths above a layer's top (``lamp_glow_top``)


def lamp_glow_top(top, falloff, ground):
    """The height (z, units) where the lamps' glow kernels take a layer (its top and falloff above the ground at z
    ``ground``, units) to end: its top, or with a falloff one falloff length above it.  A density e^{-x} above the
    top (x in falloff lengths) is the mixture int e^{-s} 1[x < s] ds of hard tops at s; the glow is linear in the
    density, so it is the e^{-s}-weighted mean of hard-top glows, and one Gauss-Laguerre node (s = 1, weight 1)
    takes it as the glow of a hard top at one falloff length (the same column above the top, beta0 H / |v_z|,
    along every slanted ray).  Against quadrature of the graded layer, lamps 1-3 m below the top: 0.2-3.2 % of
    the glow (two nodes: 0.1-4.2 %, not better for twice the cost; docs/measurements/2026-11-27-lamp-layer.md)."""
    return float(ground) + float(top) + LAMP_FALLOFF_CUT * float(falloff)


def lamp_glow_span(m, top_z, origin, direction):
    """(t0, t1): the part of a ray from ``origin`` (unit ``direction``) where the lamps' homogeneous kernels apply,
    below ``top_z`` (``lamp_glow_top``), in units along the ray: from the origin inside the layer (t0 = 0) to where the ray
    leaves it going up (t1 = daylight.UNBOUNDED if it never does); from an origin above it, from where the ray enters
    it going down (t1 = UNBOUNDED); t0 = t1 = UNBOUNDED for a ray that never meets it.  A lamp's glow is the
    kernel's from origin + t0 u over that length: nothing scatters above the top, and the clear air above it
    dims nothing (Sun et al. 2005 Eq. 5 over the part of the ray in the medium)."""
    z, vz = _z(m, origin), _z(m, direction)
    gap = top_z - z                                    # > 0: the origin is inside the layer
    to_top = m.abs(gap) / m.maximum(m.abs(vz), 1e-12)  # along the ray to the top's height
    inside = m.less(0.0, gap)
    far = daylight.UNBOUNDED
    leaves = inside * m.less(0.0, vz)                  # inside, going up: the ray leaves at the top
    enters = (1.0 - inside) * m.less(vz, 0.0)          # above, going down: it enters there
    t1 = m.select(leaves, m.minimum(to_top, far), far)
    t0 = m.select(inside, 0.0, m.select(enters, m.minimum(to_top, far), far))
    return t0, t1


PROXY_DEPTH = 20.0   # the materials' stand-in transmittance stops falling this many mean free paths out


def proxy_transmittance(m, day, length):
    """A grey stand-in for ``view_transmittance`` in the materials where the compositor corrects every pixel to
    the exact colour (the Compositor method: ``comp_fog.build_fog_group`` multiplies by the exact over this at the
    pixel's surface): e^{-k L}, k the layer's and the air's mean extinction at the ground, held at e^{-PROXY_DEPTH}.
    Two nodes a sample instead of the layer's and the air's optical depths (each shader node on every sample costs
    about 1 % of a render); within a pixel it only weighs the samples' surfaces, exactly where they lie inside a
    layer near the ground."""
    air = air_channels(m, day)
    k = day.beta if air is None else day.beta + (air[0] + air[1] + air[2]) * (1.0 / 3.0)
    return m.exp(-1.0 * m.minimum(k * length, PROXY_DEPTH))


def grey(m, value):
    """The mean of an RGB value's channels; a grey value as it is (a factor that must be one number: a Mix
    Shader's)."""
    return _grey(m, value) if _is_rgb(value) else value


def _is_rgb(value):
    return getattr(value, "vector", False) or (isinstance(value, np.ndarray) and value.shape[-1:] == (3,)
                                               and value.ndim > 0)


def sky_seen(m, day, origin, direction):
    """The fraction of the World seen along a ray from ``origin`` that meets no surface (unit ``direction``):
    ``daylight.sky_transmittance`` (0 for a ray that points down: it would meet the ground); with air RGB, through
    both to infinity."""
    if day.air is None:
        return daylight.sky_transmittance(m, _z(m, origin) - day.ground, _z(m, direction), *_layer(day))
    return view_transmittance(m, day, origin, direction, daylight.UNBOUNDED)


def _tag(value):
    """A number as a node group's name takes it (no '.': Blender's '.001' copies are told by it)."""
    return f"{value:.6g}".replace(".", "p").replace("-", "m").replace("+", "")


def ray_glow(m, day, origin, direction, length, sun_share=None):
    """The glow along a camera segment (``_ray_glow``); where the World holds its own air (``day.world_sky``) the air's
    part is the World's radiance times the air's opacity along the segment (the section above)."""
    glow = _ray_glow(m, day, origin, direction, length, sun_share)
    if day.world_sky is None or day.air is None:
        return glow
    t = air_transmittance(m, day, origin, direction, length)
    if day.grey_air:
        return glow + m.scale(world_radiance(m, day, direction), 1.0 - (t[0] + t[1] + t[2]) * (1.0 / 3.0))
    return glow + world_radiance(m, day, direction) * m.combine(*(1.0 - c for c in t))


def _ray_glow(m, day, origin, direction, length, sun_share=None):
    """The sun's and the sky's single scattering along a camera segment, W/(m^2 sr) (RGB), the layer's albedo
    included; from ``day.glow_table`` if the Daylight has one (``table_glow``: the same integrals baked for the
    camera's height), else by the kernels: E_sun ``daylight.sun_airlight`` (phase at the angle between the ray and the sun) + L_sky
    ``daylight.sky_airlight``; ``length`` model.FAR for a ray to the sky.  Each is one shared sub-program per g
    (``m.group``: a node group built once per file, so a rebuild of the fog does not build its nodes again).

    With air (``aerial.air_glow``, per colour channel): the sun's scattering by the layer (Henyey-Greenstein) and
    by the air (Rayleigh), the sun reaching each point through both; the air's scattering of the sky; and the
    layer's exact sky glow times the air's share of it (its dimming of the sky's light and of the glow on its way
    to the camera).

    ``sun_share``: the share of the layer's sun glow that the sun reaches past shadow casters
    (``sun_shafts.sun_lit_share``), or None for all of it; the sky's glow and the air's are left whole (light shafts of
    the layer only)."""
    if day.glow_table is not None:
        return table_glow(m, day, direction, length, sun_share)
    pz, vz = _z(m, origin) - day.ground, _z(m, direction)
    args = _layer(day)
    g = float(day.g)
    tag = f"g {round(g * 10000):+d}e-4"   # no '.' in a group's name: Blender's '.001' copies are told by it
    mu_s, cos_theta = sun_elevation(m, day), m.dot(direction, day.sun)
    sky = m.group(f"daylight sky {tag}", lambda mm, *a: daylight.sky_airlight(mm, *a, albedo=1.0, g=g),
                  pz, vz, length, *args)
    air = air_channels(m, day)
    if air is None:
        sun = m.group(f"daylight sun {tag}", lambda mm, *a: daylight.sun_airlight(mm, *a, albedo=1.0, g=g),
                      pz, vz, length, mu_s, cos_theta, *args)
        return _albedo(m, day, m.scale(day.sun_irradiance, _shared(sun, sun_share)) + m.scale(day.sky_radiance, sky))
    up = m.less(0.0, mu_s)
    p_l = m.select(up, daylight.hg_phase(m, g, cos_theta), 0.0)
    p_r = m.select(up, aerial.rayleigh_phase(m, cos_theta), 0.0)
    top, falloff, h_air = float(day.top), float(day.falloff), float(day.air_height)
    name = "daylight air " + " ".join(_tag(v) for v in (top, falloff, h_air, g))

    def kernel(mm, pz_, vz_, length_, mu_, beta_, *b):
        return tuple(v for channel in aerial.air_glow(mm, pz_, vz_, length_, mu_, beta_, top, falloff, b, h_air, g)
                     for v in channel)
    flat = m.group(name, kernel, pz, vz, length, mu_s, day.beta, *air)
    return _air_glow_light(m, day, p_l, p_r, [(sun_l, sun_a, sky * sky_ratio, sky_a) for sun_l, sun_a, sky_a, sky_ratio
                                              in (flat[4 * k:4 * k + 4] for k in range(3))], sun_share)


def _shared(value, share):
    """``value`` times a share, or itself for None."""
    return value if share is None else value * share


def _air_glow_light(m, day, p_l, p_r, channels, sun_share=None):
    """The glow with air, W/(m^2 sr) (RGB), from each colour channel's integrals (sun_l, sun_a, sky_l, sky_a): the
    sun's (E_sun per channel) scattered by the layer (phase p_l, the layer's albedo; times ``sun_share`` if given)
    and by the air (phase p_r), and the sky's (L_sky) glow in the layer (its albedo) and in the air.  Where the World
    holds its air (``day.world_sky``) the air's two terms are left out (``ray_glow`` takes them from the World) and
    the sun is the Sun light above the air (``sun_above_air``)."""
    p_l = _shared(p_l, sun_share)
    albedo = [m.dot(day.albedo, axis) for axis in AXES] if _is_rgb(day.albedo) else [day.albedo] * 3
    if day.world_sky is not None:   # the air's own scattering is in the World
        suns = [(a * p_l) * sun_l * k for a, k, (sun_l, _, _, _) in zip(albedo, sun_above_air(m, day), channels)]
        skies = [a * sky_l for a, (_, _, sky_l, _) in zip(albedo, channels)]
    else:
        suns = [(a * p_l) * sun_l + p_r * sun_a for a, (sun_l, sun_a, _, _) in zip(albedo, channels)]
        skies = [a * sky_l + sky_a for a, (_, _, sky_l, sky_a) in zip(albedo, channels)]
    return day.sun_irradiance * m.combine(*suns) + day.sky_radiance * m.combine(*skies)


def table_glow(m, day, direction, length, sun_share=None):
    """``ray_glow`` from the Daylight's ``GlowTable`` (baked for the camera's height: ``bake_glow_table``): one
    bilinear lookup per block, the phase functions and the sun's and the sky's light per pixel."""
    t = day.glow_table
    x, y = glow_coordinates(m, _z(m, direction), length, t.length_scale)
    cos_theta = m.dot(direction, day.sun)
    rows = GLOW_ELEVATIONS

    def texel(block, channel):
        return m.table(t.spec, x, y, row0=block * rows, rows=rows, channel=channel)
    p_l = _shared(daylight.hg_phase(m, float(day.g), cos_theta), sun_share)
    if t.blocks == 1:
        return _albedo(m, day, m.scale(day.sun_irradiance, p_l * texel(0, 0))
                       + m.scale(day.sky_radiance, texel(0, 1)))
    return _air_glow_light(m, day, p_l, aerial.rayleigh_phase(m, cos_theta),
                           [tuple(texel(k, c) for c in range(4)) for k in range(3)])


def times(m, rgb, factor):
    """An RGB value times a factor that is RGB (channel by channel) or grey."""
    if isinstance(factor, (int, float)):
        return rgb if factor == 1.0 else m.scale(rgb, factor)
    return rgb * factor if _is_rgb(factor) else m.scale(rgb, factor)


def _albedo(m, day, rgb):
    """``rgb`` times the layer's albedo (RGB or grey)."""
    return times(m, rgb, day.albedo)


def direct_dimming(m, day, point, normal, sun_visible=None):
    """The factor on a surface's direct light from the sun and the sky (Dobashi et al. 2002 Eq. 11's g_l): the sun's
    transmittance to the point (``daylight.sun_transmittance``) and the sky's direct irradiance through the fog
    (``daylight.sky_tilted_irradiance``), weighted by their fog-free irradiances on it, E_sun max(n.s, 0) and
    pi L_sky (1 + n_z) / 2.  One factor for the user's shader, which sums both lights: exact
    where one of them dominates or the two transmittances agree.  ``sun_visible``: 1 where the sun reaches the point,
    0 in a shadow (``sun_shafts.sun_surface_lit``; the sun's weight is 0 there and the factor is the sky's alone), None:
    the weighted factor everywhere.  With air RGB: both lights through the layer's and the air's column (the direct
    sky light depends on the column alone, ``daylight.tilted_irradiance_of_column``)."""
    z = _z(m, point) - day.ground
    args = _layer(day)
    w_sun = _grey(m, day.sun_irradiance) * m.maximum(m.dot(normal, day.sun), 0.0)
    if sun_visible is not None:
        w_sun = w_sun * sun_visible
    sky = _grey(m, day.sky_radiance)
    nz = _z(m, normal)
    free = w_sun + sky * (math.pi * 0.5) * (1.0 + nz) + 1e-30
    air = air_channels(m, day)
    if air is None:
        t_sun = daylight.sun_transmittance(m, z, sun_elevation(m, day), *args)
        fogged = w_sun * t_sun + sky * daylight.sky_tilted_irradiance(m, z, nz, *args)
        return (fogged + 1e-30) / free
    mu_s = sun_elevation(m, day)
    c_l, c_a = daylight.column_depth(m, z, *args), aerial.air_column_depth(m, z, 1.0, day.air_height)
    if day.world_sky is not None:   # the Sun light and the World are their light at the ground, through the air: a
        c_a = c_a - aerial.air_column_depth(m, 0.0, 1.0, day.air_height)   # point above it has the air below back
    up = m.less(0.0, mu_s)
    out = []
    for b in air:
        c = c_l + b * c_a
        t_sun = m.select(up, daylight.exp_neg(m, c / m.maximum(mu_s, daylight.MIN_MU)), 0.0)
        out.append((w_sun * t_sun + sky * daylight.tilted_irradiance_of_column(m, m.maximum(c, 0.0), nz) + 1e-30)
                   / free)
    return m.combine(*out)


def _irradiance(m, spec, x, basis, normal, day, part=0):
    """One map's irradiance over pi at table coordinate x for a normal's SH ``basis``: the sun's (``part`` 0: its
    peak I_s C_g(n.s) plus its residual) or the sky's (1), clamped at 0."""
    total = 0.0
    for k in range(SH_COUNT):
        total = total + _coefficient(m, spec, x, part * SH_COUNT + k) * basis[k]
    if part == 0:
        peak = _coefficient(m, spec, x, 2 * SH_COUNT) * _coefficient(
            m, spec, 0.5 * (m.dot(normal, day.sun) + 1.0), 2 * SH_COUNT + 1)
        total = total + peak
    return m.maximum(total, 0.0)


def _coefficient(m, spec, x, i):
    return m.table(spec, x, (i // 4) / (TABLE_ROWS - 1.0), channel=i % 4)


def fog_light(m, spec, day, point, normal, sun_share=None):
    """The irradiance over pi that the layer's single scattering sends onto a surface at ``point`` with unit
    ``normal``, W/(m^2 sr) (RGB), from the baked map (``bake_fog_light``, ``spec`` its TableSpec)
    at the point's height: E_sun (I_s C_g(n.s) + the sun's residual map) + L_sky (the sky's map), each map
    clamped at 0 (an order-2 map rings below 0 facing away from a peaked field); times the layer's albedo.  Times a
    Lambertian albedo: the radiance the surface reflects.  With air ``spec`` is three maps, one per colour channel,
    both species' light and the albedos in them (``bake_fog_light``).  ``sun_share``: the share of the sun's part that
    the sun's shadows in the fog leave (``sun_shafts.sun_surface_share``), or None for all of it."""
    x = m.clamp01((_z(m, point) - day.ground) * (1.0 / table_height(day.top, day.falloff)))
    basis = sh_basis(m, normal)
    if isinstance(spec, tuple):   # with air: one map per colour channel, the albedos in it
        sun_e, sky_l = ([m.dot(v, axis) for axis in AXES] for v in (day.sun_irradiance, day.sky_radiance))
        sun_e = [e * k for e, k in zip(sun_e, sun_above_air(m, day))]
        return m.combine(*(_shared(e, sun_share) * _irradiance(m, c, x, basis, normal, day)
                           + l * _irradiance(m, c, x, basis, normal, day, 1) for c, e, l in zip(spec, sun_e, sky_l)))
    return _albedo(m, day, m.scale(day.sun_irradiance, _shared(_irradiance(m, spec, x, basis, normal, day), sun_share))
                   + m.scale(day.sky_radiance, _irradiance(m, spec, x, basis, normal, day, 1)))
