"""Light shafts' shadow maps: where each grid point of a light's map looks, and the lookups of a direction in it.

A map holds D(u), the distance from the light to the first surface in each direction u, baked by ray casts from the
light (``shadow_maps.py``): a longitude-latitude grid for a point light (``point_map_directions``, its rows' rays
thinned towards the poles by ``point_map_casts``), a square grid over a spot's cone (``spot_map_directions``).  A moving
light's maps, one a frame, are packed four to a texel in an atlas (``atlas_frames``, ``atlas_layout``,
``atlas_place``); a moving spot's poses share one map that holds all their cones (``spot_union``).  A fog point is lit where it lies nearer the
light than the map's surface at its grid point (``lit``, ``map_depth``): the visibility H of the lit shares
(``shafts.py``, ``sun_shafts.py``).

Every lookup takes an ops namespace ``m`` first (``ops.py``): numpy, the compositor's nodes.
"""
import math

import numpy as np


POINT_MAP = (1024, 512)   # longitude x latitude grid points of a point light's map (0.35 deg apart)
SPOT_MAP = 512            # grid points across a spot's map (its cone plus SPOT_MARGIN)
SPOT_MARGIN = 1.05        # a spot's map spans tan(half angle) x this
NO_HIT = 1.0e30           # m: the map's distance where a direction meets nothing
FOG_BIAS = (0.002, 0.003)   # (relative, m): a fog point is lit if d < D (1 - rel) - abs: contact shadows


MAP_BUDGET = 16 * POINT_MAP[0] * POINT_MAP[1]   # grid points of all the still maps together (8.4 M: 134 MB as the
#                                                 float images Blender holds, 16 bytes a point), beyond which they shrink
# the largest growth of a shaft scene's relative RMSE against path tracing when its lights' maps took level 0, 1, 2, 3
# (docs/measurements/2026-12-01-city-night.md: colonnade, window room, hooded lamp, street lamps): a shrunk map's
# error, as a share of its light's glow, in the predicted error (``shadow_maps.map_level_error``)
MAP_LEVEL_ERROR = (0.0, 0.001, 0.003, 0.007)
SMALLEST_LEVEL = 3        # a map halves across at most this many times (a point light's 128 x 64: 2.8 deg a point; at
#                           64 x 32 the shaft scenes were 8-10 % off path tracing: docs/measurements/2026-12-01-city-night.md)


# --- maps -----------------------------------------------------------------------------------------------

def map_grid(spot, level=0):
    """(width, height) grid points of a light's still map ``level`` times halved across: a point light's POINT_MAP,
    a spot's SPOT_MAP square (``spot``: True)."""
    full = (SPOT_MAP, SPOT_MAP) if spot else POINT_MAP
    return tuple(max(n >> int(level), 2) for n in full)


def map_levels(weights, spots, budget=MAP_BUDGET, smallest=SMALLEST_LEVEL):
    """(N,) int: how many times each still map halves across (its grid points a quarter at each level), so that
    all of them hold at most ``budget`` grid points (``map_grid``), none below level ``smallest``.

    ``weights`` (N,): each light's share of the picture's fog, up to a factor (``sampling.importance``);
    ``spots`` (N,) bool: a spot's map (else a point light's).  A shadow's edge in the fog moves by up to a
    grid point's angle, which goes as t^(-1/2) for a map of t points, and what that moves in the picture goes as
    the light's weight w: the sum of w t^(-1/2) is least, for t's summing to the budget, where t goes as
    w^(2/3) (Lagrange).  So t = c w^(2/3) between the smallest and the full map, c found by bisection to fill the
    budget, and each map takes the first level at or below its t (the levels' totals stay within the budget unless
    the smallest maps alone exceed it); what rounding down leaves of the budget takes the heaviest maps a level up.  Every map is full where the
    full maps fit."""
    w = np.maximum(np.nan_to_num(np.asarray(weights, float), nan=0.0), 0.0)
    full = np.array([float(np.prod(map_grid(s))) for s in spots]).reshape(w.shape)
    if full.sum() <= budget or not len(w):
        return np.zeros(len(w), int)
    share = w ** (2.0 / 3.0)
    if share.max() <= 0.0:
        share = np.ones_like(w)
    least = full / 4.0 ** smallest
    lo, hi = 0.0, float(full.max() / share[share > 0].min())
    for _ in range(64):
        c = 0.5 * (lo + hi)
        lo, hi = (c, hi) if np.clip(c * share, least, full).sum() < budget else (lo, c)
    t = np.clip(lo * share, least, full)
    levels = np.clip(np.ceil(np.log2(full / t) / 2.0 - 1e-9), 0, smallest).astype(int)
    points = full / 4.0 ** levels
    for i in np.argsort(-w, kind="stable"):   # what rounding down left of the budget: the heaviest maps a level up
        while levels[i] > 0 and points.sum() + 3.0 * points[i] <= budget:
            levels[i] -= 1
            points[i] *= 4.0
    return levels


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


def map_depth(m, spec, spot, u):
    """The map's distance (m) from the light to its first surface in the world direction ``u``: the grid
    point nearest to u in the map ``spec`` (``nearest``); ``spot``: (frame, half_width) of a spot's map, None
    for a point light's."""
    return nearest_depth(m, spec, *(point_map_xy(m, u) if spot is None else spot_map_xy(m, u, *spot)))


def nearest_depth(m, spec, x, y):
    """The map ``spec``'s distance at its grid point nearest to (x, y) in [0, 1] (``nearest``)."""
    return m.table(spec, nearest(m, x, spec.width), nearest(m, y, spec.height), nearest=True)
