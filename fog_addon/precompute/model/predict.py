"""The error predictor of the model ladder, and the choice of each light's step by a target error.

Issue 8 §2: for every light, the rungs below "full" (``rungs.STEPS``) leave
terms out; the error a step makes in a pixel is the fog light it leaves out,
relative to that pixel's fog value.  Both come from the scene, not from a
render: the camera's view is sampled by rays (``view.py`` casts them
into the scene and reads each hit's position, normal and material), and the
numpy twin of the shaders (the same rung kernels, ``shading.py``'s terms)
gives every light's glow and scattered fog light there.

Per sample p, channel c and light i (W/(m^2 sr), before the fog's albedo,
which multiplies every term of a channel alike and so cancels):

* glow_i = I_i * airlight (Sun et al. 2005 Eq. 11; Eq. 12 for a ray to the sky);
* scatter_i = I_i * e^{-beta D_vp} (rho_d M_0 + rho_s M_n) (Eq. 17-18, 19);
* fog_p = sum_i glow_i + scatter_i + other_p: the pixel's fog value, the denominator; other_p is the fog light of
  the sources no step leaves out (a fog layer's sun and sky, glowing objects: ``ViewSamples.other``), composed as
  the pixel's.

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

from ..core import spec
from . import bakers
from ..physics.point import model
from . import rungs, shading
from ..physics.spot import spot as spot_mod
from ..core.medium import Medium
from ..core.ops import NumpyOps

FLOOR = 1e-3          # samples below this fraction of the peak fog are not judged (issue 8 §2)
MIN_FOG = 1e-30       # fog light (W/m^2/sr) below which a sample is not judged: an opaque fog's far samples
THIN_SHARE = 0.25     # Dense Fog is left out for a light whose multiply scattered light is at most this share of
#                       the Quality's target at every judged view sample (``multiple_parts``; ``ops/left_out.dense_fog``)
CHUNK_VALUES = 1 << 17   # samples x lights a light kind's terms are evaluated for at once: their temporaries (about
#                         0.7 kB each) stay near 0.1 GB however many lights there are
RIM_SAFETY = 2.0      # a cheaper rim's deviation at the samples counts twice: between them it can peak higher


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
    shapes: Any = None  # LightShapes, or None: every light a point light
    other: Any = None   # (P, 3) W/(m^2 sr): the fog light of the sources the ladder does not step (a fog layer's
    #                     sun and sky, glowing objects: ``ops/left_out.with_other``) before the fog's albedo, or None


class Cone(NamedTuple):
    """A spot light's cone as Blender gives it (``shading.Spot``'s parameters)."""
    cos_half: float   # cos(spot_size / 2)
    blend: float      # spot_blend in [0, 1]


class Rectangle(NamedTuple):
    """An area light's emitter (``shading.Area``'s parameters, ``area.half_sizes``)."""
    half_x: float     # m
    half_y: float     # m


class LightShapes(NamedTuple):
    """The shapes of the lights as the view samples saw them: each light a point (None), a spot's ``Cone`` or an
    area light's ``Rectangle``, and the orientation the kernels read them in."""
    kinds: Any        # (N,) a Cone, a Rectangle or None for each light
    rows: Any         # (P, N, 3, 3) the inverse of each light's 3x3 world matrix (identity for a point light)


class Prediction(NamedTuple):
    steps: Any         # (N,) int: each light's step (rungs.STEPS)
    light_error: Any   # (N,) max over samples of what the light's step drops / fog
    error: float       # max over samples of the sum over the lights: the predicted error of the choice
    judged: int        # samples judged (fog >= FLOOR * peak)
    limited: bool = False   # the budget took steps beyond the target (error may exceed it)
    fits: bool = True       # the steps fit the budget (False: even every light off does not)
    rims: Any = None        # (N,) int: the point count of each spot's rim (spot.RIM_LADDER; meaningless for points)
    fog: Any = None         # (glow, scatter) of ``light_fog`` (with Dense Fog unscaled, if judged with it)
    single: Any = None      # (glow, scatter) without Dense Fog, where its scales made the judge compute them


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


def joint(budgets, n):
    """One Budget of ``n`` lights that fits where each of ``budgets`` fits (their resources side by side, each
    cost as (K, N, STEPS))."""
    costs, limits = [], []
    for b in budgets:
        cost = np.asarray(b.cost, float)
        costs.append(cost if cost.ndim == 3 else np.repeat(cost[:, None, :], n, axis=1))
        limits.extend(np.atleast_1d(np.asarray(b.limit, float)))
    return Budget(np.concatenate(costs, axis=0), limits, " and ".join(b.name for b in budgets))


def _numpy_ops(g):
    return NumpyOps(bakers.numpy_tables(float(g)))


def light_fog(samples, intensity, beta, g=0.0, multiple_albedo=None):
    """(glow, scatter), each (P, N, 3) W/(m^2 sr): every light's terms at every sample (module docstring).

    intensity: (N, 3) RGB radiant intensity I0, W/sr; beta: 1/m; g: Henyey-Greenstein anisotropy.
    The full rungs of the "nodes" preference (its tables; the quadrature where g is below the
    tables' range), the shaders' twin: ``shading.py``'s terms and composition, run once on broadcast
    (P, N, 3) arrays for the point lights and once for the spots.  ``multiple_albedo``: with Dense Fog's
    multiply scattered light of that grey albedo (``rungs.multiple_rungs``; point lights), else None.
    """
    m = _numpy_ops(g)
    if multiple_albedo is not None:
        from ..physics.point import multiple
        spec = multiple.table_spec(g, multiple_albedo)
        m.tables[spec.name] = bakers.table_array(spec, g)
    view = _view(m, samples)
    intensity = np.asarray(intensity, float)
    glow = np.zeros(np.shape(samples.lights))
    scatter = np.zeros_like(glow)
    for k, light in _light_kinds(samples, intensity):
        models = _models(g, light, multiple_albedo=multiple_albedo)
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            values = shading.light_glows(m, view.camera, view.direction, view.geometry.view_distance, light,
                                         Medium(beta), models)
            terms = shading.shade_point(m, view.geometry, view.material, light, Medium(beta), models, air=0.0)
        values.update({o: getattr(terms, o.field) for o in rungs.SURFACE_OUTPUTS if o.kind == rungs.REFLECTED})
        glow[:, k], scatter[:, k] = _pixel_parts(m, values, beta, view)
    return glow, scatter


def _preference(g):
    """The models the predictor takes as exact: the node groups' tables, OSL's quadrature where g is below them."""
    return "nodes" if g >= rungs.MIN_TABLE_ANISOTROPY else "osl"


class _View(NamedTuple):
    """The view samples as ``shading.py`` takes them, broadcast against the lights' axis: (P, 1, 3) vectors,
    (P, 1) scalars (a ray to the background ends at the camera: D_vp = 0, coverage 0)."""
    camera: Any
    direction: Any
    geometry: Any     # shading.Geometry
    material: Any     # shading.Material
    coverage: Any     # (P, 1): 1 where the sample's ray meets a surface, 0 where it goes to the background


def _view(m, samples):
    cam = np.asarray(samples.camera, float)[:, None, :]
    d = np.asarray(samples.direction, float)[:, None, :]
    dist = np.asarray(samples.distance, float)[:, None]
    sky = ~np.isfinite(dist)
    d_vp = np.where(sky, 0.0, dist)
    geo = shading.Geometry(cam, cam + m.scale(d, d_vp), -d, d_vp, np.asarray(samples.normal, float)[:, None, :])
    material = shading.Material(np.asarray(samples.rho_d, float)[:, None, :],
                                np.asarray(samples.rho_s, float)[:, None, :],
                                np.asarray(samples.level, float)[:, None])
    return _View(cam, d, geo, material, (~sky).astype(float))


def _light_kinds(samples, intensity):
    """[(indices k, shading.Light of the lights k as (P, K, 3) arrays)]: the point lights', the spots'
    (``shading.Spot`` of their cones), then the area lights' (``shading.Area``), each only if there is one, and
    each kind's lights cut in runs of at most CHUNK_VALUES / P (the temporaries of their terms are bounded)."""
    lights = np.asarray(samples.lights, float)
    shapes = samples.shapes
    kinds = [None] * lights.shape[1] if shapes is None else list(shapes.kinds)
    run = max(1, CHUNK_VALUES // max(lights.shape[0], 1))
    out = []
    for shape, kernel in ((type(None), None), (Cone, shading.Spot), (Rectangle, shading.Area)):
        every = np.array([i for i, s in enumerate(kinds) if isinstance(s, shape)], int)
        for k in (every[i:i + run] for i in range(0, len(every), run)):
            out.append(_light_run(lights, intensity, shapes, kinds, k, kernel))
    return out


def _light_run(lights, intensity, shapes, kinds, k, kernel):
    """(k, shading.Light of the lights k, all of one kind: ``kernel`` None for point lights)."""
    if kernel is None:
        return k, shading.Light(lights[:, k], intensity[k])
    rows = np.asarray(shapes.rows, float)[:, k]
    params = np.array([tuple(kinds[i]) for i in k], float)
    return k, shading.Light(lights[:, k], intensity[k], kernel(tuple(rows[..., i, :] for i in range(3)),
                                                               params[:, 0], params[:, 1]))


def _models(g, light, rim_nodes=spot_mod.RIM_NODES, multiple_albedo=None):
    """The exact models of ``light`` (a shading.Light of ``_light_kinds``) the predictor judges with."""
    kind = "area" if isinstance(light.spot, shading.Area) else "spot" if light.spot is not None else "point"
    return rungs.choose(_preference(g), 0, g, kind, rim_nodes, multiple_albedo=multiple_albedo)


def multiple_parts(samples, intensity, beta, g, albedo, single=None, dense=None):
    """(P, N): at each judged sample, each light's multiply scattered light (Dense Fog, ``multiple.py``) as a share
    of the sample's fog with it (single plus multiple scattering, as ``choose_steps`` judges), the largest over the
    channels; 0 at samples not judged (below FLOOR of the peak).  Spot and area lights are judged as the point
    lights at their positions (the shapes set aside: the predictor's numpy twin has Dense Fog for point lights
    only), an estimate of their share.  ``single``, ``dense``: ``light_fog``'s (glow, scatter) without it and with
    it if already computed for the same samples (``Prediction.fog``; not reused when the samples have shapes)."""
    if samples.shapes is not None:
        samples, single, dense = samples._replace(shapes=None), None, None
    glow, scatter = single if single is not None else light_fog(samples, intensity, beta, g)
    glow_m, scatter_m = dense if dense is not None else light_fog(samples, intensity, beta, g, multiple_albedo=albedo)
    return judged_shares(np.abs((glow_m + scatter_m) - (glow + scatter)), sample_fog(glow_m, scatter_m, samples.other))


def sample_fog(glow, scatter, other=None):
    """(P, 3) W/(m^2 sr): each sample's fog, the lights' ``glow`` and ``scatter`` (P, N, 3) summed, plus the fog light
    of the sources the ladder does not step (``other``, ``ViewSamples.other``; None: none)."""
    fog = (np.asarray(glow, float) + np.asarray(scatter, float)).sum(axis=1)
    return fog if other is None else fog + np.asarray(other, float)


def judged_shares(part, fog):
    """(P, N): each light's ``part`` (P, N, 3) as a share of the sample's ``fog`` (P, 3), the largest over the
    channels, at the judged samples (fog at least FLOOR of the peak), 0 elsewhere (and everywhere without fog)."""
    peak = fog.max() if fog.size else 0.0
    if not peak > MIN_FOG:
        return np.zeros(part.shape[:2])
    judged = (fog >= FLOOR * peak) & (fog > MIN_FOG)
    inv = np.where(judged, 1.0 / np.where(judged, fog, 1.0), 0.0)
    return (part * inv[:, None, :]).max(axis=2)


def every_nth(samples, n):
    """Every ``n``th of the view ``samples`` (a ``ViewSamples``, its shapes' rows too)."""
    if n <= 1:
        return samples
    cut = lambda a: None if a is None else np.asarray(a)[::n]   # noqa: E731
    shapes = samples.shapes
    return samples._replace(**{f: cut(getattr(samples, f)) for f in ViewSamples._fields if f != "shapes"},
                            shapes=None if shapes is None else shapes._replace(rows=cut(shapes.rows)))


def multiple_share(samples, intensity, beta, g, albedo, single=None):
    """(N,) the largest share of a judged sample's fog that each light's multiply scattered light makes
    (``multiple_parts``): where it is a small part of the Quality's target, Dense Fog is left out for the light
    and costs nothing (``ops/plan.choose_models``)."""
    return multiple_parts(samples, intensity, beta, g, albedo, single).max(axis=0, initial=0.0)


def missing_share(parts, left_out):
    """The largest share of a judged sample's fog that the lights ``left_out`` (indices) miss together when their
    multiply scattered light is not modelled: the sum of their ``multiple_parts`` at a sample, its largest over the
    samples (each light's share is taken at its own largest channel, so this bounds the sum's)."""
    k = np.asarray(list(left_out), int)
    return float(parts[:, k].sum(axis=1).max(initial=0.0)) if len(k) else 0.0


def _finite(v):
    """A term with what numpy's overflow left (NaN, inf) taken as 0: the predictor then judges the rest."""
    return np.nan_to_num(np.asarray(v, float), nan=0.0, posinf=0.0)


def _pixel_parts(m, values, beta, view):
    """(glow, scatter), (P, K, 3): ``shading.pixel_light`` of the GLOW and of the REFLECTED quantities in
    ``values`` (Output -> value) on their own, the parts the ladder drops (rungs.STEPS: the scattered fog
    light first, then the glows); a sample's coverage (0 or 1) selects its surface's or the sky's glow."""
    t_vp = model.transmittance(m, beta, view.geometry.view_distance)
    finite = {o: _finite(v) for o, v in values.items()}
    return tuple(shading.pixel_light(m, {o: v for o, v in finite.items() if o.kind == kind}, t_vp, view.coverage)
                 for kind in (rungs.GLOW, rungs.REFLECTED))


def rim_deviation(samples, intensity, beta, glow, g=0.0):
    """(R, P, N, 3) W/(m^2 sr): how far each spot's glow moves at every sample when its rim takes the point
    count ``spot.RIM_LADDER[1 + r]`` instead of spot.RIM_NODES (0 for point lights); ``glow``: the exact
    glows of :func:`light_fog` (spot.RIM_NODES points), which it does not compute again.  None without spots."""
    spots = [(k, light) for k, light in _light_kinds(samples, np.asarray(intensity, float))
             if isinstance(light.spot, shading.Spot)]
    if not spots:
        return None
    m = _numpy_ops(g)
    view = _view(m, samples)
    ladder = spot_mod.RIM_LADDER[1:]
    out = np.zeros((len(ladder),) + np.shape(samples.lights))
    for r, n in enumerate(ladder):
        for k, light in spots:
            with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
                values = shading.light_glows(m, view.camera, view.direction, view.geometry.view_distance, light,
                                             Medium(beta), _models(g, light, n))
            cheap, _ = _pixel_parts(m, values, beta, view)
            out[r][:, k] = np.abs(cheap - glow[:, k])
    return out


def choose_steps(glow, scatter, target, budget=None, rim_dev=None, other=None):
    """Each light's step down the ladder so that the predicted error stays within ``target``, and each spot's
    rim (``rim_dev``: :func:`rim_deviation`).

    glow, scatter: (P, N, 3) from :func:`light_fog`; target: relative error
    (None: every light full); ``other``: (P, 3), the fog light no step leaves out (``ViewSamples.other``).
    Greedy: the candidate drops (a light's scatter, then its glow) are taken in order of the largest share of any
    judged sample's fog they would leave out, each while the running sum of what is dropped stays within ``target``
    of the fog at every judged sample.

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
    fog = sample_fog(glow, scatter, other)             # (P, 3)
    peak = fog.max() if fog.size else 0.0
    # a pixel whose fog light is below MIN_FOG (an opaque fog's far pixels: e^{-beta d} underflows) is not judged:
    # its inverse would overflow and its shares turn NaN
    judged = (fog >= FLOOR * peak) & (fog > MIN_FOG) if peak > MIN_FOG else np.zeros(fog.shape, bool)
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

    if target is not None and peak > MIN_FOG:
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
    # each light's largest share of a sample's fog that its step leaves out (its scatter from step 1, its glow too
    # from step 2), taken from the shares above: no (P, N, 3) array of the drops is made
    light_error = np.where(steps >= 2, share_g, np.where(steps >= 1, share_s, 0.0))
    rims = np.full(n, spot_mod.RIM_NODES)
    if rim_dev is not None and target is not None and peak > MIN_FOG:
        rim_dev = RIM_SAFETY * np.asarray(rim_dev, float)
        for i in np.argsort((rim_dev[0] * inv[:, None, :]).max(axis=(0, 2)), kind="stable"):
            for r in reversed(range(len(rim_dev))) if steps[i] < 2 else ():   # the fewest points first
                trial = dropped + rim_dev[r][:, i]
                if (trial * inv).max() <= target:
                    dropped, rims[i] = trial, spot_mod.RIM_LADDER[1 + r]
                    own = rim_dev[r][:, i] + (scatter[:, i] if steps[i] >= 1 else 0.0)
                    light_error[i] = (own * inv).max()
                    break
    error = float((dropped * inv).max()) if fog.size else 0.0
    fits = budget is None or budget.fits(steps)
    return Prediction(steps, light_error, error, int(judged.any(axis=1).sum()), limited, fits, rims)


def light_terms(samples, intensity, beta, g=0.0, multiple_albedo=None, multiple_scale=None):
    """(fog, single, multiple_scale): :func:`light_fog`'s (glow, scatter), with Dense Fog's multiply scattered light
    of grey albedo ``multiple_albedo`` if not None; where ``multiple_scale`` (N,) scales it (``escape.field_scales``:
    the share the scene's surfaces leave, as the render scales it) the (glow, scatter) without it, else None: what
    :func:`predict` judges (:func:`judged_terms`)."""
    fog = light_fog(samples, intensity, beta, g, multiple_albedo=multiple_albedo)
    scaled = multiple_albedo is not None and multiple_scale is not None and np.any(np.asarray(multiple_scale) != 1.0)
    return (fog, light_fog(samples, intensity, beta, g) if scaled else None, multiple_scale)


def judged_terms(terms):
    """The (glow, scatter) the ladder judges from :func:`light_terms`' ``terms``: each light's Dense Fog scaled."""
    fog, single, scale = terms
    return fog if single is None else scaled_fog(single, fog, scale)


def predict(samples, intensity, beta, quality, budget=None, g=0.0, multiple_albedo=None, multiple_scale=None,
            terms=None):
    """The choice for a view at a Quality (preset name, number or None): :class:`Prediction`.
    ``multiple_albedo``: the point lights' terms judged with Dense Fog's multiply scattered light of that grey
    albedo (a step that drops a term drops its multiply scattered part too), else None; ``multiple_scale``: (N,)
    each light's scale of that light (``escape.field_scales``: the share the scene's surfaces leave), as the
    render scales it (:func:`scaled_fog`), or None for 1.  ``terms``: :func:`light_terms`' if already computed
    (then the two before are its)."""
    terms = light_terms(samples, intensity, beta, g, multiple_albedo, multiple_scale) if terms is None else terms
    (glow, scatter), single, _ = terms
    return choose_steps(*judged_terms(terms), spec.target_error(quality), budget,
                        rim_deviation(samples, intensity, beta, glow, g),
                        samples.other)._replace(fog=(glow, scatter), single=single)


def scaled_fog(single, dense, scale):
    """(glow, scatter), (P, N, 3): each light's single scattering plus ``scale`` (N,) times its multiply scattered
    part (``dense`` less ``single``, each a (glow, scatter) of :func:`light_fog`): Dense Fog's field as the render
    has it beside surfaces (``rungs.choose``'s ``multiple_scale``)."""
    k = np.asarray(scale, float)[None, :, None]
    return tuple(s + k * (d - s) for s, d in zip(single, dense))
