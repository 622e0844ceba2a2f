"""Segments and visibility as kernel inputs (issue 26 item 4): ``segments.glow`` against quadrature.

The reference is independent of the code under test: scipy's adaptive quadrature (QUADPACK QAGS) of Sun
et al. 2005 Eq. 5 times the Henyey-Greenstein weight and Blender's spot factor (blender-facts section 1),
with the integrand and the cone-edge breakpoints of tools/spot_reference.py, taken over only the lit
parts of the segment: the hand-given intervals clipped to the segment and merged here in plain Python
(Dobashi et al. 2002 Eq. 2's H as their indicator).  A point light is that integrand with no cone.

Tolerances are the stated accuracy of the model each glow runs on (``rungs``: the table of g's
``max_error``, plus ``SPOT_RIM_ERROR`` for a spot's rim), as tests/test_airlight.py and
tests/test_spot.py measure them on rays from the camera: a lit piece is a ray from another origin.
"""
import functools
import math
import warnings
from typing import Any, NamedTuple

import numpy as np
import pytest
from scipy import integrate

from fog_addon.precompute.core import tables
from fog_addon.precompute.model import rungs
from fog_addon.precompute.physics.point import airlight, model
from fog_addon.precompute.physics.spot import spot
from tools.research import segments
from fog_addon.precompute.core.ops import NumpyOps
from tools import spot_reference as ref
from tools.shader_float32 import Float32Ops

G = 0.7          # the anisotropic case (one table baked for it)
EPSREL = 1e-10   # the reference's quadrature, piece by piece


class Spot(NamedTuple):   # as shading.Spot: what segments.glow reads of a spot light
    rows: Any
    cos_half: Any
    blend: Any


class Case(NamedTuple):
    beta: float
    origin: Any
    direction: Any
    light: Any
    inv: Any          # the light's inverse 3x3 matrix, None for a point light
    cos_half: float
    blend: float
    length: float     # m, math.inf for the sky


@functools.lru_cache(maxsize=None)
def _ops(g):
    spec = tables.anisotropic(tables.AIRLIGHT, g)
    return NumpyOps({spec.name: airlight.bake_airlight_table(spec)})


def _tol(g, is_spot, quadrature=False):
    """The stated accuracy of the glow's model (rungs.py)."""
    air, _, air_quadrature, _, _ = rungs.anisotropic_rungs(g)
    return (air_quadrature if quadrature else air).max_error + (rungs.SPOT_RIM_ERROR[spot.RIM_NODES] if is_spot else 0)


def _unit(v):
    return v / np.linalg.norm(v)


def _case(rng, is_spot, sky=False):
    """A random segment and light: beta log-uniform in [1e-3, 1] 1/m, the origin T_sv in [0.01, 20] optical
    depths from the light, aimed near the light half the time, length T in [0.01, 50] (or the sky); a spot
    of size 1-180 degrees, blend 0-1 (0 a fifth of the time), any orientation, half the time a non-uniform
    scale, its axis aimed at a point of the segment three times in four."""
    lu = lambda lo, hi: math.exp(rng.uniform(math.log(lo), math.log(hi)))
    beta = lu(1e-3, 1.0)
    light = rng.normal(size=3) * rng.uniform(0.0, 10.0)
    d_sv = lu(0.01, 20.0) / beta
    origin = light + _unit(rng.normal(size=3)) * d_sv
    if rng.uniform() < 0.5:
        direction = _unit(light - origin + rng.normal(size=3) * d_sv * rng.uniform(0.0, 1.5))
    else:
        direction = _unit(rng.normal(size=3))
    length = math.inf if sky else lu(0.01, 50.0) / beta
    if not is_spot:
        return Case(beta, origin, direction, light, None, -1.0, 0.0, length)
    size = math.radians(rng.uniform(1.0, 180.0))
    blend = 0.0 if rng.uniform() < 0.2 else rng.uniform(0.0, 1.0)
    if rng.uniform() < 0.75:
        reach = length if math.isfinite(length) else d_sv + 3.0 / beta
        rot = ref._aimed_rotation(rng, _unit(origin + rng.uniform(0.0, reach) * direction - light))
    else:
        rot = ref.random_rotation(rng)
    matrix = rot @ (np.diag(rng.uniform(0.5, 2.0, 3)) if rng.uniform() < 0.5 else np.eye(3))
    return Case(beta, origin, direction, light, np.linalg.inv(matrix), math.cos(size / 2), blend, length)


def _spot(c):
    return None if c.inv is None else Spot(tuple(c.inv), c.cos_half, c.blend)


def _glow(c, lit, g=0.0, m=None, **kw):
    """The model's glow per unit intensity (1/m^2) of case ``c`` with the lit intervals ``lit``."""
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        return float(segments.glow(m or _ops(g), c.beta, segments.Segment(c.origin, c.direction, c.length), c.light,
                                   _spot(c), lit, g=g, **kw))


# --- the reference --------------------------------------------------------------------------------------

def union(lit, length):
    """The lit intervals clipped to [0, length] and merged: sorted disjoint [a, b] (plain Python)."""
    pieces = sorted((max(a, 0.0), min(b, length)) for a, b in lit if min(b, length) > max(a, 0.0))
    merged = []
    for a, b in pieces:
        if merged and a <= merged[-1][1]:
            merged[-1][1] = max(merged[-1][1], b)
        else:
            merged.append([a, b])
    return merged


def reference(c, lit, g=0.0):
    """Eq. 5 by scipy quad over the union of ``lit`` (intervals along the segment, m), 1/m^2.

    A point light is the spot integrand of tools/spot_reference.py with a cone that holds everything
    (cos_half = -2).  Each lit piece is split at the point closest to the light and at graded distances
    h 4^k about it, at the cone's edges (analytic roots and a grid scan), and at extinction scales 4^k /
    beta from its start; a piece to infinity stops 60 optical depths past its start or the light."""
    if not c.beta > 0.0:
        return 0.0
    inv, cos_half, blend = (np.eye(3), -2.0, 0.0) if c.inv is None else (c.inv, c.cos_half, c.blend)
    ray = ref._Ray(c.beta, c.origin, c.direction, c.light, inv, cos_half, blend, g)
    total = estimate = 0.0
    for a, b in union(lit, c.length):
        end = b if math.isfinite(b) else max(a, ray.along) + 60.0 / c.beta
        pts = {ray.along}
        if c.inv is not None:
            for k in ray.edges_cosines():
                pts.update(ray.quadratic_roots(k))
                pts.update(ray.scan_roots(k, end, ref.GRID))
        s = ray.h
        while 0.0 < s < 2.0 * (end + abs(ray.along)):
            pts.update((ray.along - s, ray.along + s))
            s *= 4.0
        s = 1.0 / c.beta / 16.0
        while s < end - a:
            pts.add(a + s)
            s *= 4.0
        edges = [a, *sorted(p for p in pts if a < p < end), end]
        with warnings.catch_warnings():   # QUADPACK warns on slivers between two roots of one cone edge
            warnings.simplefilter("ignore", integrate.IntegrationWarning)
            for x0, x1 in zip(edges[:-1], edges[1:]):
                value, error = integrate.quad(ray, x0, x1, epsabs=0.0, epsrel=EPSREL, limit=400)
                total += value
                estimate += error
    assert estimate <= 1e-8 * total, (estimate, total)   # the slivers' estimates are ~1e-40 of the glow
    return total


def _check(pairs, tol, label):
    """Relative errors of (got, want) pairs below ``tol``; a glow the reference finds 0 (a ray that misses
    a spot's cone) must be 0 or below 1e-30 1/m^2.  Returns the largest error."""
    errs = []
    for got, want, c in pairs:
        assert math.isfinite(got) and got >= 0.0, (label, got, want, c)
        if want > 1e-30:
            errs.append(abs(got / want - 1.0))
            assert errs[-1] < tol, (label, got, want, c)
        else:
            assert got < 1e-25, (label, got, want, c)
    print(f"{label}: max {max(errs):.2e}, median {np.median(errs):.2e} over {len(errs)} glows")
    return max(errs)


# --- unshadowed: today's glow -----------------------------------------------------------------------------

def _random_rays(rng, n, sky=False):
    """n random segments as arrays (the shaders' batches)."""
    beta = np.exp(rng.uniform(math.log(1e-3), 0.0, n))
    light = rng.normal(size=(n, 3)) * 5.0
    d_sv = np.exp(rng.uniform(math.log(0.01), math.log(20.0), n)) / beta
    origin = light + d_sv[:, None] * rng.normal(size=(n, 3)) / math.sqrt(3.0)
    direction = rng.normal(size=(n, 3))
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    length = np.exp(rng.uniform(math.log(0.01), math.log(50.0), n)) / beta
    return beta, origin, direction, light, (math.inf if sky else length)


@pytest.mark.parametrize("g", [0.0, G])
@pytest.mark.parametrize("quadrature", [False, True])
def test_unshadowed_point_light_is_todays_glow(g, quadrature):
    """``lit=None`` on 2 000 random rays (to a surface, and to the sky) gives today's kernels bit for bit
    (model.airlight_segment / airlight_background, or the OSL method's quadrature); the camera's segment is
    one segment among others.  All-lit intervals (one covering [0, length], beside empty and out-of-range
    ones) give it within float rounding."""
    rng = np.random.default_rng(1 + quadrature)
    m = _ops(g)
    for sky in (False, True):
        beta, origin, direction, light, length = _random_rays(rng, 2000, sky)
        d_sv, along, h = model.ray_light_geometry(m, origin, direction, light)
        with np.errstate(over="ignore", invalid="ignore"):
            if quadrature:
                today = (model.airlight_quadrature_background(m, beta, d_sv, along, h, g) if sky else
                         model.airlight_quadrature(m, beta, d_sv, along, h, length, g))
            else:
                today = (model.airlight_background(m, beta, d_sv, along, h, g) if sky else
                         model.airlight_segment(m, beta, d_sv, along, h, length, g))
            seg = segments.Segment(origin, direction, length)
            got = segments.glow(m, beta, seg, light, g=g, quadrature=quadrature)
            end = np.full(2000, np.inf) if sky else length
            lit = ((end + 1.0, end), (-1.0, end * 2.0), (0.5 * end, 0.5 * end))
            all_lit = segments.glow(m, beta, seg, light, lit=lit, g=g, quadrature=quadrature)
            as_array = segments.glow(m, beta, seg._replace(length=np.full(2000, np.inf)), light, g=g,
                                     quadrature=quadrature) if sky else got
        np.testing.assert_array_equal(got, today)
        np.testing.assert_allclose(as_array, today, rtol=1e-12, atol=0.0)   # sky lengths in a value: FAR
        assert np.all(today > 0.0)
        np.testing.assert_allclose(all_lit, today, rtol=1e-12, atol=0.0)


@pytest.mark.parametrize("g", [0.0, G])
def test_unshadowed_spot_is_todays_glow(g):
    """``lit=None`` gives spot.airlight_spot bit for bit on 150 random spots (to surfaces and the sky), and
    all-lit intervals the same within float rounding."""
    rng = np.random.default_rng(5)
    m = _ops(g)
    hit = 0
    for i in range(150):
        c = _case(rng, True, sky=i % 5 == 0)
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            today = float(spot.airlight_spot(m, c.beta, c.origin, c.direction, c.light, tuple(c.inv), c.cos_half,
                                             c.blend, min(c.length, model.FAR), g))
        assert _glow(c, None, g) == today
        all_lit = _glow(c, ((0.0, math.inf), (3.0, 2.0)), g)
        assert abs(all_lit - today) <= 1e-12 * today, (all_lit, today)
        hit += today > 0.0
    assert hit > 100


# --- the example: half in shadow --------------------------------------------------------------------

@pytest.mark.parametrize("is_spot,g", [(False, 0.0), (False, G), (True, 0.0), (True, G)])
def test_half_in_shadow_glows_as_its_lit_half(is_spot, g):
    """A segment whose first or second half is in shadow (visibility given by hand) glows as the quadrature
    of its lit half alone, within the stated accuracy of the model, on 40 random segments; the shadow
    takes a visible share of the glow (so the test sees it)."""
    rng = np.random.default_rng(11 + is_spot + int(10 * g))
    results, shadowed = [], 0
    for i in range(40):
        c = _case(rng, is_spot)
        half = 0.5 * c.length
        lit = ((0.0, half),) if i % 2 else ((half, c.length),)
        got = _glow(c, lit, g)
        results.append((got, reference(c, lit, g), c))
        full = _glow(c, None, g)
        shadowed += full > 0.0 and got < (1.0 - 0.01) * full
    _check(results, _tol(g, is_spot), f"half in shadow, spot {is_spot}, g {g}")
    assert shadowed >= 15


@pytest.mark.parametrize("is_spot", [False, True])
def test_half_in_shadow_osl_method(is_spot):
    """The same with the OSL method's kernels (quadrature, no tables), to its own stated accuracy."""
    rng = np.random.default_rng(31 + is_spot)
    results = []
    for i in range(20):
        c = _case(rng, is_spot)
        lit = ((0.0, 0.5 * c.length),) if i % 2 else ((0.5 * c.length, c.length),)
        results.append((_glow(c, lit, 0.0, quadrature=True), reference(c, lit), c))
    _check(results, _tol(0.0, is_spot, quadrature=True), f"half in shadow, OSL method, spot {is_spot}")


# --- several intervals ----------------------------------------------------------------------------------------

def _cuts(rng, length, n):
    """n sorted random points in (0, length)."""
    return np.sort(rng.uniform(0.0, 1.0, n)) * length


@pytest.mark.parametrize("is_spot", [False, True])
def test_several_intervals_in_any_order(is_spot):
    """Three disjoint lit intervals in random order and an empty slot (K = 4) against quadrature of their
    union; the glow does not depend on their order (bit for bit: the sorting network only moves values).
    With ``ordered=True`` (no sorting) the non-empty intervals must come in order, the empty ones anywhere."""
    rng = np.random.default_rng(41 + is_spot)
    results = []
    for _ in range(25):
        c = _case(rng, is_spot)
        t = _cuts(rng, c.length, 6)
        lit = [(t[0], t[1]), (t[2], t[3]), (t[4], t[5]), (7.0, 7.0)]
        order = rng.permutation(4)
        got = _glow(c, [lit[k] for k in order])
        assert got == _glow(c, lit) == _glow(c, lit, ordered=True)
        assert _glow(c, [(t[5], t[2])] + lit[:3], ordered=True) == _glow(c, lit[:3], ordered=True)
        results.append((got, reference(c, lit), c))
    _check(results, _tol(0.0, is_spot), f"three intervals, spot {is_spot}")


@pytest.mark.parametrize("is_spot", [False, True])
def test_overlapping_intervals_are_merged(is_spot):
    """Overlapping lit intervals (one nested in another, two crossing, a duplicate) in random order glow as
    their union, not as the sum of their glows."""
    rng = np.random.default_rng(51 + is_spot)
    results, double = [], 0
    for _ in range(25):
        c = _case(rng, is_spot)
        t = _cuts(rng, c.length, 6)
        lit = [(t[0], t[3]), (t[1], t[2]), (t[2], t[4]), (t[0], t[3]), (t[5], c.length)]
        got = _glow(c, [lit[k] for k in rng.permutation(len(lit))])
        results.append((got, reference(c, lit), c))
        separately = sum(_glow(c, [p]) for p in lit)
        double += separately > 1.05 * got
    _check(results, _tol(0.0, is_spot), f"overlapping intervals, spot {is_spot}")
    assert double >= 10


@pytest.mark.parametrize("is_spot", [False, True])
def test_empty_and_out_of_range_intervals(is_spot):
    """Empty intervals (t0 >= t1) add exactly nothing wherever they sit; an interval beyond the segment's end
    or before its origin glows 0; one across the end is cut there, one across the origin at 0 (bit for bit);
    a zero-length segment glows 0."""
    rng = np.random.default_rng(61 + is_spot)
    for _ in range(30):
        c = _case(rng, is_spot)
        length = c.length
        a, b = _cuts(rng, length, 2)
        one = _glow(c, [(a, b)])
        assert one > 0.0 or reference(c, [(a, b)]) < 1e-30
        for empties in ([(b, a)], [(a, a)], [(length, 0.0)], [(math.inf, -math.inf)], [(2 * length, length)]):
            assert _glow(c, empties + [(a, b)]) == one
            assert _glow(c, [(a, b)] + empties) == one
            assert _glow(c, empties) == 0.0
        assert _glow(c, [(length * 1.0001, length * 3.0)]) == 0.0
        assert _glow(c, [(-3.0, -1e-9)]) == 0.0
        assert _glow(c, [(a, length * 5.0)]) == _glow(c, [(a, length)])
        assert _glow(c, [(a, math.inf)]) == _glow(c, [(a, length)])
        assert _glow(c, [(-length, b)]) == _glow(c, [(0.0, b)])
        assert _glow(c._replace(length=0.0), None) == 0.0
        assert _glow(c._replace(length=0.0), [(0.0, 1.0), (-1.0, math.inf)]) == 0.0


# --- segments that do not start at the camera ----------------------------------------------------------------

@pytest.mark.parametrize("is_spot", [False, True])
def test_segment_behind_glass_and_from_a_mirror(is_spot):
    """A camera ray through a pane at s0: the caller's e^{-beta s0} times the glow of the segment that starts
    at the pane (its lit intervals measured from there) is the quadrature of the camera ray's lit parts
    beyond s0.  A segment reflected by a mirror at s0 (a new direction from the mirror's point) against the
    quadrature from that point.  The camera ray's glow is its two parts' sum (Eq. 19 recursively)."""
    rng = np.random.default_rng(71 + is_spot)
    behind, mirrored, whole = [], [], []
    for _ in range(20):
        c = _case(rng, is_spot)
        t = _cuts(rng, c.length, 5)
        s0 = t[0]
        lit = [(t[1], t[2]), (t[3], t[4])]
        rest = c._replace(origin=c.origin + s0 * c.direction, length=c.length - s0)
        rest_lit = [(a - s0, b - s0) for a, b in lit]
        got = math.exp(-c.beta * s0) * _glow(rest, rest_lit)
        behind.append((got, reference(c, [(max(a, s0), b) for a, b in lit]), c))
        first = c._replace(length=s0)
        whole.append((_glow(first, lit) + got, reference(c, lit), c))
        normal = _unit(rng.normal(size=3))
        reflected = _unit(c.direction - 2.0 * np.dot(c.direction, normal) * normal)
        mirror = rest._replace(direction=reflected)
        mirrored.append((_glow(mirror, rest_lit), reference(mirror, rest_lit), mirror))
    tol = _tol(0.0, is_spot)
    _check(behind, tol, f"behind a pane, spot {is_spot}")
    _check(mirrored, tol, f"from a mirror, spot {is_spot}")
    _check(whole, tol, f"camera ray in two segments, spot {is_spot}")


@pytest.mark.parametrize("is_spot", [False, True])
def test_infinite_segment(is_spot):
    """Segments to the sky (length inf) lit up to s, from s on, and in two pieces, against quadrature to
    infinity."""
    rng = np.random.default_rng(81 + is_spot)
    results = []
    for i in range(30):
        c = _case(rng, is_spot, sky=True)
        s1, s2, s3 = np.sort(rng.uniform(0.0, 20.0, 3)) / c.beta
        lit = ([(0.0, s1)], [(s1, math.inf)], [(s1, s2), (s3, math.inf)])[i % 3]
        results.append((_glow(c, lit), reference(c, lit), c))
    _check(results, _tol(0.0, is_spot), f"to the sky, spot {is_spot}")


# --- limits ---------------------------------------------------------------------------------------------------

def test_thin_fog_limit():
    """beta -> 0: the glow over the lit parts is beta times the vacuum integral, closed form
    (1 / 4 pi h) [atan((t - t_c) / h)] over each lit piece (t_c the point closest to the light)."""
    rng = np.random.default_rng(91)
    for _ in range(40):
        c = _case(rng, False)._replace(beta=1e-9)
        c = c._replace(length=rng.uniform(1.0, 100.0))
        t = _cuts(rng, c.length, 4)
        lit = [(t[2], t[3]), (t[0], t[1])]
        p = c.origin - c.light
        t_c = -float(p @ c.direction)
        h = float(np.linalg.norm(p + t_c * c.direction))
        vacuum = sum(math.atan((b - t_c) / h) - math.atan((a - t_c) / h) for a, b in union(lit, c.length))
        want = c.beta * vacuum / (4.0 * math.pi * h)
        got = _glow(c, lit)
        assert abs(got / want - 1.0) < _tol(0.0, False), (got, want, c)


def _extreme_cases():
    """Segments where the kernels' limits are taken: the light on the segment's line (ahead, behind, at the
    origin, at the segment's end), lit intervals ending at the light, spot rays along the cone's edge and
    through its apex, optical depths from 1e-12 to 1e4, zero-length segments."""
    light = np.zeros(3)
    inv = np.eye(3)
    cases = []
    for beta in (0.0, 1e-12, 1e-6, 0.1, 10.0):
        for origin, direction, length in (
                (np.array([0.0, 0.0, -5.0]), np.array([0.0, 0.0, 1.0]), 10.0),   # through the light
                (np.array([0.0, 0.0, -5.0]), np.array([0.0, 0.0, 1.0]), 5.0),    # ends at the light
                (np.array([0.0, 0.0, -5.0]), np.array([0.0, 0.0, -1.0]), math.inf),  # away from it
                (np.zeros(3), np.array([0.0, 0.0, -1.0]), 3.0),                   # starts at the light
                (np.array([1e-9, 0.0, -1e-9]), _unit(np.array([1.0, 0.0, -1.0])), math.inf),   # on a cone's edge
                (np.array([3.0, 0.0, 0.0]), _unit(np.array([-1.0, 0.0, 1.0])), 30.0),
                (np.array([0.0, 0.0, 5.0]), np.array([0.0, 0.0, -1.0]), math.inf),   # through the apex
                (np.array([1.0, 2.0, 3.0]), _unit(np.array([1.0, 1.0, 0.0])), 0.0)):   # zero length
            for cos_half, blend in ((None, None), (math.cos(math.pi / 4), 0.0), (math.cos(math.pi / 4), 0.5),
                                    (0.0, 1.0), (math.cos(1e-3), 0.0)):
                cases.append(Case(beta, origin, direction, light, None if cos_half is None else inv,
                                  cos_half, blend, length))
    return cases


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_no_nan_or_inf_at_the_limits(dtype):
    """Every extreme case, unshadowed and with lit intervals that start or end at the light, at the
    segment's ends, at infinity or nowhere: finite and non-negative, in float64 and in float32 (every
    intermediate, as the shaders).  Zero-length segments glow exactly 0."""
    table = _ops(0.0).tables[tables.AIRLIGHT.name]
    m = NumpyOps({tables.AIRLIGHT.name: table}) if dtype == np.float64 else Float32Ops({tables.AIRLIGHT.name: table})
    f = np.dtype(dtype).type
    for c in _extreme_cases():
        along = float(-(c.origin - c.light) @ c.direction)
        end = c.length
        for lit in (None, [(0.0, along)], [(along, math.inf)], [(-math.inf, math.inf), (along, along)],
                    [(end, end), (0.0, 0.0)], [(along - 1e-7, along + 1e-7), (0.0, 1e-12)]):
            arr = lambda v: np.asarray(v, dtype)
            spot_light = None if c.inv is None else Spot(tuple(arr(c.inv)), f(c.cos_half), f(c.blend))
            lit_v = None if lit is None else [(f(a), f(b)) for a, b in lit]
            length = end if math.isinf(end) else f(end)
            with np.errstate(over="ignore", invalid="ignore", divide="ignore", under="ignore"):
                got = segments.glow(m, f(c.beta), segments.Segment(arr(c.origin), arr(c.direction), length),
                                    arr(c.light), spot_light, lit_v)
            assert np.isfinite(got) and got >= 0.0, (c, lit, got)
            if end == 0.0 or c.beta == 0.0:
                assert got == 0.0, (c, lit, got)


def test_vectorised_lit_intervals():
    """One batch of 500 segments with per-pixel intervals (``segments.lit_from_array``, K = 3) gives what
    each segment gives alone."""
    rng = np.random.default_rng(101)
    m = _ops(0.0)
    beta, origin, direction, light, length = _random_rays(rng, 500)
    cuts = np.sort(rng.uniform(-0.2, 1.2, (500, 6)), axis=1) * length[:, None]
    arr = cuts.reshape(500, 3, 2)[:, rng.permutation(3), :]
    with np.errstate(over="ignore", invalid="ignore"):
        batch = segments.glow(m, beta, segments.Segment(origin, direction, length), light,
                              lit=segments.lit_from_array(arr))
        alone = [float(segments.glow(m, beta[i], segments.Segment(origin[i], direction[i], length[i]), light[i],
                                     lit=segments.lit_from_array(arr[i]))) for i in range(0, 500, 50)]
    np.testing.assert_array_equal(batch[::50], alone)
    assert np.all(np.isfinite(batch)) and np.all(batch >= 0.0)


# --- the ops protocol ---------------------------------------------------------------------------------------

class _Strict:
    """A value that has only what ``ops.ShaderOps`` values have: + - * / (no comparisons, no truth value)."""
    __slots__ = ("v",)

    def __init__(self, v):
        self.v = v

    def _bin(self, other, fn):
        return _Strict(fn(self.v, _raw(other)))

    __add__ = lambda s, o: s._bin(o, lambda a, b: a + b)
    __radd__ = lambda s, o: s._bin(o, lambda a, b: b + a)
    __sub__ = lambda s, o: s._bin(o, lambda a, b: a - b)
    __rsub__ = lambda s, o: s._bin(o, lambda a, b: b - a)
    __mul__ = lambda s, o: s._bin(o, lambda a, b: a * b)
    __rmul__ = lambda s, o: s._bin(o, lambda a, b: b * a)
    __truediv__ = lambda s, o: s._bin(o, lambda a, b: a / b)
    __rtruediv__ = lambda s, o: s._bin(o, lambda a, b: b / a)
    __neg__ = lambda s: _Strict(-s.v)

    def __bool__(self):
        raise TypeError("a kernel value has no truth value in shader nodes or OSL")


def _raw(x):
    if isinstance(x, _Strict):
        return x.v
    if type(x) in (tuple, list):
        return type(x)(_raw(v) for v in x)
    if isinstance(x, (np.ndarray, np.generic)) and not isinstance(x, float):
        raise TypeError(f"a kernel handed a numpy {type(x).__name__} to the ops")
    return x


def _wrap(x):
    return tuple(_wrap(v) for v in x) if isinstance(x, tuple) else _Strict(x)


class StrictOps:
    """The ShaderOps protocol and nothing else, over NumpyOps: a kernel that calls numpy, math or Python
    control flow on its values fails here."""
    _NAMES = ("const", "exp", "sqrt", "sin", "cos", "tan", "mul_add", "floor", "abs", "minimum", "maximum", "atan2",
              "power", "less", "select", "clamp01", "smoothstep", "dot", "cross", "length", "scale", "combine",
              "table")

    def __init__(self, inner):
        self._inner = inner
        self.groups = []
        self.calls = 0   # operations built (a node each, about)

    def __getattr__(self, name):
        if name not in self._NAMES:
            raise AttributeError(f"{name} is not a shader op")
        fn = getattr(self._inner, name)

        def call(*a, **k):
            self.calls += 1
            return _wrap(fn(*(_raw(v) for v in a), **k))
        return call

    def group(self, name, fn, *args):
        self.groups.append(name)
        return fn(self, *args)

    def fori(self, count, body, state, done=None):
        raw = self._inner.fori(count, lambda *s: _raw(body(*_wrap(s))), _raw(tuple(state)),
                               None if done is None else lambda *s: _raw(done(*_wrap(s))))
        return _wrap(tuple(raw))


@pytest.mark.parametrize("quadrature", [False, True])
def test_kernels_use_only_the_ops(quadrature):
    """The point and spot glows with lit intervals, built through ops that offer only ShaderOps, give the
    numpy result bit for bit (so the same source builds as shader nodes and OSL), in named groups."""
    rng = np.random.default_rng(111)
    for is_spot in (False, True):
        c = _case(rng, is_spot)
        lit = [(0.3 * c.length, 0.6 * c.length), (0.1 * c.length, 0.4 * c.length), (1.0, 0.0)]
        strict = StrictOps(_ops(0.0))
        w = lambda v: _Strict(np.asarray(v, float))
        spot_light = None if c.inv is None else Spot(tuple(w(r) for r in c.inv), w(c.cos_half), w(c.blend))
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            got = segments.glow(strict, w(c.beta), segments.Segment(w(c.origin), w(c.direction), w(c.length)),
                                w(c.light), spot_light, [(w(a), w(b)) for a, b in lit], quadrature=quadrature)
        assert float(got.v) == _glow(c, lit, quadrature=quadrature)
        assert any(name.startswith(("Lit Glow [3 intervals", "Spot Lit Glow [3 intervals")) for name in strict.groups)


def test_sky_segment_costs_todays_background():
    """An unshadowed segment to the sky (length the Python inf, known when the shader is built) builds
    today's background kernel (one tail), not the segment kernel at model.FAR (two tails and the short
    segment's quadrature), which gives the same value."""
    rng = np.random.default_rng(121)
    beta, origin, direction, light, _ = _random_rays(rng, 1)
    w = lambda v: _Strict(np.asarray(v, float))
    sky, today = StrictOps(_ops(0.0)), StrictOps(_ops(0.0))
    segments.glow(sky, w(beta), segments.Segment(w(origin), w(direction), math.inf), w(light))
    model.airlight_background(today, w(beta), *model.ray_light_geometry(today, w(origin), w(direction), w(light)))
    assert sky.calls == today.calls
