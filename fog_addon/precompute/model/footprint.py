"""Where in the picture a term of the fog can be non-zero: the windows the Compositor method crops to.

Blender's compositor evaluates a node over every pixel of its input's domain, and a Crop node makes that
domain smaller (``nodes/comp_fog.py``).  Two terms have a support smaller than the picture:

* a spot's glow (Sun et al. 2005 Eq. 11-12 on the part of the ray inside the cone, ``spot.airlight``) is
  0 on every pixel whose ray misses the cone.  The cone is cut ``GLOW_RADIUS`` from the light: a ray that
  meets it only beyond gets at most 2 beta p_max e^{-beta R} / (4 pi R) per unit intensity (the line's
  integral of 1 / r^2 where r >= R is at most 2 / R; p_max = (1 + g) / (1 - g)^2 <= 780 the phase
  function's peak), 1.2e-4 beta e^{-beta R} with R = 1e6 m: nothing a pixel shows at any density.  So the
  window does not depend on the fog's density;
* the fog light surfaces reflect (Eq. 17-18) is needed only where a surface is.

A spot's glow window also heeds **occluders**: flat convex polygons that every camera ray meeting them ends on
(``occluded_window``; ``view.py`` finds them: opaque fogged faces, or the outline of a flat mesh that
tiles a convex region (``flat_outline``), in a picture where every surface is fogged). The glow integrates a
ray only up to its surface, so the part of the cone beyond such a face's plane is seen only by pixels whose
rays pass beside the face; a spot aimed at a floor is then cropped to the cone above the floor (issue 9's 64
spots: 38 % of the picture a spot on average, 10 % with the floor). A pixel's compositor fog mixes in the glow
of its centre ray to the sky where the pixel is partly covered, so the face's picture is first shrunk by
``margin`` (a few pixels: the pixel filter's reach).

A window is the bounding box (u0, u1, v0, v1) in normalised picture coordinates (0 at the left and bottom
edges of the camera's frame, 1 at the right and top) of the projection of a convex set: exact for the
convex hull of the points it is given.  Points behind the camera's near plane are clipped away; what
crosses it projects to the picture's border.  Pure numpy: matrices in, windows out.
"""
import math

import numpy as np

GLOW_RADIUS = 1e6     # m: where a spot's cone is cut (module docstring)
HULL_SIDES = 16       # sides of the polygon about the cone's axis (circumscribed: it contains the circle)
NEAR = 1e-6           # m: points nearer the camera's plane than this count as behind it
FULL = (0.0, 1.0, 0.0, 1.0)
EMPTY = (0.0, 0.0, 0.0, 0.0)


def cone_hull(cos_half, radius, sides=HULL_SIDES):
    """(2 sides + 1, 3) points in the light's space whose convex hull contains the spot's cone (cos of the
    angle from -Z at least ``cos_half`` >= 0, half-angle <= 90 degrees) within ``radius`` of its apex: the
    apex; a polygon at depth radius cos(half) about the axis, circumscribing the circle of radius
    radius sin(half) (up to that depth the cone is inside the pyramid on it); the same polygon at depth
    ``radius`` (beyond, the cut cone lies within radius sin(half) of the axis)."""
    sin_half = np.sqrt(max(0.0, 1.0 - cos_half * cos_half))
    angle = 2.0 * np.pi * np.arange(sides) / sides
    ring = np.stack([np.cos(angle), np.sin(angle), np.zeros(sides)], axis=1) * (
        radius * sin_half / np.cos(np.pi / sides))
    near, far = ring - [0.0, 0.0, radius * cos_half], ring - [0.0, 0.0, radius]
    return np.concatenate([np.zeros((1, 3)), near, far])


def cone_edges(sides=HULL_SIDES):
    """(4 sides, 2) indices into :func:`cone_hull`'s points of its polytope's edges: apex to the near polygon,
    around it, from it to the far polygon, around that."""
    k = np.arange(sides)
    near, far, nxt = 1 + k, 1 + sides + k, 1 + (k + 1) % sides
    return np.concatenate([np.stack([np.zeros(sides, int), near], 1), np.stack([near, nxt], 1),
                           np.stack([near, far], 1), np.stack([far, nxt + sides], 1)])


CONE_EDGES = cone_edges()


def spot_points(matrix, cos_half):
    """World points (m) whose convex hull contains a spot's cone up to GLOW_RADIUS from the light.

    matrix: the light's 4x4 world matrix (its 3x3 may scale the cone non-uniformly: Blender's falloff
    follows the light-space direction, ``spot.light_space``)."""
    m = np.asarray(matrix, float)
    shrink = np.linalg.svd(m[:3, :3], compute_uv=False).min()   # world distance >= shrink * light-space distance
    hull = cone_hull(cos_half, GLOW_RADIUS / max(shrink, 1e-30))
    return hull @ m[:3, :3].T + m[:3, 3]


def box_points(bound_box, matrix):
    """(8, 3) world corners of an object's local bounding box (Blender's ``Object.bound_box``)."""
    m = np.asarray(matrix, float)
    return np.asarray(bound_box, float) @ m[:3, :3].T + m[:3, 3]


def _corner_bounds(corners, camera_matrix, frame):
    """(front, crossing, (lo_u, hi_u, lo_v, hi_v)) of boxes (M, 8, 3 world corners): which lie wholly in front
    of the camera's plane, which cross it, and the bounds of their corners projected on the picture (normalised
    picture units, not clipped; meaningful for the boxes in front)."""
    local = _local(corners, camera_matrix).reshape(-1, 8, 3)
    depth = -local[..., 2]
    front = (depth >= NEAR).all(axis=1)
    crossing = (depth >= NEAR).any(axis=1) & ~front
    z = np.maximum(depth, NEAR)
    left, right, bottom, top = frame
    u = (local[..., 0] / z - left) / (right - left)
    v = (local[..., 1] / z - bottom) / (top - bottom)
    return front, crossing, (u.min(axis=1), u.max(axis=1), v.min(axis=1), v.max(axis=1))


def boxes_window(corners, camera_matrix, frame):
    """The union of the windows of boxes (M, 8, 3 world corners, ``box_points``): at once for the boxes wholly
    in front of the camera (the bounding box of their projected corners, within the window of each hull,
    skipped if outside the frame), by :func:`window` for those crossing the camera's plane."""
    front, crossing, bounds = _corner_bounds(corners, camera_matrix, frame)
    lo_u, hi_u, lo_v, hi_v = (b[front] for b in bounds)
    seen = (hi_u >= 0.0) & (lo_u <= 1.0) & (hi_v >= 0.0) & (lo_v <= 1.0)
    out = EMPTY
    if seen.any():
        out = tuple(float(np.clip(x, 0.0, 1.0)) for x in (lo_u[seen].min(), hi_u[seen].max(),
                                                            lo_v[seen].min(), hi_v[seen].max()))
    for box in np.asarray(corners, float).reshape(-1, 8, 3)[crossing]:
        out = union(out, window(box, camera_matrix, frame))
    return out


def clip_depth(clip_end, frame):
    """The depth (m) within which every ray of the picture is shorter than ``clip_end``: clip_end times the
    cosine of the frame's widest ray (the clip end as a depth or as a distance along the ray alike)."""
    left, right, bottom, top = frame
    return clip_end / math.sqrt(1.0 + max(left * left, right * right) + max(bottom * bottom, top * top))


def boxes_areas(corners, camera_matrix, frame):
    """(M,) share of the picture each box (M, 8, 3 world corners, ``box_points``) covers at most: the bounding
    box of its projected corners within the picture, 1 for a box crossing the camera's plane, 0 behind it.
    For ranking (``view.py`` searches the largest for occluders)."""
    front, crossing, bounds = _corner_bounds(corners, camera_matrix, frame)
    lo_u, hi_u, lo_v, hi_v = (np.clip(b, 0.0, 1.0) for b in bounds)
    return np.where(front, (hi_u - lo_u) * (hi_v - lo_v), np.where(crossing, 1.0, 0.0))


def window(points, camera_matrix, frame):
    """The window of the convex hull of ``points`` (N, 3, world m) seen by a perspective camera.

    camera_matrix: its 4x4 world matrix (it looks along its local -Z); frame: (left, right, bottom, top)
    of its frame at unit distance (``Camera.view_frame`` divided by its depth; shifts included).
    Returns (u0, u1, v0, v1) within [0, 1], EMPTY if all of it is behind the camera.
    """
    return _bounds(picture_hull(_local(points, camera_matrix), None, frame))


def _local(points, camera_matrix):
    """``points`` (N, 3 world) in the camera's axes, the camera at the origin (its axes are orthonormal)."""
    cam = np.asarray(camera_matrix, float)
    return (np.asarray(points, float).reshape(-1, 3) - cam[:3, 3]) @ cam[:3, :3]


def clip_hull(points, normal, offset):
    """(M, D) points whose convex hull is the convex hull of ``points`` (N, D) cut to normal . x >= offset:
    the points on that side, and where the segments between any two of them cross the plane (every edge of
    the hull is such a segment, and every segment lies in it)."""
    pts = np.asarray(points, float).reshape(-1, len(normal))
    side = pts @ np.asarray(normal, float) - offset
    i, j = np.triu_indices(len(pts), 1)
    crossing = side[i] * side[j] < 0.0
    t = side[i[crossing]] / (side[i[crossing]] - side[j[crossing]])
    cut = pts[i[crossing]] + t[:, None] * (pts[j[crossing]] - pts[i[crossing]])
    return np.concatenate([pts[side >= 0.0], cut])


def clip_polytope(points, edges, normal, offset):
    """(points, edges) of the convex polytope with corners ``points`` (N, 3) and ``edges`` (E, 2 indices)
    cut to normal . x >= offset: its corners on that side, where its edges cross the plane, and the edges
    of the cut face (those crossings in order about their centre).  ``edges`` None: the hull of the points
    by :func:`clip_hull` (every pair; as many points as pairs cross, so only for few points)."""
    if edges is None:
        return clip_hull(points, normal, offset), None
    pts, normal = np.asarray(points, float), np.asarray(normal, float)
    side = pts @ normal - offset
    keep = side >= 0.0
    index = np.cumsum(keep) - 1
    a, b = np.asarray(edges, int).T
    both, crossing = keep[a] & keep[b], keep[a] != keep[b]
    inner = np.where(keep[a[crossing]], a[crossing], b[crossing])
    outer = np.where(keep[a[crossing]], b[crossing], a[crossing])
    t = side[inner] / (side[inner] - side[outer])
    out = np.concatenate([pts[keep], pts[inner] + t[:, None] * (pts[outer] - pts[inner])])
    cut = int(keep.sum()) + np.arange(len(inner))
    links = [np.stack([index[a[both]], index[b[both]]], 1), np.stack([index[inner], cut], 1)]
    face = np.concatenate([cut, index[keep & (side == 0.0)]])
    if len(face) >= 2:
        axis = np.eye(3)[np.argmin(np.abs(normal))]
        u = np.cross(normal, axis)
        v = np.cross(normal, u)
        rel = out[face] - out[face].mean(axis=0)
        ring = face[np.argsort(np.arctan2(rel @ v, rel @ u))]
        links.append(np.stack([ring, np.roll(ring, -1)], 1)[:len(ring) if len(ring) > 2 else 1])
    return out, np.concatenate(links).reshape(-1, 2)


def picture_hull(local, edges, frame, near=NEAR):
    """(K, 2) corners, counter-clockwise, of the projection of the convex polytope (``clip_polytope``:
    ``local`` its corners in the camera's axes, as ``_local``) cut to depth >= ``near``, in normalised picture
    coordinates (not clipped to the picture)."""
    front, _ = clip_polytope(local, edges, (0.0, 0.0, -1.0), near)
    if not len(front):
        return np.zeros((0, 2))
    z = np.maximum(-front[:, 2], near)
    left, right, bottom, top = frame
    return convex_hull_2d(np.stack([(front[:, 0] / z - left) / (right - left),
                                    (front[:, 1] / z - bottom) / (top - bottom)], axis=1))


def _bounds(polygon):
    """The window of a picture polygon: the bounding box of its part in the picture, EMPTY if none."""
    inside = clip_to_unit_square(polygon) if len(polygon) else polygon
    if not len(inside):
        return EMPTY
    lo, hi = np.clip(inside.min(axis=0), 0.0, 1.0), np.clip(inside.max(axis=0), 0.0, 1.0)
    return float(lo[0]), float(hi[0]), float(lo[1]), float(hi[1])


def occluded_window(points, occluder, camera_matrix, frame, margin, near=NEAR, edges=None, far=math.inf):
    """The window of the convex polytope with corners ``points`` (N, 3 world m) and ``edges`` (``clip_polytope``;
    ``CONE_EDGES`` for ``spot_points``) where the camera sees it past ``occluder``: a flat convex polygon (K, 3
    world m, its corners in order) that ends every camera ray meeting it at a depth from ``near`` (the
    camera's clip start) to ``far`` (``clip_depth``: where no ray of the picture has reached its clip end)
    (module docstring).

    What lies on the camera's side of the occluder's plane keeps its window; what lies beyond is seen only
    outside the occluder's picture shrunk by ``margin`` = (mu, mv) (normalised picture units): that picture
    minus the shrunk polygon is the union, over its edges, of the part beyond each edge's line.  Without a
    plane (a degenerate polygon, or the camera in its plane) or a picture, the plain :func:`window`."""
    local, poly = _local(points, camera_matrix), _local(occluder, camera_matrix)
    normal = np.sum(np.cross(poly, np.roll(poly, -1, axis=0)), axis=0)   # Newell's normal
    size, extent = np.linalg.norm(normal), float(np.abs(poly).max())
    offset = float(normal @ poly.mean(axis=0)) / max(size, 1e-300)
    seen = clip_polygon(clip_polygon(poly, (0.0, 0.0, -1.0), near), (0.0, 0.0, 1.0), -far)
    shade = picture_hull(seen, None, frame) if len(seen) else seen
    if size <= 1e-12 * max(extent * extent, 1e-300) or abs(offset) <= 1e-9 * extent or len(shade) < 3:
        return _bounds(picture_hull(local, edges, frame))
    toward = -np.sign(offset) * normal / size   # the camera (the origin) is on the side toward . x >= level
    level = float(toward @ poly[0])
    out = _bounds(picture_hull(*clip_polytope(local, edges, toward, level), frame))
    beyond = picture_hull(*clip_polytope(local, edges, -toward, -level), frame)
    if not len(beyond):
        return out
    scale = 1.0 / np.asarray(margin, float)   # in units of the margin, the shrinking is by 1 along each normal
    shade, beyond = shade * scale, beyond * scale
    for a, b in zip(shade, np.roll(shade, -1, axis=0)):
        edge = b - a
        outward = np.array([edge[1], -edge[0]]) / max(np.linalg.norm(edge), 1e-300)   # counter-clockwise corners
        piece = clip_polygon(beyond, outward, float(outward @ a) - 1.0)
        out = union(out, _bounds(piece / scale) if len(piece) else EMPTY)
    return out


def flat_outline(points, area, tolerance=1e-6):
    """(K, 3) corners, in order, of the convex polygon that a mesh's faces tile when they are flat and
    without holes (a floor of many faces), else None: ``points`` (N, 3) their corners, ``area`` the sum of
    their areas (m^2).  Every corner within ``tolerance`` of the mean plane (relative to the extent), and the
    faces' areas summing to the area of the corners' convex hull within ``tolerance``: the faces lie in
    the hull, so they cover it (the hull is convex) but for overlaps exactly as large as holes."""
    pts = np.asarray(points, float).reshape(-1, 3)
    if len(pts) < 3 or area <= 0.0:
        return None
    centre = pts.mean(axis=0)
    _, sv, vt = np.linalg.svd(pts - centre, full_matrices=False)
    extent = float(sv[0]) / math.sqrt(len(pts)) + 1e-300
    if np.abs((pts - centre) @ vt[2]).max() > tolerance * max(extent, np.abs(pts - centre).max()):
        return None
    hull = convex_hull_2d((pts - centre) @ vt[:2].T)
    if len(hull) < 3:
        return None
    x, y = hull[:, 0], hull[:, 1]
    hull_area = 0.5 * abs(float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)))
    if abs(hull_area - area) > tolerance * hull_area:
        return None
    return centre + hull @ vt[:2]


def convex_hull_2d(points):
    """(K, 2) corners of the convex hull of (N, 2) points, counter-clockwise (Andrew's monotone chain)."""
    pts = [tuple(p) for p in np.unique(np.asarray(points, float), axis=0).tolist()]
    if len(pts) < 3:
        return np.array(pts).reshape(-1, 2)

    def chain(seq):
        out = []
        for x, y in seq:
            while len(out) >= 2 and ((out[-1][0] - out[-2][0]) * (y - out[-2][1])
                                     - (out[-1][1] - out[-2][1]) * (x - out[-2][0])) <= 0.0:
                out.pop()
            out.append((x, y))
        return out[:-1]

    return np.array(chain(pts) + chain(pts[::-1]))


def clip_polygon(polygon, normal, offset):
    """The convex ``polygon`` (K, D: its corners in order; a point or a segment too) cut to normal . x >=
    offset (Sutherland-Hodgman, one plane; any dimension D)."""
    poly = np.asarray(polygon, float).reshape(-1, len(normal))
    side = poly @ np.asarray(normal, float) - offset
    out = []
    for k in range(len(poly)):
        if (side[k] >= 0.0) != (side[k - 1] >= 0.0) and len(poly) > 1:
            t = side[k - 1] / (side[k - 1] - side[k])
            out.append(poly[k - 1] + t * (poly[k] - poly[k - 1]))
        if side[k] >= 0.0:
            out.append(poly[k])
    return np.array(out).reshape(-1, len(normal))


def clip_to_unit_square(polygon):
    """The convex ``polygon`` (K, 2; a point or a segment too) clipped to [0, 1]^2 (Sutherland-Hodgman)."""
    poly = np.asarray(polygon, float).reshape(-1, 2)
    for normal, offset in (((1.0, 0.0), 0.0), ((-1.0, 0.0), -1.0), ((0.0, 1.0), 0.0), ((0.0, -1.0), -1.0)):
        poly = clip_polygon(poly, normal, offset)
        if not len(poly):
            break
    return poly


def intersection(a, b):
    """The window common to windows ``a`` and ``b`` (each holds a set: so does this), EMPTY if none."""
    if a == EMPTY or b == EMPTY:
        return EMPTY
    out = (max(a[0], b[0]), min(a[1], b[1]), max(a[2], b[2]), min(a[3], b[3]))
    return out if out[0] <= out[1] and out[2] <= out[3] else EMPTY


def union(a, b):
    """The smallest window holding windows ``a`` and ``b`` (EMPTY holds nothing)."""
    if a == EMPTY:
        return b
    if b == EMPTY:
        return a
    return (min(a[0], b[0]), max(a[1], b[1]), min(a[2], b[2]), max(a[3], b[3]))


# The crop of a window's side [l, h] (normalised) in a picture of r px at p percent, as Blender simple
# expressions (the compositor's drivers evaluate them at render time, without the add-on): every pixel whose
# centre is in [l, h], at least 2 px (or the picture), of the picture's parity (the compositor centres a
# smaller image on the picture: with the same parity the way back is a whole number of pixels, (START +
# EXTENT / 2 - SIZE / 2)).  Each under Blender's 256 characters.
SIZE = "int(r*p/100)"
_SPAN = f"min(max(ceil(h*{SIZE})-floor(l*{SIZE}),2),{SIZE})"
EXTENT = f"{_SPAN}+fmod({SIZE}-{_SPAN},2)"
START = f"max(min(floor(l*{SIZE}),{SIZE}-({EXTENT})),0)"
_SIMPLE = {"floor": math.floor, "ceil": math.ceil, "fmod": math.fmod, "max": max, "min": min, "int": int}


def evaluate(expression, lo, hi, size):
    """``expression`` (SIZE, START or EXTENT) for a window's side [lo, hi] in a picture ``size`` px across, as
    a driver evaluates it."""
    return eval(expression, dict(_SIMPLE), {"l": lo, "h": hi, "r": size, "p": 100})


def pixels(win, width, height):
    """(x, y, w, h): the pixels the compositor crops ``win`` to in a width x height picture."""
    (x, w), (y, h) = ((int(evaluate(START, lo, hi, n)), int(evaluate(EXTENT, lo, hi, n)))
                      for lo, hi, n in ((*win[:2], width), (*win[2:], height)))
    return x, y, w, h
