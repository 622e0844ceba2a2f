"""The error predictor of the model ladder, and the choice of each light's step by a target error.

Issue 8 §2: for every light, the rungs below "full" (``rungs.STEPS``) leave
terms out; the error a step makes in a pixel is the fog light it leaves out,
relative to that pixel's fog value.  Both come from the scene, not from a
render: the camera's view is sampled by rays (``ops/view.py`` casts them
into the scene and reads each hit's position, normal and material), and the
numpy twin of the shaders (the same rung kernels, ``shading.py``'s terms)
gives every light's glow and scattered fog light there.

Per sample p, channel c and light i (W/(m^2 sr), before the fog's albedo,
which multiplies every term of a channel alike and so cancels):

* glow_i = I_i * airlight (Sun et al. 2005 Eq. 11; Eq. 12 for a ray to the sky);
* scatter_i = I_i * e^{-beta D_vp} (rho_d M_0 + rho_s M_n) (Eq. 17-18, 19);
* fog_p = sum_i glow_i + scatter_i: the pixel's fog value, the denominator.

Step 1 of light i drops scatter_i, step 2 drops glow_i too.  The error of a
choice at p is sum over the lights of what they drop / fog_p: exactly the
difference between the auto and the all-exact render's fog light at p, so
the prediction is a bound for the sampled pixels and an estimate between
them.  As in the proof protocol, only samples whose fog is at least
``FLOOR`` of the view's peak count (a near-black pixel has no fog to be
relative to).
"""
from typing import Any, NamedTuple

import numpy as np

from . import bakers, model, rungs, shading
from . import spot as spot_mod
from .ops import NumpyOps

FLOOR = 1e-3          # samples below this fraction of the peak fog are not judged (issue 8 §2)
RIM_SAFETY = 2.0      # a cheaper rim's deviation at the samples counts twice: between them it can peak higher
QUALITY = {"draft": 0.05, "final": 0.01, "exact": None}   # Quality presets: target relative error (None: no step)
DEFAULT_QUALITY = "final"


class ViewSamples(NamedTuple):
    """Points the camera sees (P samples; background rays have distance inf), world space, m."""
    camera: Any       # (P, 3) camera position of each sample (animations: several frames)
    direction: Any    # (P, 3) unit ray direction
    distance: Any     # (P,) D_vp to the hit, inf for a ray to the background
    normal: Any       # (P, 3) unit normal facing the camera (ignored for the background)
    rho_d: Any        # (P, 3) diffuse albedo of the hit's material (surface.principled_to_phong)
    rho_s: Any        # (P, 3) glossy albedo
    level: Any        # (P,) table level of the glossy exponent
    lights: Any       # (P, N, 3) each light's position when the sample was taken
    frame: Any = None  # (P,) the frame of each sample (for reports)
    spots: Any = None  # SpotSamples, or None: every light a point light


class SpotSamples(NamedTuple):
    """The cones of the lights that are spots (``shading.Spot``), as the view samples saw them."""
    is_spot: Any      # (N,) bool
    rows: Any         # (P, N, 3, 3) the inverse of each light's 3x3 world matrix (identity for a point light)
    cos_half: Any     # (N,) cos(spot_size / 2)
    blend: Any        # (N,) spot_blend


class Prediction(NamedTuple):
    steps: Any         # (N,) int: each light's step (rungs.STEPS)
    light_error: Any   # (N,) max over samples of what the light's step drops / fog
    error: float       # max over samples of the sum over the lights: the predicted error of the choice
    judged: int        # samples judged (fog >= FLOOR * peak)
    limited: bool = False   # the budget took steps beyond the target (error may exceed it)
    fits: bool = True       # the steps fit the budget (False: even every light off does not)
    rims: Any = None        # (N,) int: the point count of each spot's rim (spot.RIM_LADDER; meaningless for points)


class Budget(NamedTuple):
    """What a renderer can hold, per resource k: sum over the lights i of ``cost[k][i][step_i]`` (or, the
    same for every light, ``cost[k][step_i]``) <= ``limit[k]``."""
    cost: Any          # (K, len(rungs.STEPS)) or (K, N, len(rungs.STEPS)): each resource's cost of a light by step
    limit: Any         # (K,)
    name: str          # what runs out (for reports)

    def fits(self, steps):
        cost = np.asarray(self.cost, float)
        steps = np.asarray(steps, int)
        used = cost[:, np.arange(len(steps)), steps] if cost.ndim == 3 else cost[:, steps]
        return bool((used.sum(axis=1) <= np.asarray(self.limit, float)).all())


def target_error(quality):
    """Target relative error from a Quality preset name or a number (None or "exact": no step taken)."""
    if quality is None:
        return None
    if isinstance(quality, str):
        key = quality.strip().lower()
        if key not in QUALITY:
            raise ValueError(f"unknown quality {quality!r}: use {', '.join(QUALITY)} or a relative error "
                             "such as 0.01")
        return QUALITY[key]
    value = float(quality)
    if not (np.isfinite(value) and 0.0 < value < 1.0):
        raise ValueError(f"the target error must be a fraction in (0, 1), such as 0.01 for 1 %, got {quality!r}")
    return value


def _numpy_ops(g):
    return NumpyOps(bakers.numpy_tables(float(g)))


def light_fog(samples, intensity, beta, g=0.0):
    """(glow, scatter), each (P, N, 3) W/(m^2 sr): every light's terms at every sample (module docstring).

    intensity: (N, 3) RGB radiant intensity I0, W/sr; beta: 1/m; g: Henyey-Greenstein anisotropy.
    The full rungs of the "nodes" preference (its tables; the quadrature where g is below the
    tables' range), the shaders' twin.
    """
    m = _numpy_ops(g)
    preference = _preference(g)
    full = rungs.choose(preference, 0, g)
    cam, d, lights, sky, d_vp, d_sv, along, h = rays = _rays(m, samples)
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        air = np.where(sky, m.run(full.background, beta, d_sv, along, h),
                       m.run(full.airlight, beta, d_sv, along, h, d_vp))
        to_l = lights - (cam + m.scale(d, d_vp))
        d_sp = np.maximum(m.length(to_l), model.MIN_DISTANCE)
        n = np.asarray(samples.normal, float)[:, None, :]
        cos_n = m.dot(to_l, n) / d_sp
        cos_r = m.dot(to_l, shading.mirror(m, -d, n)) / d_sp
        level = np.broadcast_to(np.asarray(samples.level, float)[:, None], cos_r.shape)
        diffuse = m.run(full.scatter, beta, d_sp, cos_n, np.zeros_like(level))
        glossy = m.run(full.scatter, beta, d_sp, cos_r, level)
        k, light = _spot_lights(samples, lights)
        if k.size:   # the spots' glow and cone (shading.shade_point)
            spot = rungs.choose(preference, 0, g, spot=True)
            air[:, k] = _spot_glow(m, spot, beta, k, light, rays)
            cone = shading.surface_cone(m, light, cam + m.scale(d, d_vp))
            axis = spot_mod.world_axis(m, light.spot.rows)
            diffuse[:, k], glossy[:, k] = m.run(spot.scatter, beta, d_sp[:, k], cos_n[:, k], cos_r[:, k], level[:, k],
                                                *cone, m.dot(n, axis), m.dot(shading.mirror(m, -d, n), axis))
    t_vp = np.exp(-beta * d_vp)[..., None]
    reflected = (np.asarray(samples.rho_d, float)[:, None, :] * diffuse[..., None]
                 + np.asarray(samples.rho_s, float)[:, None, :] * glossy[..., None])
    intensity = np.asarray(intensity, float)[None, :, :]
    glow = intensity * np.nan_to_num(air, nan=0.0, posinf=0.0)[..., None]
    scatter = np.where(sky[..., None], 0.0, intensity * t_vp * np.nan_to_num(reflected, nan=0.0, posinf=0.0))
    return glow, scatter


def _preference(g):
    """The models the predictor takes as exact: the node groups' tables, OSL's quadrature where g is below them."""
    return "nodes" if g >= rungs.MIN_TABLE_ANISOTROPY else "osl"


def _rays(m, samples):
    """(camera (P, 1, 3), direction (P, 1, 3), lights (P, N, 3), sky (P, 1), d_vp (P, 1), d_sv, along, h (P, N))."""
    cam = np.asarray(samples.camera, float)[:, None, :]
    d = np.asarray(samples.direction, float)[:, None, :]
    lights = np.asarray(samples.lights, float)
    dist = np.asarray(samples.distance, float)[:, None]
    sky = ~np.isfinite(dist)
    return (cam, d, lights, sky, np.where(sky, 0.0, dist), *model.ray_light_geometry(m, cam, d, lights))


def _spot_lights(samples, lights):
    """(indices k of the spots, shading.Light of them (no intensity)); k is empty for point lights only."""
    spots = samples.spots
    if spots is None or not np.any(spots.is_spot):
        return np.zeros(0, int), None
    k = np.flatnonzero(spots.is_spot)
    rows = np.asarray(spots.rows, float)[:, k]
    return k, shading.Light(lights[:, k], None, shading.Spot(tuple(rows[..., i, :] for i in range(3)),
                                                              np.asarray(spots.cos_half, float)[k],
                                                              np.asarray(spots.blend, float)[k]))


def _spot_glow(m, models, beta, k, light, rays):
    """(P, K) the glow per unit intensity of the spots ``k`` (``_spot_lights``) with their ``models``."""
    cam, d, _, sky, d_vp, d_sv, along, h = rays
    args = (beta, d_sv[:, k], along[:, k], h[:, k])
    ray = shading.spot_ray(m, light, models.airlight, cam, d)
    return np.where(sky, m.run(models.background, *args, *ray), m.run(models.airlight, *args, d_vp, *ray))


def rim_deviation(samples, intensity, beta, glow, g=0.0):
    """(R, P, N, 3) W/(m^2 sr): how far each spot's glow moves at every sample when its rim takes the point
    count ``spot.RIM_LADDER[1 + r]`` instead of spot.RIM_NODES (0 for point lights); ``glow``: the exact
    glows of :func:`light_fog` (spot.RIM_NODES points), which it does not compute again."""
    m = _numpy_ops(g)
    preference = _preference(g)
    rays = _rays(m, samples)
    k, light = _spot_lights(samples, rays[2])
    ladder = spot_mod.RIM_LADDER[1:]
    out = np.zeros((len(ladder),) + rays[2].shape)
    for r, n in enumerate(ladder if k.size else ()):
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            cheap = _spot_glow(m, rungs.choose(preference, 0, g, True, n), beta, k, light, rays)
        cheap = np.asarray(intensity, float)[None, k, :] * np.nan_to_num(cheap, nan=0.0, posinf=0.0)[..., None]
        out[r][:, k] = np.abs(cheap - glow[:, k])
    return out


def choose_steps(glow, scatter, target, budget=None, rim_dev=None):
    """Each light's step down the ladder so that the predicted error stays within ``target``, and each spot's
    rim (``rim_dev``: :func:`rim_deviation`).

    glow, scatter: (P, N, 3) from :func:`light_fog`; target: relative error
    (None: every light full).  Greedy: the candidate drops (a light's scatter,
    then its glow) are taken in order of the largest share of any judged
    sample's fog they would leave out, each while the running sum of what is
    dropped stays within ``target`` of the fog at every judged sample.

    ``budget`` (:class:`Budget`, e.g. EEVEE's uniform block): if the steps
    don't fit it, more drops are taken in the same order, whatever they
    cost in error, until they do (``limited``; the error is still predicted
    the same way, and may exceed the target); a light off is then left out
    (``rungs.LEFT_OUT``, no fog error of its own) right after it is switched off.

    Then each light whose glow stays takes the fewest rim points (``spot.RIM_LADDER``) whose deviation,
    counted RIM_SAFETY times, still keeps the sum within ``target`` (the lights in the order of their
    deviation's largest share, smallest first).  A point light's deviation is 0: its count is meaningless.
    """
    glow = np.asarray(glow, float)
    scatter = np.asarray(scatter, float)
    n = glow.shape[1]
    fog = (glow + scatter).sum(axis=1)                 # (P, 3)
    peak = fog.max() if fog.size else 0.0
    judged = fog >= FLOOR * peak if peak > 0.0 else np.zeros(fog.shape, bool)
    inv = np.where(judged, 1.0 / np.where(judged, fog, 1.0), 0.0)
    steps = np.zeros(n, int)
    dropped = np.zeros_like(fog)
    share_s = (scatter * inv[:, None, :]).max(axis=(0, 2)) if fog.size else np.zeros(n)
    share_g = ((glow + scatter) * inv[:, None, :]).max(axis=(0, 2)) if fog.size else np.zeros(n)
    # a light's scatter drop sorts before its glow drop (share_g >= share_s, ties by step)
    candidates = sorted([(share_s[i], i, 1) for i in range(n)] + [(share_g[i], i, 2) for i in range(n)]
                        + [(share_g[i], i, rungs.LEFT_OUT) for i in range(n)])
    def drop(i, step):   # what light i's step leaves out, (P, 3)
        return scatter[:, i] if step == 1 else glow[:, i] if step == 2 else np.zeros_like(fog)

    if target is not None and peak > 0.0:
        for _, i, step in candidates:
            if steps[i] != step - 1 or step == rungs.LEFT_OUT:
                continue
            trial = dropped + drop(i, step)
            if (trial * inv).max() <= target:
                dropped, steps[i] = trial, step
    limited = False
    for _, i, step in candidates if budget is not None else ():
        if budget.fits(steps):
            break
        if steps[i] == step - 1:
            dropped, steps[i], limited = dropped + drop(i, step), step, True
    light_drop = np.where(steps[None, :, None] >= 1, scatter, 0.0) + np.where(steps[None, :, None] >= 2, glow, 0.0)
    rims = np.full(n, spot_mod.RIM_NODES)
    if rim_dev is not None and target is not None and peak > 0.0:
        rim_dev = RIM_SAFETY * np.asarray(rim_dev, float)
        for i in np.argsort((rim_dev[0] * inv[:, None, :]).max(axis=(0, 2)), kind="stable"):
            for r in reversed(range(len(rim_dev))) if steps[i] < 2 else ():   # the fewest points first
                trial = dropped + rim_dev[r][:, i]
                if (trial * inv).max() <= target:
                    dropped, rims[i] = trial, spot_mod.RIM_LADDER[1 + r]
                    light_drop[:, i] += rim_dev[r][:, i]
                    break
    light_error = (light_drop * inv[:, None, :]).max(axis=(0, 2)) if fog.size else np.zeros(n)
    error = float((dropped * inv).max()) if fog.size else 0.0
    fits = budget is None or budget.fits(steps)
    return Prediction(steps, light_error, error, int(judged.any(axis=1).sum()), limited, fits, rims)


def predict(samples, intensity, beta, quality, budget=None, g=0.0):
    """The choice for a view at a Quality (preset name, number or None): :class:`Prediction`."""
    glow, scatter = light_fog(samples, intensity, beta, g)
    return choose_steps(glow, scatter, target_error(quality), budget,
                        rim_deviation(samples, intensity, beta, glow, g))
