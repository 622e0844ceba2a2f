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
    lo, la = np.meshgrid(lon, _point_map_latitudes(height))
    return _unit_directions(la, lo)


def _point_map_latitudes(height):
    """The latitudes (rad) of a point light's map's rows, -pi/2 to pi/2."""
    return -0.5 * math.pi + math.pi * np.arange(height) / (height - 1)


def _unit_directions(lat, lon):
    """(..., 3) unit world vectors at latitudes ``lat`` and longitudes ``lon`` (rad, arrays of one shape)."""
    return np.stack([np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon), np.sin(lat)], axis=-1)


def point_map_casts(width=POINT_MAP[0], height=POINT_MAP[1]):
    """(directions (N, 3), fill (height, width) int): the rays that bake a point light's map and, for each grid
    point, the ray whose distance it takes.

    A row at latitude phi is a circle cos(phi) times the equator's, so its ``width`` grid points lie cos(phi) times
    as close as the equator's: it casts ceil(cos(phi) (width - 1)) + 1 rays, evenly in longitude, and each grid
    point takes the nearest of them.  No two neighbouring rays of a row are farther apart than the equator's grid
    points (0.35 degrees), so whatever the map resolves at the equator it resolves at every latitude (the thin
    occluders of ``benchmarks/shafts_stability.py``); the rays are 2/pi of the grid's (334 000 for 524 288)."""
    lat = _point_map_latitudes(height)
    counts = np.ceil(np.cos(lat).clip(0.0, 1.0) * (width - 1) - 1e-9).astype(np.int64).clip(1, width - 1) + 1
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    row = np.repeat(np.arange(height), counts)
    k = np.arange(int(counts.sum())) - starts[row]
    directions = _unit_directions(lat[row], -math.pi + 2.0 * math.pi * k / (counts[row] - 1))
    nearest_ray = np.floor(np.arange(width)[None, :] * ((counts[:, None] - 1) / (width - 1)) + 0.5).astype(np.int64)
    return directions, starts[:, None] + nearest_ray


def point_map_xy(m, u):
    """(x, y) in [0, 1] of the world direction ``u`` (any length) in a point light's map."""
    return point_map_xy_of(m, *(m.dot(u, a) for a in ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))))


def point_map_xy_of(m, ux, uy, uz):
    """``point_map_xy`` of the direction with world components (ux, uy, uz): longitude and latitude over their
    ranges (the quadrature's nodes give the components, so no vector is built)."""
    horizontal = m.sqrt(m.mul_add(ux, ux, uy * uy))
    return (m.mul_add(m.atan2(uy, ux), 0.5 / math.pi, 0.5),
            m.mul_add(m.atan2(uz, horizontal), 1.0 / math.pi, 0.5))


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


# --- an animation's maps: one atlas a light (``shadow_maps.ensure``) ------------------------------------------

ANIMATED_POINT_MAP = (512, 256)   # grid points of a moving point light's map each frame (0.7 deg apart; 4x fewer than
#                                   POINT_MAP: docs/measurements/2026-11-29-animated-shadow-maps.md)
ANIMATED_SPOT_MAP = 256   # grid points across a moving spot's map each frame (over the cones of all its poses)
ATLAS_MAX_FRAMES = 128    # maps an animation's atlas holds at most: a longer range takes every k-th frame
ATLAS_CHANNELS = 4        # maps a texel holds (R, G, B, A: four frames in one slot of the atlas)
ATLAS_MAX_SIDE = 16384    # px: an atlas's side at most (the GPU compositor's textures)
SPOT_UNION_LIMIT = math.radians(75.0)   # a moving spot's poses' cones in one map out to this angle from its axis,
#                                          else it takes a point light's map (the whole sphere)
# the atlas's tile at a frame, a simple expression (no Python: a farm without the add-on evaluates it) of the frame and
# the atlas's first frame s, stride k and tile count n: the latest baked frame at or before it, clamped to the range
ATLAS_TILE = "min(max(floor((frame - s) / k + 0.001), 0), n - 1)"


def atlas_frames(start, end, step, cap=ATLAS_MAX_FRAMES):
    """(first, stride, count): the frames an animation's maps are baked for, start + stride t for t < count, every
    ``step``-th frame of start..end (as a render of the animation takes them), every k-th of those if they are more
    than ``cap`` (stride = k step)."""
    step = max(int(step), 1)
    frames = max((int(end) - int(start)) // step + 1, 1)
    stride = step * math.ceil(frames / cap)
    return int(start), stride, (max(int(end) - int(start), 0)) // stride + 1


def atlas_layout(count, width, height):
    """(columns, rows) of the slots of an atlas of ``count`` maps of width x height grid points, ATLAS_CHANNELS maps
    a slot (one a channel), about as wide as high."""
    slots = max(math.ceil(count / ATLAS_CHANNELS), 1)
    columns = min(max(int(round(math.sqrt(slots * height / width))), 1), slots, max(ATLAS_MAX_SIDE // width, 1))
    return columns, math.ceil(slots / columns)


def atlas_place(tile, columns):
    """(column, row, channel) of the atlas's ``tile`` (the driver's ATLAS_TILE; ``comp_shafts.atlas_tile`` in nodes)."""
    slot, channel = divmod(int(tile), ATLAS_CHANNELS)
    row, column = divmod(slot, columns)
    return column, row, channel


def spot_union(frames, cos_half, limit=SPOT_UNION_LIMIT):
    """(frame, half_width) of one spot map that holds the cone (its map's, ``spot_half_width``) of each of ``frames``
    ((right, up, forward) of the spot's poses, ``spot_frame``): the axis their mean, the half width the widest of the
    cones' edges seen along it (64 directions on each); None if an edge lies beyond ``limit`` from the axis."""
    frames = [tuple(np.asarray(v, float) for v in f) for f in frames]
    forward = np.sum([f[2] for f in frames], axis=0)
    if np.linalg.norm(forward) < 1e-6:
        return None
    forward /= np.linalg.norm(forward)
    up = frames[0][1] - forward * np.dot(frames[0][1], forward)
    if np.linalg.norm(up) < 1e-6:
        up = frames[0][0] - forward * np.dot(frames[0][0], forward)
    up /= np.linalg.norm(up)
    right = np.cross(up, -forward)
    half = spot_half_width(cos_half)
    phi = np.linspace(0.0, 2.0 * math.pi, 64, endpoint=False)
    widest = 0.0
    for r, u, f in frames:
        edge = f + half * (np.cos(phi)[:, None] * r + np.sin(phi)[:, None] * u)
        edge /= np.linalg.norm(edge, axis=1, keepdims=True)
        z = edge @ forward
        if z.min() <= math.cos(limit):
            return None
        widest = max(widest, float(np.max(np.abs(edge @ right) / z)), float(np.max(np.abs(edge @ up) / z)))
    if widest > math.tan(limit):
        return None
    return (tuple(map(float, right)), tuple(map(float, up)), tuple(map(float, forward))), widest * 1.01


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
    return m.floor(m.mul_add(x, n - 1.0, 0.5)) * (1.0 / (n - 1.0))


def lit(m, d, depth):
    """1 where a fog point d m from the light is in front of the first surface, depth m away in its
    direction (less a bias of FOG_BIAS: a lamp 2 cm under a hood lights no fog above it)."""
    return m.less(d, m.mul_add(depth, 1.0 - FOG_BIAS[0], -FOG_BIAS[1]))


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
                  cone=()):
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
    holds them).  ``cone``: as ``lit_share``'s."""
    facing = m.select(m.less(m.dot(normal, viewer - point), 0.0), -1.0, 1.0)
    normal = m.scale(normal, facing)

    def ray(mm, px, py, pz, nx, ny, nz, lx, ly, lz, beta_, r2, phi, shift_, *cone_):   # one direction's integrals
        u = hemisphere_direction(mm, mm.combine(nx, ny, nz), r2, phi)
        return ray_integrals(mm, mm.combine(px, py, pz), u, mm.combine(lx, ly, lz), beta_, shadow, nodes, shift_, g,
                             falloff, name, cone_)
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
              name=None, tail_nodes=0, far=1.0e6, cone=()):
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
    """
    t_c, h, args = _ray_frame(m, camera, direction, light, beta)
    args = args + tuple(cone)
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


def ray_integrals(m, origin, direction, light, beta, shadow, nodes, shift=0.5, g=0.0, falloff=None, name=None,
                  cone=()):
    """(G_H, G) along the whole ray from ``origin`` along the unit ``direction`` (module docstring, to
    infinity), each over beta I0 / 4 pi, in 1/m: (1 / h) int e^{-beta (t + d)} w f (H) d theta by ``nodes``
    equiangular nodes (``lit_share``'s; ``cone`` too)."""
    t_c, h, args = _ray_frame(m, origin, direction, light, beta)
    args = args + tuple(cone)
    theta0 = m.maximum(m.atan2(-1.0 * t_c, h), -MAX_ANGLE)
    step = (MAX_ANGLE - theta0) * (1.0 / nodes)
    lit_sum, total = _quadrature(m, theta0, step, nodes, shift, shadow, g, falloff, name, args)
    scale = step / h
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
        for k in range(count):
            theta = start_ + width_ * (k + shift_)
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


def _hg(m, g, mu):
    """4 pi p_HG(mu) = (1 - g^2) / (1 + g^2 - 2 g mu)^{3/2} (Henyey and Greenstein 1941)."""
    base = (1.0 + g * g) - (2.0 * g) * mu
    return (1.0 - g * g) / (base * m.sqrt(base))


def _hg_of_sine(m, g, sin):
    """``_hg`` at mu = -sin: a quadrature node's scattering angle towards the camera (base in one Multiply Add)."""
    base = m.mul_add(sin, 2.0 * g, 1.0 + g * g)
    return (1.0 - g * g) / (base * m.sqrt(base))


def map_depth(m, spec, spot, u):
    """The map's distance (m) from the light to its first surface in the world direction ``u``: the grid
    point nearest to u in the map ``spec`` (``nearest``); ``spot``: (frame, half_width) of a spot's map, None
    for a point light's."""
    return nearest_depth(m, spec, *(point_map_xy(m, u) if spot is None else spot_map_xy(m, u, *spot)))


def nearest_depth(m, spec, x, y):
    """The map ``spec``'s distance at its grid point nearest to (x, y) in [0, 1] (``nearest``)."""
    return m.table(spec, nearest(m, x, spec.width), nearest(m, y, spec.height))


# --- the sun: an orthographic map and the lit share of its glow in a fog layer ---------------------------

SUN_MAP = 1024        # grid points along the longer side of the sun's map (its cells are square)
SUN_REACH = 6.0       # mean free paths: the sun's map covers the layer this far around the camera (e^-6: 0.25 %)
SUN_BIAS_CELLS = 1.0  # a fog point is lit if nearer the sun than the map's surface less this many cells
MIN_SUN_ELEVATION = 0.02   # sine: the sun's lit-share weights take at least this elevation (a sun on the horizon)


class SunFrame(NamedTuple):
    """Where a sun's map lies (Python floats, world units): grid point (i, j) of a width x height map is the ray
    along ``forward`` (the sunlight's direction, away from the sun) from origin + a right + b up, with
    a = a0 + i (a1 - a0) / (width - 1), b likewise; its value is the distance along ``forward`` from that
    plane to the first surface (NO_HIT if none)."""
    right: tuple
    up: tuple
    forward: tuple
    a: tuple        # (a0, a1): the map's extent along right
    b: tuple        # (b0, b1): along up
    w0: float       # the plane's place along forward (every point of the region lies beyond it)
    bias: float     # units: SUN_BIAS_CELLS cells (a surface's depth changes across a cell at a low sun)


def sun_frame_axes(sun):
    """(right, up, forward) unit world vectors of a sun's map, ``sun`` the unit vector towards the sun: forward =
    -sun, right horizontal (x for a sun straight up)."""
    forward = -np.asarray(sun, float) / np.linalg.norm(sun)
    right = np.cross(forward, (0.0, 0.0, 1.0))
    if np.linalg.norm(right) < 1e-6:
        right = np.array([1.0, 0.0, 0.0])
    right /= np.linalg.norm(right)
    return right, np.cross(right, forward), forward


def sun_frame(sun, points, casters=None, size=SUN_MAP):
    """(SunFrame, (width, height)) of a sun's map over the world ``points`` ((N, 3), the corners of the region whose
    fog the map must cover): their bounding rectangle seen from the sun, cut to that of the ``casters``' corners
    ((M, 3) or None: their shadows fall nowhere else), with square cells, ``size`` grid points along its longer
    side; None where the two do not overlap (no shadow falls in the region)."""
    right, up, forward = sun_frame_axes(sun)
    p = np.asarray(points, float).reshape(-1, 3)
    a, b, w = p @ right, p @ up, p @ forward
    a0, a1, b0, b1 = a.min(), a.max(), b.min(), b.max()
    if casters is not None:
        c = np.asarray(casters, float).reshape(-1, 3)
        a0, a1 = max(a0, (c @ right).min()), min(a1, (c @ right).max())
        b0, b1 = max(b0, (c @ up).min()), min(b1, (c @ up).max())
        w = np.concatenate([w, c @ forward])
        if a0 >= a1 or b0 >= b1:
            return None
    cell = max(a1 - a0, b1 - b0, 1e-6) / (size - 1)
    width = int(min(size, max(2, math.ceil((a1 - a0) / cell) + 1)))
    height = int(min(size, max(2, math.ceil((b1 - b0) / cell) + 1)))
    frame = SunFrame(tuple(map(float, right)), tuple(map(float, up)), tuple(map(float, forward)),
                     (float(a0), float(a0 + cell * (width - 1))), (float(b0), float(b0 + cell * (height - 1))),
                     float(w.min() - cell), SUN_BIAS_CELLS * cell)
    return frame, (width, height)


def sun_map_origins(frame, width, height):
    """(height, width, 3) world points where a sun's map's rays start (``SunFrame``)."""
    a = np.linspace(frame.a[0], frame.a[1], width)
    b = np.linspace(frame.b[0], frame.b[1], height)
    aa, bb = np.meshgrid(a, b)
    return (aa[..., None] * np.asarray(frame.right) + bb[..., None] * np.asarray(frame.up)
            + frame.w0 * np.asarray(frame.forward))


def sun_map_read(m, spec, frame, point):
    """(depth, beyond, inside) of the world ``point`` in a sun's map: the map's distance at its nearest grid point
    (``nearest``), the point's own distance from the map's plane along the sunlight, and 1 where it lies over the
    map (0 outside it)."""
    x = (m.dot(point, frame.right) - frame.a[0]) * (1.0 / (frame.a[1] - frame.a[0]))
    y = (m.dot(point, frame.up) - frame.b[0]) * (1.0 / (frame.b[1] - frame.b[0]))
    depth = nearest_depth(m, spec, x, y)
    inside = m.less(-1e-6, x) * m.less(x, 1.0 + 1e-6) * m.less(-1e-6, y) * m.less(y, 1.0 + 1e-6)
    return depth, m.dot(point, frame.forward) - frame.w0, inside


def sun_lit(m, spec, frame, point):
    """1 where the sun reaches the fog at the world ``point``: nearer the sun than the first surface of its map's
    nearest grid point (less ``frame.bias``); 1 outside the map (nothing there was mapped as casting a shadow)."""
    depth, beyond, inside = sun_map_read(m, spec, frame, point)
    return m.select(inside, m.less(beyond, depth - frame.bias), 1.0)


SUN_SURFACE_SAMPLES = (8, 4)   # directions over a surface's hemisphere x nodes along each (``sun_surface_share``)
SUN_SURFACE_SLOPE = 10.0   # the steepest slope (tan) of a surface within a map cell that ``sun_surface_lit`` allows for


def sun_surface_lit(m, spec, frame, point, normal):
    """1 where the sun reaches the surface at the world ``point`` (unit ``normal``): it is its map cell's first
    surface, its distance along the sunlight within one cell times (1 + the surface's slope to the sunlight, at
    most SUN_SURFACE_SLOPE) of the map's (a surface's depth changes by that across a cell); 1 outside the map.
    What a surface's direct light takes of the sun (``sunlight.direct_dimming``): Cycles and EEVEE shadow the
    sun's light themselves, the factor then weighs the sky's alone."""
    depth, beyond, inside = sun_map_read(m, spec, frame, point)
    c = m.maximum(m.abs(m.dot(normal, frame.forward)), 1.0 / SUN_SURFACE_SLOPE)
    tolerance = (frame.bias / SUN_BIAS_CELLS) * (1.0 + m.sqrt(1.0 - c * c) / c)
    return m.select(inside, m.less(beyond, depth + tolerance), 1.0)


def sun_attenuation_rate(m, beta, vz, mu_s):
    """a (1/unit): the sun's single scattering along a ray of elevation sine ``vz`` inside a layer of extinction
    ``beta`` under a hard top falls as e^{-a t} along it, a = beta (1 - v_z / mu_s) (Dobashi et al. 2002 Eq. 11 in
    one homogeneous species: the camera segment's e^{-beta t} times the sun's e^{-beta (top - z(t)) / mu_s},
    z(t) = z_0 + t v_z), mu_s the sun's elevation sine (at least MIN_SUN_ELEVATION)."""
    return beta * (1.0 - vz / m.maximum(mu_s, MIN_SUN_ELEVATION))


SUN_RATE_CLAMP = 40.0   # |a L| beyond this samples as this (its nodes then crowd at one end either way)


def _rate_length(m, rate_length):
    """(A, flat): A = a L clamped to +-SUN_RATE_CLAMP and 1 in place of |A| < 1e-3, where ``flat`` is 1 (the
    e^{-a t} density is flat there: its formulas' A -> 0 limits apply, no 0/0)."""
    big = m.minimum(m.maximum(rate_length, -SUN_RATE_CLAMP), SUN_RATE_CLAMP)
    flat = m.less(m.abs(big), 1e-3)
    return m.select(flat, 1.0, big), flat


def sun_node_place(m, u, rate_length):
    """t / L of the node at ``u`` in (0, 1) of the density e^{-a t} on [0, L] (A = a L, ``rate_length``): the
    inverse of its distribution, -ln(1 - u (1 - e^{-A})) / A, u itself as A -> 0 (no 0/0)."""
    safe, flat = _rate_length(m, rate_length)
    placed = -1.0 * m.log(1.0 - u * (1.0 - m.exp(-1.0 * safe))) / safe
    return m.select(flat, u, placed)


def sun_lit_share(m, spec, frame, origin, direction, length, rate, nodes, shift=0.5, name=None):
    """S in [0, 1], the share of the sun's single scattering along the segment [0, ``length``] (units) of the ray
    from ``origin`` (unit ``direction``) that reaches it past the shadow casters (Dobashi et al. 2002 Eq. 2's H
    against the sun's map, ``sun_lit``): its e^{-a t} weight (``sun_attenuation_rate``) sampled exactly by
    ``nodes`` nodes placed in its quantiles (``sun_node_place``), so every node weighs alike and
    S = (1 / K) sum_k H(t_k), 1 to the bit where nothing casts a shadow.  ``shift`` in [0, 1): where the nodes sit
    in their quantile strata (``offset`` interleaves them over 2 x 2 pixels).  The layer's falloff above its top
    and the air are left out of the weights: S is exact where H is constant along the ray, whatever the weights.
    ``name``: one node group for every node (it must say all of what a node builds: the map and its frame), or None
    (inline)."""
    def node(mm, ox, oy, oz, dx, dy, dz, length_, a_l, u):
        t = length_ * sun_node_place(mm, u, a_l)
        return sun_lit(mm, spec, frame, mm.combine(ox, oy, oz) + mm.scale(mm.combine(dx, dy, dz), t))
    xyz = [m.dot(v, axis) for v in (origin, direction) for axis in ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))]
    a_l = rate * length
    lit_sum = 0.0
    for k in range(nodes):
        args = (*xyz, length, a_l, (shift + float(k)) * (1.0 / nodes))
        lit_sum = lit_sum + (m.group(name, node, *args) if name else node(m, *args))
    return lit_sum * (1.0 / nodes)


def sun_ray_span(m, point, direction, top_z, ground, reach):
    """Units along the ray from ``point`` (unit ``direction``) to where it leaves the layer between ``ground`` and
    ``top_z`` (z, units), at most ``reach``."""
    z, vz = m.dot(point, (0.0, 0.0, 1.0)), m.dot(direction, (0.0, 0.0, 1.0))
    up = (top_z - z) / m.maximum(vz, 1e-6)
    down = (z - ground) / m.maximum(-1.0 * vz, 1e-6)
    return m.maximum(m.minimum(m.select(m.less(0.0, vz), up, down), reach), 0.0)


def sun_surface_share(m, spec, frame, point, normal, viewer, beta, sun, g, top_z, ground, shift=0.5,
                      directions=SUN_SURFACE_SAMPLES[0], nodes=SUN_SURFACE_SAMPLES[1], name=None):
    """(lit, total): the sun's part of the fog light a diffuse surface ``point`` receives (Sun et al. 2005 Eq. 17's
    G_0 over its hemisphere, weighted cos / pi) with and without the sun's shadows in the fog, whose ratio is the
    share its shadows leave (``surface_share``'s for a lamp).  Along each of ``directions`` cosine-weighted
    directions omega (``hemisphere_angles``, turned by ``shift``) the sun's single scattering in the layer falls as
    e^{-a t} (``sun_attenuation_rate``) up to where the ray leaves the layer (``sun_ray_span``, at most SUN_REACH
    mean free paths): its integral p(omega . s) (1 - e^{-a L}) / a weighs the direction (the sun's transmittance to
    the point, common to all, is left out), and ``sun_lit_share``'s ``nodes`` nodes its lit share.  The rays start
    two map cells off the surface along its normal (its own depth in the map is no shadow).  ``normal`` is turned to
    face ``viewer``; ``sun``: the unit vector towards the sun; ``g``: the Henyey-Greenstein anisotropy (Python
    float); ``name``: one node group per direction."""
    facing = m.select(m.less(m.dot(normal, viewer - point), 0.0), -1.0, 1.0)
    normal = m.scale(normal, facing)
    lift = 2.0 * frame.bias / SUN_BIAS_CELLS

    def ray(mm, px, py, pz, nx, ny, nz, sx, sy, sz, beta_, r2, phi, shift_):
        n, s = mm.combine(nx, ny, nz), mm.combine(sx, sy, sz)
        u = hemisphere_direction(mm, n, r2, phi)
        origin = mm.combine(px, py, pz) + mm.scale(n, lift)
        length = sun_ray_span(mm, origin, u, top_z, ground, SUN_REACH / mm.maximum(beta_, 1e-9))
        rate = sun_attenuation_rate(mm, beta_, mm.dot(u, (0.0, 0.0, 1.0)), mm.dot(s, (0.0, 0.0, 1.0)))
        a_l, flat = _rate_length(mm, rate * length)
        integral = mm.select(flat, length, length * (1.0 - mm.exp(-1.0 * a_l)) / a_l)
        weight = integral * (_hg(mm, g, mm.dot(u, s)) if g else 1.0)
        lit = sun_lit_share(mm, spec, frame, origin, u, length, rate, nodes, shift_)
        return weight * lit, weight
    return hemisphere_sums(m, ray, (point, normal, sun), beta, directions, shift,
                           name and f"{name} Sun Hemisphere Ray {directions}x{nodes}")
