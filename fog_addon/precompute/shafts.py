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

exact when H is constant along the ray.  H_k comes from a shadow map of the light (``point_map_xy``,
``spot_map_xy``): the distance D(u) from the light to the first surface in each direction u, baked by
ray casts from the light (``nodes/shafts.py``); the ray point is lit where d_k < D(u_k) (``lit``).  Biri
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

import numpy as np



class Samples(NamedTuple):
    """How finely a Quality integrates the shafts (``samples_for``)."""
    view_nodes: int           # K: nodes along a pixel's ray (``lit_share``)
    surface_directions: int   # directions over a surface's hemisphere a pixel (``surface_share``)
    surface_nodes: int        # nodes along each


SAMPLES = {"draft": Samples(12, 4, 8), "final": Samples(24, 8, 12), "exact": Samples(48, 12, 16)}
TAIL_SHARE = 4            # the sky past a surface takes K / TAIL_SHARE nodes (``lit_share``)
DEFAULT_SAMPLES = SAMPLES["final"]   # a Quality given as a target error
POINT_MAP = (1024, 512)   # longitude x latitude grid points of a point light's map (0.35 deg apart)
SPOT_MAP = 512            # grid points across a spot's map (its cone plus SPOT_MARGIN)
SPOT_MARGIN = 1.05        # a spot's map spans tan(half angle) x this
NO_HIT = 1.0e30           # m: the map's distance where a direction meets nothing
FOG_BIAS = (0.002, 0.003)   # (relative, m): a fog point is lit if d < D (1 - rel) - abs: contact shadows
MIN_SHARE = 1e-30         # the weights' sum below which S is 1 (no light arrives at all)
MIN_OFFSET = 1e-4         # a ray's distance to the light is at least this share of the camera's (h -> 0: no 0/0)
MAX_ANGLE = 0.5 * math.pi - 1e-3   # rad: the nodes stay this far inside +-pi/2, where cos is 0 in float32
BAYER = (0, 2, 3, 1)      # 2 x 2 ordered-dither ranks, row by row (``offset``)


SAMPLE_LADDER = (SAMPLES["final"], Samples(16, 6, 8), SAMPLES["draft"])   # what many shafted lights step down
BUDGET_LIGHTS = 4   # shafted lights that each take their Quality's own samples (``samples_for``)


def nodes_per_pixel(samples):
    """Quadrature nodes a ``Samples`` evaluates at a pixel for one light: the ray's K, its tail's, the surface's."""
    tail = max(samples.view_nodes // TAIL_SHARE, 2)
    return samples.view_nodes + tail + samples.surface_directions * samples.surface_nodes


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


# --- maps -----------------------------------------------------------------------------------------------

def point_map_directions(width=POINT_MAP[0], height=POINT_MAP[1]):
    """(height, width, 3) unit world directions of a point light's map: grid point (j, i) at longitude
    -pi + 2 pi i / (width - 1), latitude -pi/2 + pi j / (height - 1) (the first and last columns meet at
    the seam, so bilinear lookups need no wrap)."""
    lon = -math.pi + 2.0 * math.pi * np.arange(width) / (width - 1)
    lat = -0.5 * math.pi + math.pi * np.arange(height) / (height - 1)
    lo, la = np.meshgrid(lon, lat)
    return np.stack([np.cos(la) * np.cos(lo), np.cos(la) * np.sin(lo), np.sin(la)], axis=-1)


def point_map_xy(m, u):
    """(x, y) in [0, 1] of the world direction ``u`` (any length) in a point light's map."""
    ux, uy = m.dot(u, (1.0, 0.0, 0.0)), m.dot(u, (0.0, 1.0, 0.0))
    horizontal = m.sqrt(ux * ux + uy * uy)
    x = m.atan2(uy, ux) * (0.5 / math.pi) + 0.5
    y = m.atan2(m.dot(u, (0.0, 0.0, 1.0)), horizontal) * (1.0 / math.pi) + 0.5
    return x, y


def spot_half_width(cos_half):
    """tan of the half angle the spot's map spans (its cone's, times SPOT_MARGIN; at most 89 deg)."""
    half = math.acos(min(max(cos_half, -1.0), 1.0))
    return math.tan(min(half, math.radians(89.0))) * SPOT_MARGIN


def spot_frame(matrix3):
    """(right, up, forward) unit world vectors of a spot whose world 3x3 matrix is ``matrix3`` (its axis,
    ``forward``, is the light's local -Z, as Blender's)."""
    m3 = np.asarray(matrix3, float)
    forward = -m3[:, 2] / max(np.linalg.norm(m3[:, 2]), 1e-30)
    up = m3[:, 1] - forward * np.dot(m3[:, 1], forward)
    up /= max(np.linalg.norm(up), 1e-30)
    return np.cross(up, -forward), up, forward


def spot_map_directions(frame, half_width, size=SPOT_MAP):
    """(size, size, 3) unit world directions of a spot's map: grid point (j, i) looks along forward +
    a right + b up with a, b = half_width (2 i / (size - 1) - 1), (2 j / (size - 1) - 1)."""
    right, up, forward = (np.asarray(v, float) for v in frame)
    a = half_width * (2.0 * np.arange(size) / (size - 1) - 1.0)
    aa, bb = np.meshgrid(a, a)
    d = forward + aa[..., None] * right + bb[..., None] * up
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def spot_map_xy(m, u, frame, half_width):
    """(x, y) in [0, 1] of the world direction ``u`` in a spot's map (clamped at its edges; behind the
    light the lookup is meaningless and the spot's factor is 0 there)."""
    right, up, forward = (tuple(float(c) for c in v) for v in frame)
    z = m.maximum(m.dot(u, forward), 1e-9)
    scale = 0.5 / half_width
    return m.dot(u, right) / z * scale + 0.5, m.dot(u, up) / z * scale + 0.5


def nearest(m, x, n):
    """x in [0, 1] moved to the nearest of n grid points (i / (n - 1)): the map's depths are read, not blended
    across an occluder's silhouette (a blend of a near and a far distance is the distance of nothing)."""
    return m.floor(x * (n - 1.0) + 0.5) * (1.0 / (n - 1.0))


def lit(m, d, depth):
    """1 where a fog point d m from the light is in front of the first surface, depth m away in its
    direction (less a bias of FOG_BIAS: a lamp 2 cm under a hood lights no fog above it)."""
    return m.less(d, depth * (1.0 - FOG_BIAS[0]) - FOG_BIAS[1])


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
                  directions=DEFAULT_SAMPLES.surface_directions, nodes=DEFAULT_SAMPLES.surface_nodes, parts=False):
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
    holds them)."""
    facing = m.select(m.less(m.dot(normal, viewer - point), 0.0), -1.0, 1.0)
    normal = m.scale(normal, facing)

    def ray(mm, px, py, pz, nx, ny, nz, lx, ly, lz, beta_, r2, phi, shift_):   # one direction's two integrals
        u = hemisphere_direction(mm, mm.combine(nx, ny, nz), r2, phi)
        return ray_integrals(mm, mm.combine(px, py, pz), u, mm.combine(lx, ly, lz), beta_, shadow, nodes, shift_, g,
                             falloff, name)
    axes = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
    xyz = [m.dot(v, a) for v in (point, normal, light) for a in axes]
    lit_sum, total = 0.0, 0.0
    for r2, phi in hemisphere_angles(m, directions, shift):
        args = (*xyz, beta, r2, phi, shift)
        lit_j, total_j = m.group(f"{name} Hemisphere Ray {nodes}", ray, *args) if name else ray(m, *args)
        lit_sum, total = lit_sum + lit_j, total + total_j
    return (lit_sum, total) if parts else share_of(lit_sum, total)


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
              name=None, tail_nodes=0, far=1.0e6):
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
    """
    t_c, h, args = _ray_frame(m, camera, direction, light, beta)
    theta_far = m.minimum(m.atan2(far - t_c, h), MAX_ANGLE)
    theta1 = m.minimum(m.atan2(length - t_c, h), theta_far)
    # a segment that ends more than h / 1e-3 before the light lies within MAX_ANGLE of -pi/2: its nodes sit at
    # its end (width 0, S = H there), not between its end and the light
    theta0 = m.minimum(m.maximum(m.atan2(-1.0 * t_c, h), -MAX_ANGLE), theta1)
    step = (theta1 - theta0) * (1.0 / nodes)
    quad = (shadow, g, falloff, name, args)
    lit_sum, total = _quadrature(m, theta0, step, nodes, shift, *quad)
    share = share_of(lit_sum, total)
    if not tail_nodes:
        return share
    tail_step = (theta_far - theta1) * (1.0 / tail_nodes)
    lit_tail, total_tail = _quadrature(m, theta1, tail_step, tail_nodes, shift, *quad)
    return share, share_of(lit_sum * step + lit_tail * tail_step, total * step + total_tail * tail_step)


def ray_integrals(m, origin, direction, light, beta, shadow, nodes, shift=0.5, g=0.0, falloff=None, name=None):
    """(G_H, G) along the whole ray from ``origin`` along the unit ``direction`` (module docstring, to
    infinity), each over beta I0 / 4 pi, in 1/m: (1 / h) int e^{-beta (t + d)} w f (H) d theta by ``nodes``
    equiangular nodes (``lit_share``'s)."""
    t_c, h, args = _ray_frame(m, origin, direction, light, beta)
    theta0 = m.maximum(m.atan2(-1.0 * t_c, h), -MAX_ANGLE)
    step = (MAX_ANGLE - theta0) * (1.0 / nodes)
    lit_sum, total = _quadrature(m, theta0, step, nodes, shift, shadow, g, falloff, name, args)
    scale = step / h
    return lit_sum * scale, total * scale


def _ray_frame(m, origin, direction, light, beta):
    """The light seen from a ray, v = light - origin: t_c (the foot of the perpendicular along the ray), h
    (the ray's distance to the light, at least MIN_OFFSET |v|), and the scalar arguments of ``node_terms``'s
    group (``_quadrature``)."""
    v = light - origin
    t_c = m.dot(v, direction)
    h = m.maximum(m.sqrt(m.dot(v, v) - t_c * t_c), MIN_OFFSET * m.length(v) + 1e-6)
    axes = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
    return t_c, h, (t_c, h, *(m.dot(v, a) for a in axes), *(m.dot(direction, a) for a in axes), beta)


def _quadrature(m, start, width, count, shift, shadow, g, falloff, name, args):
    """(sum of H e_k, sum of e_k) over ``count`` nodes at start + width (k + shift) (``node_terms``), each one
    node group ``name`` (or inline with None)."""
    def terms(mm, theta, t_c, h, vx, vy, vz, dx, dy, dz, beta):
        return node_terms(mm, theta, t_c, h, mm.combine(vx, vy, vz), mm.combine(dx, dy, dz), beta, shadow, g, falloff)

    def nodes(mm, start_, width_, shift_, *args_):
        lit_sum, total = 0.0, 0.0
        for k in range(count):
            theta = start_ + width_ * (k + shift_)
            lit_weight, weight = mm.group(name, terms, theta, *args_) if name else terms(mm, theta, *args_)
            lit_sum = lit_sum + lit_weight
            total = total + weight
        return lit_sum, total
    # with a name, the ``count`` nodes are one group too: a tree's node creation slows as it grows
    return m.group(f"{name} x{count}", nodes, start, width, shift, *args) if name else nodes(m, start, width, shift,
                                                                                            *args)


def node_terms(m, theta, t_c, h, v, direction, beta, shadow, g, falloff):
    """(H weight, weight) of the quadrature node at the angle ``theta`` around the light (``lit_share``): its
    weight e^{-beta (t + d)} w f (the Henyey-Greenstein weight w, the spot's factor f), and that times H,
    1 if the node is lit (``lit``, the map's distance at its grid point, ``map_depth``)."""
    spec, spot = shadow
    sin, cos = m.sin(theta), m.cos(theta)
    t = t_c + h * sin / cos
    d = h / cos
    u = m.scale(direction, t) - v                 # from the light to the ray point
    weight = m.exp(-1.0 * beta * (t + d))
    if g:   # the scattering angle towards the camera has cosine -sin(theta)
        weight = weight * _hg(m, g, -1.0 * sin)
    if falloff is not None:
        weight = weight * falloff(m, u, d)
    return weight * lit(m, d, map_depth(m, spec, spot, u)), weight


def _hg(m, g, mu):
    """4 pi p_HG(mu) = (1 - g^2) / (1 + g^2 - 2 g mu)^{3/2} (Henyey and Greenstein 1941)."""
    base = (1.0 + g * g) - (2.0 * g) * mu
    return (1.0 - g * g) / (base * m.sqrt(base))


def map_depth(m, spec, spot, u):
    """The map's distance (m) from the light to its first surface in the world direction ``u``: the grid
    point nearest to u in the map ``spec`` (``nearest``); ``spot``: (frame, half_width) of a spot's map, None
    for a point light's."""
    x, y = point_map_xy(m, u) if spot is None else spot_map_xy(m, u, *spot)
    return m.table(spec, nearest(m, x, spec.width), nearest(m, y, spec.height))
