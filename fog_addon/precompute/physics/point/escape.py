"""How much of a light's multiply scattered field the scene's surfaces leave it, numpy only.

Dense Fog's field (``multiple.py``) is that of unbounded fog.  Beside a hood, a wall or the ground, part of the
light's power meets the surface before it scatters and never feeds the field.  Two shares measure it:

* **The escape fraction** f (``escape_fraction``): the share of the emitted power that scatters before it meets a
  surface, over that share in unbounded fog,

      f = int w(u) (1 - e^{-beta D(u)}) du / int w(u) du,

  D(u) the distance to the first surface in direction u, w the light's emission.  It weighs every scattering
  event alike, wherever it is.
* **The traced share** (``traced_share``): the multiply scattered light the camera sees with the surfaces in the
  way, over the same in unbounded fog.  Photons leave the light, fly exponential free paths (density
  beta e^{-beta r}), stop where a surface is in the way (the scene's surfaces absorb the scattered light, as the
  references do) and scatter by the fog's phase function.  At each scattering a photon also sends its light to what
  the camera sees (next-event estimation towards the receivers, Veach 1997 §10.2, "particle tracing"): a
  scattering at y of a photon going along u adds

      phase(u . (x - y) / |x - y|) e^{-beta |x - y|} / |x - y|^2

  to the fluence at x (radiative transfer in a homogeneous medium: the point kernel; Narasimhan et al. ``002`` §2
  start from the same source), which a view ray gathers over its visible part (one point of it drawn by
  equiangular sampling, Kulla and Fajardo 2012, whose density cancels the 1 / |x - y|^2) and a surface it meets
  reflects.  The same walks give unbounded fog's sum (every photon kept, nothing in the way of its light), so the
  share is a ratio of two sums over the same random numbers.  Every order is in it: a floor also stops the light
  between later scatterings, most of a forward-scattering fog's downward light.

Units: positions and distances in m, beta in 1/m; the shares dimensionless in [0, 1].
"""
from typing import Any, NamedTuple

import numpy as np

NEAR_FRACTION = 0.25       # a scattering nearer a surface point than this fraction of the point's distance from the
#                            light counts as that far (the 1/d^2 spike: a few photons would carry the sum)


def escape_fraction(beta, depth, weight):
    """f: the emitted power's share (directions weighted by ``weight``, (J,)) that scatters before the first
    surface ``depth`` (J,) m away (inf: none), over unbounded fog's (1).  ``beta`` 1/m."""
    weight = np.asarray(weight, float)
    scattered = -np.expm1(-beta * np.minimum(np.asarray(depth, float), 1e12))
    return float((weight * scattered).sum() / max(weight.sum(), 1e-30))


def hg_phase(g, cos_theta):
    """Henyey-Greenstein's phase function, 1/sr."""
    return (1.0 - g * g) / (4.0 * np.pi * (1.0 + g * g - 2.0 * g * cos_theta) ** 1.5)


TRACED_PHOTONS = 1024      # photons a light (the share's spread over seeds 0.01-0.02: docs/measurements)
TRACED_ORDERS = 32         # scatterings a photon (the references' 32 volume bounces)
TRACED_CONNECTIONS = 4     # receivers each scattering sends its light to (drawn by what it adds there)
SKY_DEPTH = 20.0           # optical depth a view ray without a surface is followed to (e^-20)
ROULETTE = 0.05            # a photon sending less than this share of the first scatterings' mean plays roulette


class Receivers(NamedTuple):
    """What the camera sees, world space, m: view rays (the visible part of each) and the surfaces they meet."""
    camera: Any      # (R, 3) each ray's origin
    direction: Any   # (R, 3) unit directions
    length: Any      # (R,) m to the ray's surface (a ray to the sky: SKY_DEPTH / beta)
    points: Any      # (S, 3) the surfaces the rays meet
    normals: Any     # (S, 3) their unit normals, facing the camera
    albedo: Any      # (S,) their grey diffuse albedo
    distance: Any    # (S,) m from the camera to each


def emitted_directions(count, rng, axis=(0.0, 0.0, -1.0), cos_cone=-1.0, lambertian=False):
    """(count, 3) unit directions of photons leaving a light, stratified in the polar angle: uniform over the
    sphere (a point light), within the cone of half-angle cosine ``cos_cone`` about ``axis`` (a spot), or
    cosine-weighted about ``axis`` (an area light, ``lambertian``)."""
    u1 = (np.arange(count) + rng.random(count)) / count
    phi = 2.0 * np.pi * rng.random(count)
    cz = np.sqrt(1.0 - u1) if lambertian else 1.0 - u1 * (1.0 - cos_cone)
    sz = np.sqrt(np.maximum(0.0, 1.0 - cz * cz))
    return np.stack([sz * np.cos(phi), sz * np.sin(phi), cz], axis=1) @ _frame(np.asarray(axis, float))


def _frame(axis):
    """(3, 3) rows: two unit vectors normal to ``axis`` and ``axis`` normalised (a right-handed frame)."""
    a = axis / max(float(np.linalg.norm(axis)), 1e-30)
    b1 = np.cross(a, (1.0, 0.0, 0.0) if abs(a[0]) < 0.9 else (0.0, 1.0, 0.0))
    b1 /= np.linalg.norm(b1)
    return np.stack([b1, np.cross(a, b1), a])


def hg_scattered(directions, g, rng):
    """(N, 3) unit directions after a scattering by Henyey-Greenstein's phase function of anisotropy ``g`` from the
    photons' ``directions`` (N, 3) (the inverse of its cosine's distribution, Pharr et al., pbrt 3rd ed. §15.2.3)."""
    n = len(directions)
    u1, phi = rng.random(n), 2.0 * np.pi * rng.random(n)
    if abs(g) < 1e-3:
        c = 1.0 - 2.0 * u1
    else:
        s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u1)
        c = np.clip((1.0 + g * g - s * s) / (2.0 * g), -1.0, 1.0)
    side = np.where(np.abs(directions[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    b1 = np.cross(directions, side)
    b1 /= np.linalg.norm(b1, axis=1, keepdims=True)
    b2 = np.cross(directions, b1)
    sn = np.sqrt(1.0 - c * c)
    return (sn * np.cos(phi))[:, None] * b1 + (sn * np.sin(phi))[:, None] * b2 + c[:, None] * directions


def _norms(v):
    return np.sqrt(np.einsum("...i,...i->...", v, v))


def ray_weights(position, heading, receivers, beta, g):
    """(N, R) what a scattering at each ``position`` (N, 3) of a photon going along ``heading`` (N, 3) adds to each
    view ray's radiance per unit photon weight, 1/m^2 (times the fog's phase at the ray, taken isotropic: 1/4 pi),
    with the scattering's phase and the exponentials taken at the ray's nearest point (the equiangular sample's
    weight without its angle's draw); and the rays' geometry (t0, h, the angle the ray subtends) for
    ``ray_sample``.  Single precision: a weight only steers the draws."""
    position, camera = position.astype(np.float32), receivers.camera.astype(np.float32)
    direction, length = receivers.direction.astype(np.float32), receivers.length.astype(np.float32)
    rel = position[:, None, :] - camera[None]
    t0 = np.einsum("nri,ri->nr", rel, direction)
    h = np.maximum(_norms(rel - t0[..., None] * direction[None]), np.float32(1e-4))
    angle = np.arctan2(h * length[None], h * h - t0 * (length[None] - t0))   # atan((L - t0)/h) + atan(t0/h)
    tc = np.clip(t0, 0.0, length[None])
    weight = np.exp(-beta * (tc + h)) * angle / h
    if g != 0.0:
        v = camera[None] + tc[..., None] * direction[None] - position[:, None, :]
        weight *= hg_phase(g, np.einsum("nri,ni->nr", v, heading.astype(np.float32)) / np.maximum(_norms(v), 1e-12))
    else:
        weight *= np.float32(hg_phase(0.0, 0.0))
    return weight * np.float32(beta / (4.0 * np.pi)), (t0, h, angle)


def surface_weights(position, heading, receivers, beta, g, light):
    """(N, S) what a scattering at each ``position`` of a photon going along ``heading`` adds to each surface
    point's radiance towards the camera per unit photon weight, 1/m^2: its Lambertian reflection rho cos / pi of
    the scattered light (the phase, e^{-beta d} / d^2, d at least NEAR_FRACTION of the point's distance from the
    light) dimmed on the way to the camera."""
    v = receivers.points.astype(np.float32)[None] - position.astype(np.float32)[:, None, :]
    d = np.maximum(_norms(v), np.float32(1e-12))
    u = v / d[..., None]
    cos_in = np.maximum(-np.einsum("nsi,si->ns", u, receivers.normals.astype(np.float32)), np.float32(0.0))
    near = (NEAR_FRACTION * _norms(receivers.points - light)).astype(np.float32)
    view = np.exp(-beta * receivers.distance)
    return ((receivers.albedo * view / np.pi).astype(np.float32)[None] * cos_in
            * hg_phase(g, np.einsum("nsi,ni->ns", u, heading.astype(np.float32)))
            * np.exp(-beta * d) / np.maximum(d * d, (near * near)[None]))


def ray_sample(position, heading, receivers, rays, geometry, beta, g, rng):
    """(points (M, 3) on the view rays ``rays`` (M,), the estimate of each ray's radiance from the scattering at
    ``position`` (M, 3) of a photon going along ``heading`` (M, 3), 1/m^2): one point of the ray drawn by equiangular
    sampling (density proportional to 1 / (h^2 + (t - t0)^2), which cancels the kernel's 1 / d^2), the phase and the
    exponentials exact there.  ``geometry``: ``ray_weights``' (t0, h, angle), (M,) each."""
    t0, h, angle = (np.asarray(a, float) for a in geometry)
    t = t0 + h * np.tan(np.arctan2(-t0, h) + angle * rng.random(len(rays)))
    x = receivers.camera[rays] + t[:, None] * receivers.direction[rays]
    v = x - position
    d = np.maximum(_norms(v), 1e-12)
    cos = np.einsum("mi,mi->m", v, heading) / d
    return x, (beta / (4.0 * np.pi)) * hg_phase(g, cos) * np.exp(-beta * (t + d)) * angle / h


def traced_share(light, emitted, receivers, beta, g, albedo, free=None, orders=TRACED_ORDERS,
                 connections=TRACED_CONNECTIONS, rng=None):
    """(with the surfaces, without), the multiply scattered light (orders >= 2) the ``receivers`` see of photons
    leaving ``light`` (3,) m along ``emitted`` (N, 3) (``emitted_directions``), summed; their ratio is the share of
    unbounded fog's field the scene leaves (the module docstring).  ``free(origins, directions, lengths)`` -> (M,)
    bool: True where nothing is in the way of each segment (None: no surfaces); ``albedo``: the fog's (grey) single
    scattering albedo, a photon's weight's factor at each scattering; ``orders``: the scatterings a photon makes.
    Each scattering sends its light to ``connections`` receivers drawn by ``ray_weights`` and ``surface_weights``,
    weighted by one over their chance; a surface in the way of the photon's flights or of that light counts it in
    the unbounded sum only.  A photon whose light to the receivers has fallen below ROULETTE of the first
    scatterings' mean goes on with a chance in proportion, its weight divided by it (Russian roulette: the sums'
    expectations unchanged, the far photons' flights and casts spared)."""
    rng = np.random.default_rng(0) if rng is None else rng
    light = np.asarray(light, float)
    rays = len(receivers.length)
    position, heading = np.repeat(light[None], len(emitted), axis=0), np.asarray(emitted, float)
    alive, weight = np.ones(len(emitted), bool), np.ones(len(emitted))
    kept = unbounded = 0.0
    floor = None
    for _ in range(orders):
        if not len(weight):
            break
        step = -np.log1p(-rng.random(len(weight))) / beta
        if free is not None and alive.any():
            alive[alive] = free(position[alive], heading[alive], step[alive])
        position = position + step[:, None] * heading
        on_rays, geometry = ray_weights(position, heading, receivers, beta, g)
        weights = np.concatenate([on_rays, surface_weights(position, heading, receivers, beta, g, light)], axis=1)
        total = weights.sum(axis=1)
        sent = np.flatnonzero(total > 0.0)
        if len(sent):
            value, x = send_to_receivers(position[sent], heading[sent], weights[sent], total[sent], receivers, rays,
                                         [a[sent] for a in geometry], beta, g, connections, rng)
            value *= weight[sent, None]
            unbounded += float(value.sum())
            live = alive[sent]
            if free is not None and live.any():
                origin = np.repeat(position[sent][live], connections, axis=0)
                v = x[live].reshape(-1, 3) - origin
                d = np.maximum(_norms(v), 1e-12)
                seen = free(origin, v / d[:, None], np.maximum(d * (1.0 - 1e-4) - 1e-4, 0.0))
                kept += float((value[live].reshape(-1) * seen).sum())
            else:
                kept += float(value[live].sum())
        weight = weight * albedo
        sending = weight * total
        floor = ROULETTE * float(sending.mean()) if floor is None else floor
        chance = np.minimum(sending / max(floor, 1e-300), 1.0)
        on = rng.random(len(weight)) < chance
        position, heading, alive = position[on], hg_scattered(heading[on], g, rng), alive[on]
        weight = weight[on] / chance[on]
    return kept, unbounded


def send_to_receivers(position, heading, weights, total, receivers, rays, geometry, beta, g, connections, rng):
    """((M, C) the estimates, (M, C, 3) the receiving points) of ``connections`` receivers drawn for each scattering
    (stratified, by ``weights`` (M, R + S) of sum ``total``): a ray's ``ray_sample``, a surface point's own weight,
    each over its chance and the draws' count."""
    cdf = np.cumsum(weights, axis=1) / total[:, None]
    u = (np.arange(connections)[None, :] + rng.random((len(total), connections))) / connections
    pick = np.minimum((cdf[:, None, :] < u[:, :, None]).sum(axis=2), weights.shape[1] - 1)    # (M, C)
    chance = np.maximum(np.take_along_axis(weights, pick, axis=1) / total[:, None], 1e-300)
    flat = pick.reshape(-1)
    rows = np.repeat(np.arange(len(total)), connections)
    value = weights[rows, flat]   # (a surface point's estimate is its weight)
    x = receivers.points[np.clip(flat - rays, 0, max(len(receivers.points) - 1, 0))] if len(receivers.points) \
        else np.zeros((len(flat), 3))
    on_ray = (flat < rays).nonzero()[0]
    if len(on_ray):
        ray = flat[on_ray]
        x[on_ray], value[on_ray] = ray_sample(position[rows[on_ray]], heading[rows[on_ray]], receivers, ray,
                                              [a[rows[on_ray], ray] for a in geometry], beta, g, rng)
    return (value / chance.reshape(-1) / connections).reshape(-1, connections), x.reshape(-1, connections, 3)
