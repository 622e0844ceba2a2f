"""The shading of a point in fog, written once for every backend: Sun et al. 2005 Eq. 14-19 and 12.

``shade_point`` is one light's contribution at a surface point seen by the
camera; ``shade_surface`` sums the lights and applies Eq. 19; the background
functions do the same for camera rays that meet no surface.  The node
builders (``fog_addon/nodes/light_groups.py``) only connect sockets to these
functions; numpy runs them as the shaders' twin (tests compare the two pixel
by pixel).  Every term's formula is a rung of ``rungs.py``, run through
``m.run`` so each light can get its own models.

The composition of the terms into the pixel's fog (Eq. 19 at a surface point,
Eq. 12 on a ray to the sky) is ``compose.py``'s; here the lamps' quantities of
``rungs.OUTPUTS`` (each with its kind: a glow, reflected light, a dimming
factor, its weight, a gate) are handed to it: ``surface_light`` (Eq. 19's L_a
before the albedo), ``pixel_light`` (a pixel that sees a surface over a
fraction of its area and the sky over the rest), and the materials' sums
around them, ``sum_lights`` / ``surface_fog``, ``shade_background`` (the
World).  Every backend calls them: the node groups through ``NodeOps``, the
error predictor with broadcast (P, N, 3) numpy arrays (``predict.light_fog``);
the compositor's per-pixel sum calls ``compose.compose`` with the lamps'
terms and the other sources'.  The groups' sockets are derived from
``rungs.OUTPUTS`` too.

Adding a physical term (a light's new quantity) touches:

* its kernel and rungs (``model.py`` or a module of its own, ``tables.py`` /
  ``bakers.py`` / ``nodes/images.py`` if it reads a table), and in
  ``rungs.py`` its TERMS entry, LightModels field, rungs (an "off" rung for
  the ladder), ``choose``, and its ``Output`` descriptor in OUTPUTS;
* here: the kernel's call in ``shade_point`` (or ``light_glows`` /
  ``sky_terms`` for a glow) and a field of LightTerms / SkyTerms; the
  composition picks it up by its kind;
* ``osl.py`` / ``sockets.py`` only if the kernel needs an operation the ops
  lack, ``budgets.py``'s budgets (measured costs per light) and
  ``tools/mutations.py`` (a mutation that removes it).

The builders (``light_groups.py``, ``comp_lights.py``) and the predictor
(``predict.py``) need no edit: they take their sockets and sums from OUTPUTS
and these functions.  A term that needs new inputs from the scene (a light's
or the camera's property: ``nodes/light.py``, ``view.py``, the settings)
adds them there.

Units: positions and distances in m, beta in 1/m, light intensity I0 in W/sr
(RGB: power * colour / 4 pi), radiances in W/(m^2 sr).
"""
import math
from typing import Any, NamedTuple

from ..core import tables
from ..physics.area import area
from ..physics.point import model
from ..physics.spot import spot
from . import compose, rungs

MIN_BETA = 1e-12   # 1/unit: a fog thinner than this is no fog (``shade_background``: the World seen and lighting)


class Geometry(NamedTuple):
    """A camera ray's surface hit: all vectors in world space."""
    camera: Any          # camera position, m
    position: Any        # surface point p, m
    incoming: Any        # unit vector from p towards the camera
    view_distance: Any   # D_vp, m
    normal: Any          # unit shading normal


class Material(NamedTuple):
    """The BRDF as the fog light sees it (``surface.principled_to_phong``)."""
    diffuse: Any         # rho_d, RGB albedo of the Lambertian lobe
    specular: Any        # rho_s, RGB albedo of the Phong lobe about the mirrored view vector
    level: Any           # table level 4 log2 n of the Phong exponent n


class Spot(NamedTuple):
    """A spot light's cone (``spot.py``): Blender's spot_size and spot_blend in the light's space."""
    rows: Any            # the rows of the inverse of the light's 3x3 world matrix (three vectors; any
                         # positive multiple: only directions matter)
    cos_half: Any        # cos(spot_size / 2)
    blend: Any           # spot_blend in [0, 1]


class Area(NamedTuple):
    """An area light's emitter (``area.py``): a rectangle in the light's local XY plane, shining along -Z."""
    rows: Any            # as Spot's (a rotation's inverse times a uniform scale: the kernels need metres)
    half_x: Any          # m, ``area.half_sizes``
    half_y: Any          # m


def shape_args(light):
    """The spot kernels' last two arguments for ``light.spot``: a spot's (cos_half, blend), an area light's
    half sizes (a, b)."""
    s = light.spot
    return (s.half_x, s.half_y) if isinstance(s, Area) else (s.cos_half, s.blend)


def glow_hit(m, light, ray, t_end):
    """1 if the ray (light space: ``spot.light_space_ray``) reaches the part of space the light shines into
    before ``t_end`` (a spot's cone, the half space in front of an area light), else 0."""
    if isinstance(light.spot, Area):
        return area.front_hit(m, *ray, t_end)
    return spot.cone_hit(m, *ray, light.spot.cos_half, t_end)


def direct_falloff(m, light, cone):
    """The light's direct intensity at a surface point over its intensity I0, from ``surface_cone``: Blender's
    spot factor, or an area light's Lambert cosine."""
    if isinstance(light.spot, Area):
        return area.lambert_falloff(m, cone[0])
    return spot.spot_falloff(m, *cone)


class Light(NamedTuple):
    position: Any        # m
    intensity: Any       # RGB radiant intensity I0, W/sr
    spot: Any = None     # Spot for a spot light (its models: rungs.choose's kind "spot"), Area for an area light
    #                      (kind "area"), None for a point light
    u: Any = None        # a uniform number in [0, 1) that changes every render sample, for glow rungs that sample
    #                      (``rungs.Rung.sampled``: the viewport preview's sampled lights), else None


class LightTerms(NamedTuple):
    """One light's terms at a surface point (``shade_point``)."""
    airlight: Any        # RGB glow along the camera ray (Eq. 11 times I0), W/(m^2 sr), before the albedo
    scattered: Any       # RGB fog light the surface reflects (Eq. 17-18 times I0), leaving p
    attenuation: Any     # e^{-beta D_sp}: the light's direct light at p is dimmed by this (Eq. 14)
    weight: Any          # the light's unshadowed reflected radiance at p (grey), for EEVEE's shared attenuation
    seen: Any = None     # a spot's: 1 if the camera ray meets its cone (else its glow is 0), None for a point light


class SurfaceFog(NamedTuple):
    """What a fogged material needs (``shade_surface``)."""
    emission: Any             # RGB: albedo * (sum airlight + e^{-beta D_vp} sum scattered), camera rays only
    emissions: list           # the same, light by light (their sum is ``emission``)
    transmittance: Any        # e^{-beta D_vp} on camera rays, 1 on others: scales the user's shader
    direct_attenuation: Any   # EEVEE: the lights' e^{-beta D_sp}, averaged with the weights of LightTerms
    cycles_mix: Any           # 1 - scale of the user's shader in Cycles (lights attenuate themselves)
    eevee_mix: Any            # 1 - scale of the user's shader in EEVEE (light node trees are ignored there)


def mirror(m, incoming, normal):
    """The mirror direction of ``incoming`` about ``normal``: the glossy lobe's axis (Sun App. B)."""
    return m.scale(normal, 2.0 * m.dot(incoming, normal)) - incoming


def _grey(m, colour):
    return m.dot(colour, m.combine(1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0))


def reflected_lobe(m, material, cos_n, cos_r):
    """f_r cos(theta_i) toward a light (1/sr, grey): the diffuse lobe rho_d cos(theta_n) / pi plus the
    energy-normalised Phong lobe rho_s (n + 1) / (2 pi) cos(theta_r)^n about the mirrored view vector
    (the BRDF of ``surface.principled_to_phong``, Sun et al. 2005 Eq. 17-18's lobes).

    cos_n: cosine between the normal and the direction to the light; cos_r: between the mirrored view
    vector and the direction to the light.  Times I0 / D_sp^2 it is the radiance the light's direct
    light reflects towards the camera, unshadowed and undimmed: EEVEE's weight for its shared
    direct attenuation (``shade_surface``).
    """
    n = m.power(2.0, material.level * (1.0 / tables.PHONG_LEVELS_PER_OCTAVE))
    glossy = (n + 1.0) * (0.5 / math.pi) * m.power(m.maximum(cos_r, 0.0), n)
    return _grey(m, material.diffuse) * m.maximum(cos_n, 0.0) * (1.0 / math.pi) + _grey(m, material.specular) * glossy


def shade_point(m, geo, material, light, medium, models, air=None):
    """One light's terms at a surface point: Sun et al. 2005 Eq. 11 (glow), 14 (direct), 17-18 (fog light).

    geo: Geometry; material: Material; light: Light; medium: ``medium.Medium``
    (beta and albedo as backend values); models: ``rungs.LightModels``; air: the glow per unit intensity
    (1/m^2) if it is already computed (``glow_pair``; then no gate, ``LightTerms.seen``, is built for it).
    Returns LightTerms.
    """
    beta = medium.beta
    to_light = light.position - geo.position
    d_sp = m.length(to_light)
    inv_d = 1.0 / m.maximum(d_sp, model.MIN_DISTANCE)
    seen = None
    if air is None:
        d_sv, along, h = model.ray_light_geometry(m, geo.camera, -1.0 * geo.incoming, light.position)
        air_ray = spot_ray(m, light, models.airlight, geo.camera, -1.0 * geo.incoming)
        air = m.run(models.airlight, beta, d_sv, along, h, geo.view_distance, *air_ray,
                    *sample_arg(light, models.airlight))
        if models.airlight.spot:
            seen = glow_hit(m, light, air_ray[:6], geo.view_distance)
    mirrored = mirror(m, geo.incoming, geo.normal)
    cos_n = m.dot(to_light, geo.normal) * inv_d
    cos_r = m.dot(to_light, mirrored) * inv_d
    cone = surface_cone(m, light, geo.position) if models.direct.spot else ()
    if models.scatter.spot:   # both lobes at once: they share the spot's table lookups
        axis = spot.world_axis(m, light.spot.rows)
        diffuse, glossy = m.run(models.scatter, beta, d_sp, cos_n, cos_r, material.level, *cone,
                                m.dot(geo.normal, axis), m.dot(mirrored, axis))
    else:
        diffuse = m.run(models.scatter, beta, d_sp, cos_n, 0.0)
        glossy = m.run(models.scatter, beta, d_sp, cos_r, material.level)
    reflected = m.scale(material.diffuse, diffuse) + m.scale(material.specular, glossy)
    weight = _grey(m, light.intensity) * reflected_lobe(m, material, cos_n, cos_r) * inv_d * inv_d
    if cone:   # a spot's direct light follows its cone (an area light's, Lambert's cosine)
        weight = weight * direct_falloff(m, light, cone)
    return LightTerms(airlight=m.scale(light.intensity, air),
                      scattered=light.intensity * reflected,
                      attenuation=m.run(models.direct, beta, d_sp),
                      weight=weight, seen=seen)


class Gated(NamedTuple):
    """A light's fog light in two parts: ``glow``, worth computing only where ``gate`` is 1 (a spot's
    glow: the shader builders put it behind a Mix Shader of that factor, which Cycles' SVM skips at 0),
    and ``rest``."""
    gate: Any
    glow: Any
    rest: Any


class LightSums(NamedTuple):
    """Some lights' share of Eq. 19 at a surface point (``sum_lights``); ``merge_sums`` adds two."""
    emissions: list           # each light's albedo * (airlight + e^{-beta D_vp} scattered), camera rays only
                              # (a Gated for a light whose glow has a gate, LightTerms.seen)
    emission: Any             # their sum (RGB)
    weighted: Any             # sum of weight * attenuation (LightTerms), for EEVEE's shared attenuation
    weight: Any               # sum of weight


def view_transmittance(m, beta, view_distance, is_camera):
    """(e^{-beta D_vp}, the factor on the user's shader): the transmittance on camera rays, 1 on others."""
    t_vp = model.transmittance(m, beta, view_distance)
    transmit = 1.0 + is_camera * (t_vp - 1.0)
    return t_vp, transmit


def total(values):
    """The sum of a non-empty list of values (numbers, arrays or shader values), left to right."""
    result = values[0]
    for v in values[1:]:
        result = result + v
    return result


def _light_values(values):
    """(Output, value) pairs of ``values`` (a dict, pairs, or LightTerms / SkyTerms: their fields of
    ``rungs.OUTPUTS``) that carry light (GLOW, REFLECTED), missing ones (None) left out."""
    if isinstance(values, (LightTerms, SkyTerms)):
        at = rungs.SURFACE_POINT if isinstance(values, LightTerms) else rungs.SKY
        values = [(o, getattr(values, o.field)) for o in rungs.OUTPUTS if o.at == at]
    pairs = values.items() if isinstance(values, dict) else values
    return [(o, v) for o, v in pairs if v is not None and o.kind in (rungs.GLOW, rungs.REFLECTED)]


def surface_light(m, values, t_vp):
    """Eq. 19's L_a over the albedo at a surface point seen at optical depth beta D_vp, W/(m^2 sr) (RGB): the
    glows along the camera ray as they are, plus the light the surface reflects dimmed by ``t_vp`` =
    e^{-beta D_vp} on its way to the camera.  ``values``: the quantities at the surface (``rungs.OUTPUTS`` at
    SURFACE_POINT; a dict or pairs Output -> value, or LightTerms) of one light or summed over lights (the
    composition is linear); any subset of them, None if it holds none (``compose.surface_light``)."""
    return compose.surface_light(m, _lamp_terms(values, t_vp))


def pixel_light(m, values, t_vp, coverage):
    """The fog light over the albedo of a pixel whose rays meet a surface at D_vp over a fraction ``coverage``
    of its area and go to infinity over the rest, W/(m^2 sr) (RGB): coverage * Eq. 19's L_a
    (``surface_light``) + (1 - coverage) * the glows to infinity (Eq. 12).  ``values``: quantities of
    ``rungs.OUTPUTS`` (Output -> value) at the surface and the sky, of one light or summed over lights, any
    subset (the error predictor composes the ones a ladder step drops on their own: coverage 0 or 1 there
    selects the sky or the surface); None if it holds none (``compose.source_light``).  The predictor's per-sample
    sum; the compositor's composes the lamps' sums with the other sources' (``compose.compose``), the materials and
    the World the same quantities through ``sum_lights`` and ``shade_background``."""
    return compose.source_light(m, coverage, _lamp_terms(values, t_vp))


def _lamp_terms(values, t_vp):
    """The composer's terms (``compose.Term``) of the lamps' ``values`` (``_light_values``) and the dimming ``t_vp``
    of their reflected light on its way to the camera."""
    return compose.output_terms(_light_values(values)) + [compose.Term(compose.DIMMING, compose.SURFACE,
                                                                       compose.LAMPS, t_vp)]


def segment_terms(m, tail, weight, t_vp, share=None):
    """The composer's terms (source ``compose.SEGMENTS``) of one light's glow along a segment past a glass pane or
    a sharp mirror, per unit albedo: ``tail`` (RGB, W/(m^2 sr)) the segment's glow by a difference of tails to
    infinity (Sun et al. 2005 Eq. 12; ``nodes/glass_tails.place_tails``), ``weight`` (RGB) the share the pane or
    the mirror passes on to the camera, ``share`` (grey, or None) the segment's lit share (Dobashi et al. 2002
    Eq. 2), ``t_vp`` (grey) the camera segment's transmittance before it (Eq. 19's T).  The pane sends the
    segment's glow on as light leaving its surface: REFLECTED at SURFACE, dimmed by T."""
    light = tail * weight
    if share is not None:
        light = m.scale(light, share)
    return [compose.Term(compose.REFLECTED, compose.SURFACE, compose.SEGMENTS, light),
            compose.Term(compose.DIMMING, compose.SURFACE, compose.SEGMENTS, t_vp)]


def sum_lights(m, terms, medium, t_vp, is_camera):
    """LightSums of the lights' ``terms`` (LightTerms, at least one): each light's fog light on camera rays
    (Eq. 19's L_a: albedo * (airlight + e^{-beta D_vp} * reflected fog light), ``surface_light``) and EEVEE's
    weights.  A light with a gate (``LightTerms.seen``) keeps its glows apart from the rest (``Gated``)."""
    albedo = medium.albedo
    emissions = []
    for t in terms:
        pairs = _light_values(t)
        if t.seen is None:
            emissions.append(m.scale(albedo * surface_light(m, pairs, t_vp), is_camera))
            continue
        glow, rest = ([(o, v) for o, v in pairs if (o.kind == rungs.GLOW) == want] for want in (True, False))
        emissions.append(Gated(t.seen, m.scale(albedo * surface_light(m, glow, t_vp), is_camera),
                               m.scale(albedo * surface_light(m, rest, t_vp), is_camera)))
    colours = [e.glow + e.rest if isinstance(e, Gated) else e for e in emissions]
    return LightSums(emissions, total(colours), total([t.weight * t.attenuation for t in terms]),
                     total([t.weight for t in terms]))


def merge_sums(a, b):
    """The LightSums of two sets of lights (either may be None)."""
    if a is None or b is None:
        return a if b is None else b
    return LightSums(a.emissions + b.emissions, a.emission + b.emission, a.weighted + b.weighted,
                     a.weight + b.weight)


def surface_fog(m, sums, transmit):
    """SurfaceFog from the lights' LightSums (None: no light) and the factor on the user's shader."""
    if sums is None:
        black = m.combine(0.0, 0.0, 0.0)
        return SurfaceFog(black, [], transmit, m.const(1.0), 1.0 - transmit, 1.0 - transmit)
    num, den = sums.weighted, sums.weight
    direct = (num + 1e-30) / (den + 1e-30)
    return SurfaceFog(sums.emission, sums.emissions, transmit, direct, 1.0 - transmit, 1.0 - transmit * direct)


def shade_surface(m, terms, medium, view_distance, is_camera):
    """Sum the lights' ``terms`` (LightTerms) at a surface point: Sun et al. 2005 Eq. 19.

    L = e^{-beta D_vp} L_p + L_a: the user's shader (L_p, with Cycles' lights
    attenuating their own direct light, Eq. 14) is scaled by the
    transmittance, and the fog adds albedo * (airlight + e^{-beta D_vp} *
    reflected fog light).  is_camera: 1 on camera rays, 0 on others (other
    rays see the material unfogged).  Returns SurfaceFog.  The node builder
    sums the lights in bundles (``sum_lights``, ``merge_sums``, ``surface_fog``).
    """
    t_vp, transmit = view_transmittance(m, medium.beta, view_distance, is_camera)
    return surface_fog(m, sum_lights(m, terms, medium, t_vp, is_camera) if terms else None, transmit)


def surface_cone(m, light, point):
    """A spot's cone as its scatter rung and ``spot.spot_falloff`` take it at a surface ``point``: (the
    point's cosine to the axis, then ``shape_args``)."""
    return (spot.axis_cosine(m, light.spot.rows, point, light.position), *shape_args(light))


def spot_ray(m, light, rung, origin, direction):
    """The spot kernels' extra arguments (``rungs.spot_rungs``) for ``rung``: the ray in the light's space,
    then ``shape_args``; none for a point light's rung."""
    if not rung.spot:
        return ()
    return (*spot.light_space_ray(m, light.spot.rows, origin, direction, light.position), *shape_args(light))


def sample_arg(light, rung):
    """A sampling glow rung's last argument (``rungs.Rung.sampled``): the light's uniform number; none else."""
    if not rung.sampled:
        return ()
    if light.u is None:
        raise ValueError(f"the {rung.name} model samples: its light needs a uniform number (Light.u)")
    return (light.u,)


def background_seen(m, camera, direction, light, models):
    """1 if a ray to infinity meets a spot's cone (else its glow is 0: ``Gated``), None for a point light."""
    if not models.background.spot:
        return None
    return glow_hit(m, light, spot_ray(m, light, models.background, camera, direction)[:6], model.FAR)


class SkyTerms(NamedTuple):
    """One light's quantities on a ray to infinity (``sky_terms``; ``rungs.OUTPUTS`` at SKY)."""
    background: Any      # RGB glow along the ray (Eq. 12 times I0), W/(m^2 sr), before the albedo
    seen: Any = None     # a spot's: 1 if the ray meets its cone (else its glow is 0), None for a point light


def sky_terms(m, camera, direction, light, medium, models):
    """SkyTerms of one light on a camera ray to infinity (unit ``direction``): ``background_point`` and
    ``background_seen``."""
    return SkyTerms(background_point(m, camera, direction, light, medium, models),
                    background_seen(m, camera, direction, light, models))


def background_point(m, camera, direction, light, medium, models):
    """One light's RGB glow along a camera ray to infinity (Sun et al. 2005 Eq. 12 times I0), W/(m^2 sr)."""
    d_sv, along, h = model.ray_light_geometry(m, camera, direction, light.position)
    return m.scale(light.intensity, m.run(models.background, medium.beta, d_sv, along, h,
                                          *spot_ray(m, light, models.background, camera, direction),
                                          *sample_arg(light, models.background)))


def glow_pair(m, camera, direction, view_distance, light, medium, models):
    """(glow to the surface at ``view_distance``, glow to infinity) per unit intensity, 1/m^2, of one light
    along one ray (unit ``direction``): Sun et al. 2005 Eq. 11 and 12 at once, for a backend that needs both
    per pixel (the compositor, whose ``CompOps`` builds a node once for the same inputs: the two share the
    ray's geometry and a point light's tail at the viewer).  A spot's come from its airlight rung's ``pair``
    kernel, which shares their cone intervals and rims (``spot.airlight_pair``)."""
    d_sv, along, h = model.ray_light_geometry(m, camera, direction, light.position)
    air_ray = spot_ray(m, light, models.airlight, camera, direction)
    if models.airlight.pair is not None and models.background.spot:
        return models.airlight.pair(m, medium.beta, d_sv, along, h, view_distance, *air_ray)
    return (m.run(models.airlight, medium.beta, d_sv, along, h, view_distance, *air_ray,
                  *sample_arg(light, models.airlight)),
            m.run(models.background, medium.beta, d_sv, along, h,
                  *spot_ray(m, light, models.background, camera, direction), *sample_arg(light, models.background)))


def light_glows(m, camera, direction, view_distance, light, medium, models):
    """One light's glows along one ray, W/(m^2 sr) (RGB), for a backend that needs the ray's glow to the surface
    and to infinity at once (the compositor's pixels, the error predictor's samples): {Output: value} of the
    GLOW quantities of ``rungs.OUTPUTS`` (Airlight at the surface at ``view_distance``, Eq. 11, and the
    Background, Eq. 12), I0 times ``glow_pair``."""
    air, back = glow_pair(m, camera, direction, view_distance, light, medium, models)
    return {rungs.AIRLIGHT_OUT: m.scale(light.intensity, air), rungs.BACKGROUND_OUT: m.scale(light.intensity, back)}


def shade_background(m, airlights, medium, is_camera, world_light=0.0):
    """(emission, transmittance) of the World: the sum of the lights' glows times the albedo on camera
    rays, and the factor on the user's World.  The fog fills all space, so nothing from infinitely far
    away comes through it: the transmittance is 0 on every ray (the World neither seen nor lighting
    surfaces, as with Cycles' World volume), unless ``world_light`` is 1 (the artist keeps the World's
    light on surfaces: then 1 on rays other than the camera's).  A fog of no density (beta 0) is no fog: the
    transmittance is 1 on every ray (e^{-beta t} at t = infinity is the limit of 0 only for beta > 0)."""
    kept = world_light * (1.0 - is_camera)
    transmittance = kept + m.less(medium.beta, MIN_BETA) * (1.0 - kept)
    if not airlights:
        return m.combine(0.0, 0.0, 0.0), transmittance
    return m.scale(medium.albedo * total(airlights), is_camera), transmittance
