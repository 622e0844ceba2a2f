"""The sun's light shafts in a fog layer: an orthographic shadow map of the sun and the lit share of its glow.

The sun's map (``sun_frame``, ``sun_map_origins``) is a plane of parallel rays along the sunlight over the region whose
fog it must cover, each grid point the distance to the first surface along its ray; a fog point is lit where it lies
nearer the sun than that (``sun_lit``), a surface where it is its cell's first surface (``sun_surface_lit``).  Along a
camera ray inside the layer the sun's single scattering falls as e^{-a t} (``sun_attenuation_rate``): its nodes are
placed in that density's quantiles (``sun_node_place``), so every node weighs alike and the lit share is the mean of H
over them (``sun_lit_share``); a surface's share integrates that over its hemisphere (``sun_surface_share``, the lamps'
``shafts.surface_share``).

Every kernel takes an ops namespace ``m`` first (``ops.py``): numpy, the compositor's nodes.
"""
import math
from typing import NamedTuple

import numpy as np

from ..shafts.shaft_maps import nearest_depth
from ..shafts.shafts import hemisphere_direction, hemisphere_sums
# --- the sun: an orthographic map and the lit share of its glow in a fog layer ---------------------------

SUN_MAP = 1024        # grid points along the longer side of the sun's map (its cells are square)
SUN_ANIMATED_MAP = 384   # the same for each frame's map in an animation's atlas (over every frame's region)
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


def _hg(m, g, mu):
    """4 pi p_HG(mu) = (1 - g^2) / (1 + g^2 - 2 g mu)^{3/2} (Henyey and Greenstein 1941)."""
    base = (1.0 + g * g) - (2.0 * g) * mu
    return (1.0 - g * g) / (base * m.sqrt(base))


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
