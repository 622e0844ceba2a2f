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


def boxes_window(corners, camera_matrix, frame):
    """The union of the windows of boxes (M, 8, 3 world corners, ``box_points``): at once for the boxes wholly
    in front of the camera (the bounding box of their projected corners, within the window of each hull,
    skipped if outside the frame), by :func:`window` for those crossing the camera's plane."""
    cam = np.asarray(camera_matrix, float)
    local = (np.asarray(corners, float).reshape(-1, 8, 3) - cam[:3, 3]) @ cam[:3, :3]
    depth = -local[..., 2]
    front = (depth >= NEAR).all(axis=1)
    crossing = (depth >= NEAR).any(axis=1) & ~front
    left, right, bottom, top = frame
    u = (local[front, :, 0] / depth[front] - left) / (right - left)
    v = (local[front, :, 1] / depth[front] - bottom) / (top - bottom)
    lo_u, hi_u, lo_v, hi_v = u.min(axis=1), u.max(axis=1), v.min(axis=1), v.max(axis=1)
    seen = (hi_u >= 0.0) & (lo_u <= 1.0) & (hi_v >= 0.0) & (lo_v <= 1.0)
    out = EMPTY
    if seen.any():
        out = tuple(float(np.clip(x, 0.0, 1.0)) for x in (lo_u[seen].min(), hi_u[seen].max(),
                                                            lo_v[seen].min(), hi_v[seen].max()))
    for box in np.asarray(corners, float).reshape(-1, 8, 3)[crossing]:
        out = union(out, window(box, cam, frame))
    return out


def window(points, camera_matrix, frame):
    """The window of the convex hull of ``points`` (N, 3, world m) seen by a perspective camera.

    camera_matrix: its 4x4 world matrix (it looks along its local -Z); frame: (left, right, bottom, top)
    of its frame at unit distance (``Camera.view_frame`` divided by its depth; shifts included).
    Returns (u0, u1, v0, v1) within [0, 1], EMPTY if all of it is behind the camera.
    """
    cam = np.asarray(camera_matrix, float)
    local = (np.asarray(points, float) - cam[:3, 3]) @ cam[:3, :3]   # the camera's axes are orthonormal
    depth = -local[:, 2]
    # the hull's part in front of the plane depth = NEAR: the points in front, and where the segments
    # between them cross the plane (every edge of the hull is such a segment, and every segment lies in it)
    i, j = np.triu_indices(len(local), 1)
    da, db = depth[i], depth[j]
    crossing = (da - NEAR) * (db - NEAR) < 0.0
    t = (NEAR - da[crossing]) / (db[crossing] - da[crossing])
    cut = local[i[crossing]] + t[:, None] * (local[j[crossing]] - local[i[crossing]])
    front = np.concatenate([local[depth >= NEAR], cut])
    if not len(front):
        return EMPTY
    z = np.maximum(-front[:, 2], NEAR)
    left, right, bottom, top = frame
    u = (front[:, 0] / z - left) / (right - left)
    v = (front[:, 1] / z - bottom) / (top - bottom)
    # the projection is the convex hull of the projected points; only its part in the frame counts
    inside = clip_to_unit_square(convex_hull_2d(np.stack([u, v], axis=1)))
    if not len(inside):
        return EMPTY
    lo, hi = np.clip(inside.min(axis=0), 0.0, 1.0), np.clip(inside.max(axis=0), 0.0, 1.0)
    return float(lo[0]), float(hi[0]), float(lo[1]), float(hi[1])


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


def clip_to_unit_square(polygon):
    """The convex ``polygon`` (K, 2; a point or a segment too) clipped to [0, 1]^2 (Sutherland-Hodgman)."""
    poly = [np.asarray(p, float) for p in polygon]
    for axis, keep_above, edge in ((0, True, 0.0), (0, False, 1.0), (1, True, 0.0), (1, False, 1.0)):
        inside = (lambda p: p[axis] >= edge) if keep_above else (lambda p: p[axis] <= edge)
        out = []
        for k, cur in enumerate(poly):
            prev = poly[k - 1]
            if inside(cur) != inside(prev) and len(poly) > 1:
                t = (edge - prev[axis]) / (cur[axis] - prev[axis])
                out.append(prev + t * (cur - prev))
            if inside(cur):
                out.append(cur)
        poly = out
        if not poly:
            break
    return np.array(poly).reshape(-1, 2)


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
