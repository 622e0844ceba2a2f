"""A fog layer's sun and sky as the composer's terms (``compose.Term``, source ``compose.DAYLIGHT``): their glow and the
fog light a surface reflects, evaluated by the daylight's kernels (``physics/daylight/sunlight.py``), at a pixel (the
Compositor), on a surface's camera ray (the Surface group) and on a ray to the sky (the World)."""
import numpy as np

from ..physics.daylight import sunlight
from ..physics.point import model
from . import compose


def pixel_terms(m, day, table, camera, direction, position, normal, reflectance, length, t_vp, cover, sun_share=None,
                surface_share=None):
    """The sun's and the sky's light at a pixel as the composer's terms (``compose.Term``, source ``compose.DAYLIGHT``,
    the layer's and the air's albedos in them): along the ray to the surface at ``length`` the glow (``sunlight.ray_glow``)
    and the fog light the surface reflects (``sunlight.fog_light`` times its ``reflectance``, taken as Lambertian: the diffuse
    plus the specular albedo), dimmed on its way by ``t_vp`` (``sunlight.view_transmittance``), and the glow to the sky; the
    composer weighs them by the pixel's coverage (Sun et al. 2005 Eq. 19 and 12).  With air the glow is evaluated
    once, along the RAY: to the surface where ``cover`` is above one half, to the sky elsewhere (without the glow's
    table its kernel is the costliest part of the picture: a pixel on a silhouette takes one side's glow).
    ``sun_share``: ``sunlight.ray_glow``'s lit share of the sun's glow, ``surface_share``: ``sunlight.fog_light``'s (``sun_shafts``)."""
    if day.air is None:
        return (surface_terms(m, day, table, camera, direction, position, normal, reflectance, length, t_vp,
                              sun_share, surface_share) + sky_terms(m, day, camera, direction, sun_share))
    to = m.select(m.less(0.5, cover), length, model.FAR)
    return [_term(compose.GLOW, compose.RAY, sunlight.ray_glow(m, day, camera, direction, to, sun_share)),
            *_reflected_terms(m, day, table, position, normal, reflectance, t_vp, surface_share)]


def surface_terms(m, day, table, camera, direction, position, normal, reflectance, length, t_vp, sun_share=None,
                  surface_share=None):
    """The sun's and the sky's light on a camera ray that meets a surface at ``length``, as the composer's terms
    (source ``compose.DAYLIGHT``; ``compose.surface_light`` sums them: Sun et al. 2005 Eq. 19): the glow along the
    ray (``sunlight.ray_glow``) and the fog light the surface reflects (``sunlight.fog_light`` times its ``reflectance``), dimmed on
    its way by ``t_vp``.  The Surface group's (its camera rays), and a pixel's without air (``pixel_terms``)."""
    return [_term(compose.GLOW, compose.SURFACE, sunlight.ray_glow(m, day, camera, direction, length, sun_share)),
            *_reflected_terms(m, day, table, position, normal, reflectance, t_vp, surface_share)]


def sky_terms(m, day, camera, direction, sun_share=None):
    """The sun's and the sky's glow along a camera ray that meets no surface, to where it leaves the layer and its
    air (Eq. 12), as the composer's term at SKY: the World's camera rays, and a pixel's without air."""
    return [_term(compose.GLOW, compose.SKY, sunlight.ray_glow(m, day, camera, direction, model.FAR, sun_share))]


def _reflected_terms(m, day, table, position, normal, reflectance, t_vp, surface_share):
    return [_term(compose.REFLECTED, compose.SURFACE,
                  reflectance * sunlight.fog_light(m, table, day, position, normal, surface_share)),
            _term(compose.DIMMING, compose.SURFACE, t_vp)]


def _term(kind, at, value):
    return compose.Term(kind, at, compose.DAYLIGHT, value)


def sampled_light(m, day, table, camera, direction, distance, normal, reflectance):
    """(P, 3) W/(m^2 sr): the sun's and the sky's fog light at view samples, composed as a pixel's (``pixel_terms``,
    ``compose.source_light``: Sun et al. 2005 Eq. 19 on a surface, Eq. 12 to the sky), the sun unshadowed: the part
    of each sample's fog that no step of the lamps' ladder leaves out (``predict.ViewSamples.other``).  ``camera``,
    ``direction``, ``normal``: (P, 3); ``distance``: (P,) units to the surface, inf for a ray to the sky (coverage
    0); ``reflectance``: (P, 3) the surface's Lambertian albedo (diffuse plus specular)."""
    distance = np.asarray(distance, float)
    cover = np.isfinite(distance).astype(float)
    length = np.where(cover > 0.0, distance, 0.0)
    position = np.asarray(camera, float) + np.asarray(direction, float) * length[:, None]
    t_vp = sunlight.view_transmittance(m, day, position, -np.asarray(direction, float), length)
    terms = pixel_terms(m, day, table, camera, direction, position, normal, reflectance, length, t_vp, cover)
    return compose.source_light(m, cover, terms)
