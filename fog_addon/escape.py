"""Dense Fog beside surfaces: the share of each light's multiply scattered field that the scene's surfaces leave.

Dense Fog's field is that of unbounded fog (``precompute/physics/point/multiple.py``).  Light that a hood, a wall
or the ground stops before it scatters never feeds it.  Here the lights' directions are ray cast against the
scene's shadow casters (``shadow_maps.scene_bvh``: a coarse point map of each light, ESCAPE_MAP) and the shares
of ``precompute/physics/point/escape.py`` evaluated:

* ``escape_fractions``: each light's escape fraction f (the share of its power that scatters at all);
* ``field_scales``: each light's second-order share at the points the camera sees (the nearest point of each
  sampled camera ray to the light, and the surface it meets), both flights stopped by the surfaces, the scale
  Dense Fog's field of that light takes in every method (``rungs.choose``'s ``multiple_scale``).  The later
  flights' losses are left out; ``ops/left_out.scale_error`` counts them in the predicted error.

Both judge at most ``shadow_maps.SHARE_LIGHTS`` lights, the most important to the picture (a city's other lamps
take the judged lamps' median scale).
"""
import math

import numpy as np

from . import shadow_maps, view
from .precompute.physics.point import escape
from .precompute.physics.shafts import shaft_maps

ESCAPE_MAP = (48, 24)      # longitude x latitude points of the second order's directions (7.5 degrees apart)
ESCAPE_GRID = (16, 9)      # the view's samples the second order is judged at
SCALE_STEP = 0.05          # scales are rounded to this (lights of one scale share their node groups)


def _emission(light, directions):
    """(J,) the light's emission towards each of ``directions`` relative to its most: 1 for a point light, a
    spot's cone, an area light's cosine about its normal."""
    axis = -np.asarray(light.matrix_world.to_3x3().col[2], float)
    axis /= max(float(np.linalg.norm(axis)), 1e-30)
    if view.is_spot(light):
        return (directions @ axis >= math.cos(0.5 * light.data.spot_size)).astype(float)
    if light.data.type == "AREA":
        return np.maximum(directions @ axis, 0.0)
    return np.ones(len(directions))


def _depths(geometry, light, size):
    """(directions (J, 3), distances (J,) to the first surface, inf where none) of a point map of ``size``."""
    directions, _ = shaft_maps.point_map_casts(*size)   # (rows thinned towards the poles: about equal areas)
    vectors, _ = shadow_maps.point_casts(*size)
    depth = shadow_maps.cast(geometry.bvh, tuple(light.matrix_world.translation), vectors).astype(float)
    return directions, np.where(depth >= shaft_maps.NO_HIT, np.inf, depth)


def escape_fractions(scene, spec, lights):
    """{light name: f in [0, 1]} (``escape.escape_fraction``) for the judged of ``lights``, from a point map of
    ``shadow_maps.SHARE_MAP``."""
    if not lights or spec.beta_per_unit <= 0.0:
        return {}
    geometry = shadow_maps.scene_bvh(scene)
    out = {}
    for light in shadow_maps.judged_lights(scene, spec, lights):
        directions, depth = _depths(geometry, light, shadow_maps.SHARE_MAP)
        out[light.name] = escape.escape_fraction(spec.beta_per_unit, depth, _emission(light, directions))
    return out


def _receivers(samples, k):
    """(K, 3) the points the camera sees that light ``k``'s field is judged at: each sampled ray's nearest point
    to the light (within the ray's visible part) and its surface point."""
    position = samples.lights[:, k, :]
    along = np.einsum("pi,pi->p", position - samples.camera, samples.direction)
    finite = np.isfinite(samples.distance)
    reach = np.where(finite, samples.distance, np.inf)
    nearest = samples.camera + np.clip(along, 0.0, reach)[:, None] * samples.direction
    surface = (samples.camera + np.where(finite, samples.distance, 0.0)[:, None] * samples.direction)[finite]
    return np.concatenate([nearest, surface])


def field_scales(scene, spec, lights, grid=ESCAPE_GRID, previous=None):
    """{light name: scale in [0, 1]}: Dense Fog's field of each judged light times this is the field with the
    scene's surfaces in the way (``escape.second_order_share`` at the view's samples on ``grid``), its mean over
    an animation's sampled frames (``view.sample_frames``: every frame renders the same groups), rounded to
    SCALE_STEP (at least SCALE_STEP); the lights not judged take the judged lights' median.  A light keeps its
    scale in ``previous`` ({name: scale}, a stored choice's; lights without one there: 1) while its new share is
    within SCALE_STEP of it, so that an edit elsewhere does not swap its groups for a share on a rounding edge.
    Empty without a camera or fog."""
    if not lights or scene.camera is None or spec.beta_per_unit <= 0.0:
        return {}
    judged = shadow_maps.judged_lights(scene, spec, lights)
    frames = view.sample_frames(scene)
    samples = view.view_samples(scene, judged, frames=frames, grid=grid)
    shares = {o.name: [] for o in judged}
    for frame, depsgraph in view.at_frames(scene, frames):
        geometry = shadow_maps.scene_bvh(scene, depsgraph)
        at = samples._replace(**{f: getattr(samples, f)[samples.frame == frame]
                                 for f in ("camera", "direction", "distance", "lights")})
        for k, light in enumerate(judged):
            shares[light.name].append(_share(geometry, light, at, k, spec))
    out = {name: _rounded(float(np.mean(v)), None if previous is None else previous.get(name, 1.0))
           for name, v in shares.items()}
    if len(judged) < len(lights):   # (the others, less important to the picture: as the judged are)
        rest = _rounded(float(np.median(list(out.values()))))
        out.update({o.name: rest for o in lights if o.name not in out})
    return out


def _rounded(share, kept=None):
    """``share`` rounded to SCALE_STEP, within [SCALE_STEP, 1]; ``kept`` instead while within SCALE_STEP of it."""
    if kept is not None and abs(share - kept) < SCALE_STEP:
        return kept
    return min(1.0, max(SCALE_STEP, SCALE_STEP * round(share / SCALE_STEP)))


def _share(geometry, light, samples, k, spec):
    """Light ``k``'s second-order share at ``samples`` (one frame's) with the surfaces of ``geometry``: the first
    flight's by ``escape.second_order_share`` over every direction, the second's (from a first scattering to a
    receiver) by ray casts from FLIGHT_POINTS first scatterings drawn by what they feed."""
    directions, depth = _depths(geometry, light, ESCAPE_MAP)
    emission = _emission(light, directions)
    if escape.escape_fraction(spec.beta_per_unit, depth, emission) >= 1.0 - 0.5 * SCALE_STEP:
        return 1.0   # (nothing stops the light's power before it scatters: no second order to judge)
    origin = np.asarray(light.matrix_world.translation)
    receivers = _receivers(samples, k)
    share, points, feeds = escape.second_order_share(origin, directions, emission, depth, receivers,
                                                     spec.beta_per_unit, spec.anisotropy, with_sources=True)
    if feeds.sum() <= 0.0:
        return share
    return share * _second_flight_seen(geometry, origin, points, feeds, receivers, spec)


FLIGHT_POINTS = 48          # first scatterings the second flight is judged from


def _second_flight_seen(geometry, origin, points, feeds, receivers, spec):
    """The share of the second order that reaches the receivers past the surfaces: at FLIGHT_POINTS first
    scatterings drawn by what they feed (quantiles of ``feeds``), the kernel-weighted share of the receivers each
    sees (ray casts), averaged."""
    at = np.searchsorted(np.cumsum(feeds) / feeds.sum(), (np.arange(FLIGHT_POINTS) + 0.5) / FLIGHT_POINTS)
    at = np.minimum(at, len(feeds) - 1)
    sources = points[at]
    kernel = escape.second_order_kernel(origin, sources, receivers, spec.beta_per_unit, spec.anisotropy)
    seen = np.zeros(kernel.shape)
    for s, y in enumerate(sources):
        v = receivers - y
        d = np.linalg.norm(v, axis=1)
        hit = shadow_maps.cast(geometry.bvh, tuple(y), v / np.maximum(d, 1e-12)[:, None])
        seen[:, s] = hit >= d * (1.0 - 1e-4) - 1e-4   # (a receiver on a surface: its own surface)
    per_source = (kernel * seen).sum(axis=0) / np.maximum(kernel.sum(axis=0), 1e-30)
    return float(per_source.mean())
