"""Light shafts: the share of a light's glow along a camera ray that the light reaches, from a shadow map.

The glow of a light along a ray segment [0, L] (Sun et al. 2005 Eq. 5) with the visibility function H of
Dobashi, Yamamoto and Nishita 2002 (Eq. 2: H = 1 where the light reaches the point, 0 behind an occluder) is

    G_H = int_0^L H(t) f(t) w(t) e^{-beta (t + d(t))} / d(t)^2 dt      (times beta I0 / 4 pi)

with d(t) the distance from the ray point to the light, w the Henyey-Greenstein weight and f a spot's
factor.  The fog computes G (H = 1) exactly with its kernels; shafts multiply it by the lit share

    S = G_H / G  in [0, 1],

which is 1 wherever nothing stands in the light's way, so an open scene keeps its exact glow to the bit.

**The lit share by quadrature in the angle around the light.**  With h the ray's distance to the light and
t = t_c + h tan(theta) (t_c: the foot of the perpendicular), dt / d^2 = d(theta) / h: in theta the
integrand's 1/d^2 peak is flat (the substitution of Sun et al. 2005 Eq. 6; Kulla and Fajardo 2012 sample
it as "equiangular").  The rest of the integrand, e^{-beta (t + d)} w f, is smooth in theta, so K midpoint
nodes theta_k over [theta_0, theta_L] integrate numerator and denominator alike:

    S ~ sum_k H_k e_k / sum_k e_k,   e_k = e^{-beta (t_k + d_k)} w_k f_k,

exact when H is constant along the ray.  H_k comes from a shadow map of the light (``shaft_maps.py``: ``point_map_xy``,
``spot_map_xy``): the distance D(u) from the light to the first surface in each direction u, baked by
ray casts from the light (``shadow_maps.py``); the ray point is lit where d_k < D(u_k) (``lit``).  Biri
2006 §III.D sums the primitive over lit segments found from shadow volumes; here the K nodes find them.

**Interleaved nodes.**  The nodes of neighbouring pixels are offset by a fixed 2 x 2 pattern (``offset``,
Keller and Heidrich 2001, "Interleaved sampling"): 4 pixels together hold 4 K nodes, and a depth-aware
filter that weighs each rank of the pattern alike (the compositor's ``_interleave_mean``) averages them.
Without it a shaft's edge moves node by node as the camera moves: S steps by 1/K between neighbouring
pixels (banding) and between frames (flicker).  The pattern is fixed to the picture and the map to the
world, so nothing is random: no noise.  A surface's share (``surface_share``) interleaves its directions
over a 4 x 4 pattern (``surface_offset``) the same way.

Every function takes an ops namespace ``m`` first (``ops.py``): numpy, the compositor's nodes.
"""
import math
from typing import NamedTuple

from ..point.model import FAR
from ..spot import spot as spot_
from . import shaft_maps
from .shaft_maps import lit, map_depth, nearest_depth, point_map_xy_of


class Samples(NamedTuple):
    """How finely a Quality integrates the shafts (``samples_for``)."""
    view_nodes: int           # K: nodes along a pixel's ray (``lit_share``)
    surface_directions: int   # directions over a surface's hemisphere a pixel (``surface_share``)
    surface_nodes: int        # nodes along each


SAMPLES = {"draft": Samples(12, 4, 8), "final": Samples(24, 8, 12), "exact": Samples(48, 12, 16)}
TAIL_SHARE = 4            # the sky past a surface takes K / TAIL_SHARE nodes (``lit_share``)
DEFAULT_SAMPLES = SAMPLES["final"]   # a Quality given as a target error
MIN_SHARE = 1e-30         # the weights' sum below which S is 1 (no light arrives at all)
MIN_OFFSET = 1e-4         # a ray's distance to the light is at least this share of the camera's (h -> 0: no 0/0)
MAX_ANGLE = 0.5 * math.pi - 1e-3   # rad: the nodes stay this far inside +-pi/2, where cos is 0 in float32
NEAREST_RAY = 0.1         # a surface's ray is weighed as passing the light at least this share of its distance
#                           from it (rad, about: ``ray_integrals``)
BAYER = (0, 2, 3, 1)      # 2 x 2 ordered-dither ranks, row by row (``offset``)


SAMPLE_LADDER = (SAMPLES["final"], Samples(16, 6, 8), SAMPLES["draft"])   # what many shafted lights step down
BUDGET_LIGHTS = 4   # shafted lights that each take their Quality's own samples (``samples_for``)


def nodes_per_pixel(samples):
    """Quadrature nodes a ``Samples`` evaluates at a pixel for one light: the ray's K, its tail's, the surface's."""
    tail = max(samples.view_nodes // TAIL_SHARE, 2)
    return samples.view_nodes + tail + samples.surface_directions * samples.surface_nodes


SHAFT_LIGHTS = {"draft": 16, "final": 64}   # lights a Quality shafts at most, the most important (``shaft_lights``)


def shaft_lights(quality):
    """How many lights a Quality shafts at most (a target error as Final; None at Exact: all of them).  Each shafted
    light is a shadow map, a shaft group and its quadrature at every pixel: the compositor's memory and time grow
    with them, so a city's far lamps glow unshadowed, and the predicted error counts what their shadows would take
    (``ops/left_out.shadow_fog``)."""
    return None if quality == "exact" else SHAFT_LIGHTS.get(quality, SHAFT_LIGHTS["final"])


def map_budget(quality):
    """Grid points all the still shadow maps hold together at a Quality (``shaft_maps.map_levels``): None (no limit,
    every map full) at Exact, else ``shaft_maps.MAP_BUDGET``."""
    return None if quality == "exact" else shaft_maps.MAP_BUDGET


def samples_for(quality, lights=1):
    """The ``Samples`` of a Quality (``spec.FogSpec.quality``: a preset name, or a target error) for each of
    ``lights`` shafted lights.  The compositor's cost is per pixel and light, so beyond BUDGET_LIGHTS lights
    each light steps down SAMPLE_LADDER until all of them evaluate no more nodes a pixel than BUDGET_LIGHTS
    lights at the Quality's own samples (never below Draft's; Exact never steps).  Each light then holds a
    smaller share of the picture's fog light, so its quadrature error moves the picture less."""
    own = SAMPLES.get(quality, DEFAULT_SAMPLES)
    if quality == "exact" or lights <= BUDGET_LIGHTS:
        return own
    budget = BUDGET_LIGHTS * nodes_per_pixel(own)
    ladder = [s for s in SAMPLE_LADDER if nodes_per_pixel(s) <= nodes_per_pixel(own)]
    return next((s for s in ladder if lights * nodes_per_pixel(s) <= budget), SAMPLES["draft"])

SURFACE_PATTERN_LEVELS = 2   # a surface's directions interleave over 2^2 x 2^2 pixels (``surface_offset``)
GOLDEN_ANGLE = math.pi * (3.0 - math.sqrt(5.0))   # rad: the spiral of ``hemisphere_directions``


def hemisphere_directions(m, normal, count, turn):
    """``count`` unit directions spread over the hemisphere about the unit ``normal`` with density cos / pi,
    each of weight 1 / count in int cos / pi d omega = 1 (``hemisphere_angles``, ``hemisphere_direction``)."""
    return [hemisphere_direction(m, normal, r2, phi) for r2, phi in hemisphere_angles(m, count, turn)]


def hemisphere_angles(m, count, turn):
    """[(sin^2 of the polar angle, azimuth in rad)] of ``count`` directions of density cos / pi: a spiral,
    direction j at sin^2 = (j + s) / count and azimuth j x the golden angle + 2 pi ``turn``.  ``turn`` in
    (0, 1) also sets s, the place in the polar strata: frac(P turn), P = 2^SURFACE_PATTERN_LEVELS, so the
    P x P pixels of ``surface_offset``'s pattern hold P polar places and P azimuths of each direction."""
    places = 2 ** SURFACE_PATTERN_LEVELS
    place = turn * places - m.floor(turn * places)
    return [((place + j) * (1.0 / count), turn * (2.0 * math.pi) + j * GOLDEN_ANGLE) for j in range(count)]


def hemisphere_direction(m, normal, r2, phi):
    """The unit direction at sin^2 of the polar angle ``r2`` and azimuth ``phi`` (rad) about the unit ``normal``
    (its tangent frame: any vector not along it, crossed)."""
    side = m.cross(normal, (0.0, 0.0, 1.0)) + m.cross(normal, (0.0, 1.0, 0.0)) * 0.01
    t1 = m.scale(side, 1.0 / m.maximum(m.length(side), 1e-9))
    t2 = m.cross(normal, t1)
    r = m.sqrt(r2)
    return m.scale(t1, m.cos(phi) * r) + m.scale(t2, m.sin(phi) * r) + m.scale(normal, m.sqrt(1.0 - r2))


def surface_share(m, point, normal, viewer, light, beta, shadow, shift=0.5, g=0.0, falloff=None, name=None,
                  directions=DEFAULT_SAMPLES.surface_directions, nodes=DEFAULT_SAMPLES.surface_nodes, parts=False,
                  cone=(), clip=None):
    """The share of the fog light a diffuse surface ``point`` receives (Sun et al. 2005 Eq. 17's G_0: the
    airlight of every direction over it, weighted cos / pi) that the light's shadows leave:

        V = int cos/pi L_a,H(omega) d omega / int cos/pi L_a(omega) d omega,

    L_a,H the glow along the ray from the point in direction omega to infinity with Dobashi et al. 2002
    Eq. 2's visibility H (``ray_integrals``).  ``directions`` cosine-weighted directions
    (``hemisphere_directions``, turned by ``shift`` so neighbouring pixels' sets interleave) and ``nodes``
    equiangular nodes along each give both integrals from the same nodes, so V is 1 to the bit where
    nothing is in the way and 0 where all the fog over the point is in shadow.  A floor in a wall's shadow
    gets the light of the beam through a window over it, as in the path-traced reference.  The glossy
    term G_n takes the same V: its lobe is a blurred part of the same hemisphere.  ``normal`` is turned to
    face ``viewer`` (the camera).  ``g``, ``falloff``, ``name``: as ``lit_share``.  ``parts``: return the two
    integrals' sums (numerator, denominator), which neighbouring pixels' interleaved sets average before the
    division (a mean of ratios would weigh a set that misses the bright directions as much as one that
    holds them).  ``cone``, ``clip``: as ``lit_share``'s."""
    facing = m.select(m.less(m.dot(normal, viewer - point), 0.0), -1.0, 1.0)
    normal = m.scale(normal, facing)

    def ray(mm, px, py, pz, nx, ny, nz, lx, ly, lz, beta_, r2, phi, shift_, *cone_):   # one direction's integrals
        u = hemisphere_direction(mm, mm.combine(nx, ny, nz), r2, phi)
        return ray_integrals(mm, mm.combine(px, py, pz), u, mm.combine(lx, ly, lz), beta_, shadow, nodes, shift_, g,
                             falloff, name, cone_, clip)
    lit_sum, total = hemisphere_sums(m, ray, (point, normal, light), beta, directions, shift,
                                     name and f"{name} Hemisphere Ray {nodes}", tuple(cone))
    return (lit_sum, total) if parts else share_of(lit_sum, total)


def hemisphere_sums(m, ray, vectors, beta, directions, shift, name=None, extra=()):
    """(sum of lit, sum of total) of ``ray(m, *xyz, beta, r2, phi, shift, *extra)`` over ``directions``
    cosine-weighted directions of ``hemisphere_angles`` turned by ``shift``; xyz: the components of the three
    ``vectors`` (a point, its normal, a third), each direction one node group ``name`` (or inline with None);
    ``extra``: more scalars for ``ray`` (a moving spot's cone: ``lit_share``'s ``cone``)."""
    axes = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
    xyz = [m.dot(v, a) for v in vectors for a in axes]
    lit_sum, total = 0.0, 0.0
    for r2, phi in hemisphere_angles(m, directions, shift):
        args = (*xyz, beta, r2, phi, shift, *extra)
        lit_j, total_j = m.group(name, ray, *args) if name else ray(m, *args)
        lit_sum, total = lit_sum + lit_j, total + total_j
    return lit_sum, total


def share_of(lit_sum, total):
    """lit / total, 1 where nothing arrives at all (both under MIN_SHARE)."""
    return (lit_sum + MIN_SHARE) / (total + MIN_SHARE)


# --- the lit share ------------------------------------------------------------------------------------

def offset(m, pixel_x, pixel_y):
    """The interleaving offset in (0, 1) of the pixel (pixel_x, pixel_y) (whole pixels): its rank in the
    2 x 2 ordered-dither pattern [[0, 2], [3, 1]] (Bayer), plus a half, over 4."""
    return _rank2(m, pixel_x, pixel_y) * 0.25 + 0.125


def surface_offset(m, pixel_x, pixel_y, levels=None):
    """The interleaving offset in (0, 1) of the pixel for ``surface_share``: its rank in the 2^levels square
    Bayer pattern (default SURFACE_PATTERN_LEVELS: 4 x 4), built as Bayer's recursion: the rank in the 2 x 2 of
    (i, j) is the most significant digit (base 4), that of (i // 2, j // 2) the next, ..., plus a half, over
    the pattern's size.  A surface's fog light varies slowly across the picture, so the pixels of a pattern
    share their directions (the compositor's SURFACE_TAPS filter)."""
    levels = SURFACE_PATTERN_LEVELS if levels is None else levels
    rank, x, y = 0.0, pixel_x, pixel_y
    for level in range(levels):
        rank = rank + _rank2(m, x, y) * float(4 ** (levels - 1 - level))
        x, y = m.floor(x * 0.5), m.floor(y * 0.5)
    size = 4 ** levels
    return rank * (1.0 / size) + 0.5 / size


def _rank2(m, pixel_x, pixel_y):
    """The rank of (pixel_x, pixel_y) in the 2 x 2 Bayer pattern (``BAYER``): 2 (i xor j) + j."""
    i = pixel_x - m.floor(pixel_x * 0.5) * 2.0
    j = pixel_y - m.floor(pixel_y * 0.5) * 2.0
    return 2.0 * (i - j) * (i - j) + j


def bayer_rank(i, j):
    """The rank ``offset`` gives pixel (i, j) of the pattern (a reference for the tests)."""
    return BAYER[2 * (j % 2) + (i % 2)]


def bayer_rank_surface(i, j, levels=None):
    """The rank ``surface_offset`` gives pixel (i, j) (a reference for the tests)."""
    levels = SURFACE_PATTERN_LEVELS if levels is None else levels
    return sum(bayer_rank(i >> k, j >> k) * 4 ** (levels - 1 - k) for k in range(levels))


def lit_share(m, camera, direction, length, light, beta, shadow, nodes, shift=0.5, g=0.0, falloff=None,
              name=None, tail_nodes=0, far=1.0e6, cone=(), clip=None):
    """S in [0, 1], the share of the glow along the segment [0, ``length``] m of the ray from ``camera``
    along the unit ``direction`` that the light at ``light`` (world, m) reaches (module docstring).

    ``shadow``: (spec, spot) of the light's map (``map_depth``); ``nodes``: K; ``shift`` in [0, 1): where
    the nodes sit in their strata (0.5: midpoints; ``offset`` interleaves them); ``g``: the
    Henyey-Greenstein anisotropy; ``falloff(m, u, d)``: a spot's factor at the ray point light + u,
    d = |u| (None: a point light).  ``name``: one node group for every node (``node_terms``) that says all
    of what it builds (the map, the spot's frame and cone, g), or None.

    With ``tail_nodes`` > 0, returns (S, S_far): S_far is the share of the whole ray to ``far`` m, its part
    beyond ``length`` integrated by that many more nodes (a pixel that sees both a surface and the sky past
    its edge: the glow to the surface takes S, the glow to the sky S_far).

    ``cone``: scalars the falloff takes after (m, u, d) (a moving spot's driven cone,
    ``comp_shafts.build_shaft_group``), passed into the node groups as their inputs.

    ``clip``: clip(m, *cone) gives a spot's (rows, cos_half) (``cone_interval``): the nodes then cover only the
    part of the ray inside its cone, where its factor is not 0.  A ray that leaves the cone a few metres from the
    camera (a spot shining towards it) holds all its glow there; spread over the whole ray, one node of K would
    hold a third of it.
    """
    t_c, h, args = _ray_frame(m, camera, direction, light, beta)
    args = args + tuple(cone)
    theta_far = m.minimum(m.atan2(far - t_c, h), MAX_ANGLE)
    theta1 = m.minimum(m.atan2(length - t_c, h), theta_far)
    # a segment that ends more than h / 1e-3 before the light lies within MAX_ANGLE of -pi/2: its nodes sit at
    # its end (width 0, S = H there), not between its end and the light
    theta0 = m.minimum(m.maximum(m.atan2(-1.0 * t_c, h), -MAX_ANGLE), theta1)
    start, end, tail_start, tail_end = theta0, theta1, theta1, theta_far
    if clip is not None:   # each segment cut to the cone (width 0 where it misses it: its glow is 0 there)
        inside, outside = _cone_angles(m, camera, direction, light, t_c, h, clip(m, *cone), far)
        start, end = _clipped(m, theta0, theta1, inside, outside)
        tail_start, tail_end = _clipped(m, theta1, theta_far, inside, outside)
    step = (end - start) * (1.0 / nodes)
    quad = (shadow, g, falloff, name, args)
    lit_sum, total = _quadrature(m, start, step, nodes, shift, *quad)
    share = share_of(lit_sum, total)
    if not tail_nodes:
        return share
    tail_step = (tail_end - tail_start) * (1.0 / tail_nodes)
    lit_tail, total_tail = _quadrature(m, tail_start, tail_step, tail_nodes, shift, *quad)
    return share, share_of(lit_sum * step + lit_tail * tail_step, total * step + total_tail * tail_step)


def _clipped(m, start, end, inside, outside):
    """The angles [start, end] cut to [inside, outside] (rad), of width 0 at ``start`` or ``end`` if they miss it."""
    first = m.minimum(m.maximum(start, inside), end)
    return first, m.maximum(m.minimum(end, outside), first)


def _cone_angles(m, origin, direction, light, t_c, h, cone, t_end):
    """The angles around the light (rad, ``lit_share``'s theta) where the ray enters and leaves a spot's
    ``cone`` = (rows, cos_half) within [0, ``t_end``] (``cone_interval``)."""
    return tuple(m.atan2(t - t_c, h) for t in cone_interval(m, origin, direction, light, *cone, t_end))


def cone_interval(m, origin, direction, light, rows, cos_half, t_end):
    """[t_in, t_out] (m, t_in = t_out where it misses it) of the ray origin + t ``direction``, t in [0, ``t_end``],
    inside a spot's cone (``spot.cone_interval``, in the light's space that ``rows`` give: ``spot.light_space``;
    half angle acos(``cos_half``))."""
    p0 = spot_.light_space(m, rows, origin - light)
    d = spot_.light_space(m, rows, direction)
    return spot_.cone_interval(m, p0, d, cos_half, t_end)


def ray_integrals(m, origin, direction, light, beta, shadow, nodes, shift=0.5, g=0.0, falloff=None, name=None,
                  cone=(), clip=None):
    """(G_H, G) along the whole ray from ``origin`` along the unit ``direction`` (module docstring, to
    infinity), each over beta I0 / 4 pi, in 1/m: (1 / h) int e^{-beta (t + d)} w f (H) d theta by ``nodes``
    equiangular nodes (``lit_share``'s; ``cone`` and ``clip`` too).

    Both are weighed as if the ray passed the light no nearer than NEAREST_RAY times the origin's distance to it
    (the nodes stay on the ray).  ``surface_share`` sums them over a few directions, and G grows as 1 / h: a
    direction that happens to pass the light within a few centimetres outweighed a hundred others (187 against
    their median 0.59 on a stairwell's wall 2.5 m from a lamp), and the filter that pools the interleaved
    directions of 5 x 5 pixels spread it into a bright 5 x 5 blob.  The cap leaves out of the weights at most the
    fog within NEAREST_RAY rad of the light's direction beyond its mean there: a few per cent of G, and of V
    only as much as that fog's shadows differ from the rest's."""
    t_c, h, args = _ray_frame(m, origin, direction, light, beta)
    args = args + tuple(cone)
    theta0 = m.maximum(m.atan2(-1.0 * t_c, h), -MAX_ANGLE)
    end = MAX_ANGLE
    if clip is not None:
        inside, outside = _cone_angles(m, origin, direction, light, t_c, h, clip(m, *cone), FAR)
        theta0, end = _clipped(m, theta0, end, inside, outside)
    step = (end - theta0) * (1.0 / nodes)
    lit_sum, total = _quadrature(m, theta0, step, nodes, shift, shadow, g, falloff, name, args)
    scale = step / m.maximum(h, m.length(light - origin) * NEAREST_RAY)
    return lit_sum * scale, total * scale


def _ray_frame(m, origin, direction, light, beta):
    """The light seen from a ray, v = light - origin: t_c (the foot of the perpendicular along the ray), h
    (the ray's distance to the light, at least MIN_OFFSET |v|), and the scalar arguments of ``node_terms``'s
    group (``_quadrature``): t_c, h, the components of -v and of the direction, -beta."""
    v = light - origin
    t_c = m.dot(v, direction)
    h = m.maximum(m.sqrt(m.dot(v, v) - t_c * t_c), MIN_OFFSET * m.length(v) + 1e-6)
    axes = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
    minus = ((-1.0, 0.0, 0.0), (0.0, -1.0, 0.0), (0.0, 0.0, -1.0))
    return t_c, h, (t_c, h, *(m.dot(v, a) for a in minus), *(m.dot(direction, a) for a in axes), beta * -1.0)


def _quadrature(m, start, width, count, shift, shadow, g, falloff, name, args):
    """(sum of H e_k, sum of e_k) over ``count`` nodes at start + width (k + shift) (``node_terms``), each one
    node group ``name`` (or inline with None)."""
    def terms(mm, theta, t_c, h, ox, oy, oz, dx, dy, dz, minus_beta, *cone):
        bound = falloff if not cone else (lambda m_, u_, d_: falloff(m_, u_, d_, *cone))
        return node_terms(mm, theta, t_c, h, (ox, oy, oz), (dx, dy, dz), minus_beta, shadow, g, bound)

    def nodes(mm, start_, width_, shift_, *args_):
        lit_sum, total = 0.0, 0.0
        first = start_ + width_ * shift_   # the first node; the others a whole width apart
        for k in range(count):
            theta = first + width_ * k if k else first
            lit_weight, weight = mm.group(name, terms, theta, *args_) if name else terms(mm, theta, *args_)
            lit_sum = lit_sum + lit_weight
            total = total + weight
        return lit_sum, total
    # with a name, the ``count`` nodes are one group too: a tree's node creation slows as it grows
    return m.group(f"{name} x{count}", nodes, start, width, shift, *args) if name else nodes(m, start, width, shift,
                                                                                            *args)


def node_terms(m, theta, t_c, h, offset, direction, minus_beta, shadow, g, falloff):
    """(H weight, weight) of the quadrature node at the angle ``theta`` around the light (``lit_share``): its
    weight e^{-beta (t + d)} w f (the Henyey-Greenstein weight w, the spot's factor f), and that times H,
    1 if the node is lit (``lit``, the map's distance at its grid point, ``map_depth``).

    ``offset`` and ``direction`` are the world components of origin - light and of the ray's direction, and
    ``minus_beta`` is -beta: the compositor evaluates this for every node of every pixel, so it works on
    components (u, from the light to the ray point, is three Multiply Add nodes) and folds what it can into them."""
    spec, spot = shadow
    sin, cos = m.sin(theta), m.cos(theta)
    d = h / cos
    t = m.mul_add(sin, d, t_c)                    # t_c + h tan(theta)
    u = [m.mul_add(c, t, o) for c, o in zip(direction, offset)]   # from the light to the ray point
    weight = m.exp((t + d) * minus_beta)
    if g:   # the scattering angle towards the camera has cosine -sin(theta)
        weight = weight * _hg_of_sine(m, g, sin)
    if spot is None and falloff is None:
        depth = nearest_depth(m, spec, *point_map_xy_of(m, *u))
    else:
        u = m.combine(*u)
        depth = map_depth(m, spec, spot, u)
        if falloff is not None:
            weight = weight * falloff(m, u, d)
    return weight * lit(m, d, depth), weight


def _hg_of_sine(m, g, sin):
    """``sun_shafts._hg`` at mu = -sin: a quadrature node's scattering angle towards the camera (base in one
    Multiply Add)."""
    base = m.mul_add(sin, 2.0 * g, 1.0 + g * g)
    return (1.0 - g * g) / (base * m.sqrt(base))
