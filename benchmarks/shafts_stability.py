"""The stability map of the light shafts' visibility source (issue 27: "Give the map of where the visibility
source fails (occluder size in pixels of its map, distance to the light, grazing rays) and what the fog then
does.  No NaN, no Inf, no black pixels").  Numpy only: no Blender.

    .venv/bin/python benchmarks/shafts_stability.py [--out CSV] [--samples CSV] [--chart PNG]
    .venv/bin/python benchmarks/shafts_stability.py --chart-only [--out CSV] [--chart PNG]

Figures and their reading: docs/measurements/2026-11-27-shafts-stability.md.

The code under test is ``fog_addon/precompute/physics/shafts/shafts.py``: ``lit_share`` with K = 24 nodes (Quality
Final) on the numpy ops, a point light's 1024 x 512 map (``POINT_MAP``) baked here from closed-form ray casts against
spheres and planes at the map's grid points (``point_map_directions``), stored float32 as the add-on's image.
S_map is the mean of the 4 interleaved shares (shift (k + 0.5) / 4, k = 0..3: the 2 x 2 pattern of
``shafts.offset``), as the compositor's filter (``comp_shafts._interleave_mean``, SHAFT_TAPS) averages them.

Two references:

* S_exact: the glow's lit share by scipy ``quad`` of e^{-beta (t + d)} / d^2 along the segment, with the exact
  visibility of the spheres (``sphere_hit`` from the light, as tests/test_shafts.py): the segment is cut at
  the ray's crossings of each sphere and of its shadow cone (closed form), the visibility of each piece is
  checked by ``sphere_hit`` at 7 points inside it, and each piece is integrated by ``quad`` (epsrel 1e-10).
* S_ideal: ``lit_share`` itself with the map replaced by the exact distance to the first sphere in each
  node's own direction (``shaft_maps.map_depth`` patched for the call): the K x 4 nodes with an infinitely fine
  map.  S_ideal - S_exact is the nodes' error, S_map - S_ideal the map's.

Cells: a map cell is 2 pi / 1023 rad (0.352 deg) of longitude; latitude's is pi / 511, 1.0006 x that.  The
scenes sit at the map's equator, where cells are square.  Fog: beta = 0.1 / m, isotropic (g = 0).

Parts (column ``part`` of the CSV, one summary row per cell of the map):

1. ``size``: a sphere whose angular diameter seen from the light is n = 0.25 ... 8 cells, its centre r = 0.5,
   2, 8, 32 m from the light; a camera ray crosses its shadow's axis at right angles BEHIND = 3 m behind its
   centre, from a camera c = 4 ... 5.1 m before the crossing to a wall WALL = 5 m past it.  64 sub-cell
   phases of the sphere's direction against the grid (an 8 x 8 stratified set: the light moving by less
   than a cell) x 3 orientations of the ray about the shadow's axis (0, 45, 90 deg from the map's rows)
   x 4 camera distances.  ``missed``: the share of samples whose S_map is exactly 1 where S_exact < 1 (the
   shaft is gone); ``missed_ideal``: the same for S_ideal (the nodes step over the shadow); ``missed_map``:
   S_map = 1 where S_ideal < 1 (the nodes would see it, the map lost it); ``map_hits``: the share of phases
   whose map holds the sphere at all (any grid point's ray hits it); ``strength``: the shadow's depth
   1 - S_map over the exact 1 - S_exact (1: right; 0: missed; 4: four times too dark);
   ``node_spacing_cells``: the interleaved nodes' spacing (theta_1 - theta_0) / 4K in cells.
2. ``grazing``: a sphere of 1 m radius 4 m from the light (14.5 deg, 82 cells across); a ray crosses its
   shadow cone's surface 8 m from the light at the angle psi to the surface, 90 deg down to 1 deg, tilted
   either along the cone's generator (``chi`` = generator: the ray runs along the shadow's edge towards the
   light, its path across the map shrinks to a few cells) or around the cone (``chi`` = around: its path in
   the map runs along the shadow's edge).  Camera 5 m before the crossing, the ray's end 3 m past it.  16
   phases and 16 azimuths of the crossing around the axis.
3. ``contact``: fog points a distance delta in front of (``side`` = front: should be lit) or behind (``side``
   = behind: should be in shadow) a plane D = 0.5 ... 32 m from the light whose normal makes the angle
   ``incidence`` = 0 ... 85 deg with the light's direction; ``shaft_maps.lit`` with the map's depth at 4000
   directions over +-4 cells (every sub-cell phase), float64 and float32.  ``lit``: the share of them lit.
   ``contact_edge``: the same directions, the distance where ``lit`` turns off found by bisection:
   ``contact_max_m`` / ``contact_mean_m``, how deep the fog in front of the surface is dark (a contact
   shadow); ``leak_max_m``, how deep the fog behind it is lit, ``leak_share`` in how many directions.
4b. ``hidden``: a camera ray aimed at a lamp (to ``offset_m``) that ends at a wall ``distance_m`` before it:
   the whole segment is in the wall's shadow, S = 0.
4. ``finite``: degenerate rays (through the light, from the light, zero length, an occluder touching or
   holding the light, underflowing and far fog, the map's pole), float64 and float32 ops, g = 0 and 0.7, the
   4 shifts, with the sky tail (tail_nodes 6, ``S_far``); and ``surface_share`` at and next to the light.
   ``nan``, ``inf``, ``out_of_range`` (outside [0, 1]) count the values.

Outputs: the summary CSV (``--out``, default benchmarks/out/shafts_stability.csv), every sample of parts 1 and
2 (``--samples``, benchmarks/out/shafts_stability_samples.csv), the chart (``--chart``,
benchmarks/out/shafts_stability.png).  About a minute on 2 cores.
"""
import argparse
import contextlib
import csv
import math
import pathlib
import sys
import time

import numpy as np
from scipy import integrate

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

import csv_rows  # noqa: E402
import smoke  # noqa: E402
from fog_addon.precompute.physics.shafts import shaft_maps, shafts  # noqa: E402
from fog_addon.precompute.core.ops import NumpyOps  # noqa: E402
from fog_addon.precompute.core.tables import TableSpec  # noqa: E402
from fog_scenes.occluders import sphere_hit  # noqa: E402

OUT = smoke.out(ROOT / "benchmarks" / "out")
KEPT = ROOT / "docs" / "measurements" / "data" / "shafts_stability_2026-11-27.csv"
WIDTH, HEIGHT = shaft_maps.POINT_MAP
CELL = 2.0 * math.pi / (WIDTH - 1)     # rad: one cell of the map
K = shafts.samples_for("final").view_nodes   # 24
SHIFTS = [(k + 0.5) / 4 for k in range(4)]
BETA = 0.1                             # 1/m
LIGHT = np.array([0.3, -0.2, 3.0])
I0, J0 = 700, 255                      # the grid point the scenes face (latitude -0.003 rad)
SPEC = TableSpec("shadow", WIDTH, HEIGHT)

SIZES = smoke.pick((0.25, 0.5, 1.0, 2.0, 4.0, 8.0), (0.5, 4.0))      # cells across
DISTANCES = smoke.pick((0.5, 2.0, 8.0, 32.0), (2.0,))   # m, light to the occluder's centre
BEHIND, WALL = 3.0, 5.0                      # m: the crossing behind the centre; the wall past the crossing
CAMERAS = smoke.pick((4.0, 4.37, 4.71, 5.13), (4.0,))   # m, camera before the crossing
ORIENTS = smoke.pick((0.0, 45.0, 90.0), (45.0,))   # deg, the ray about the shadow's axis from the map's rows
PHASES = smoke.pick([((i + 0.5) / 8, (j + 0.5) / 8) for j in range(8) for i in range(8)],   # sub-cell, part 1
                    [(0.5, 0.5)])
PHASES16 = smoke.pick([((i + 0.5) / 4, (j + 0.5) / 4) for j in range(4) for i in range(4)],   # part 2
                      [(0.5, 0.5)])

PSIS = smoke.pick((90.0, 60.0, 30.0, 15.0, 8.0, 4.0, 2.0, 1.0), (90.0, 4.0))   # deg, the ray to the shadow's surface
GRAZE_R, GRAZE_DIST, GRAZE_AT = 1.0, 4.0, 8.0         # m: sphere radius, its centre, the crossing
GRAZE_CAMERA, GRAZE_END = 5.0, 3.0

PLANE_DISTANCES = smoke.pick((0.5, 2.0, 8.0, 32.0), (2.0,))
INCIDENCES = smoke.pick((0.0, 45.0, 75.0, 85.0), (0.0, 75.0))
DELTAS = smoke.pick((1e-4, 3e-4, 1e-3, 3e-3, 1e-2, 3e-2, 0.1, 0.3, 1.0, 3.0), (1e-3, 0.1))   # m
CONTACT_POINTS = smoke.pick(4000, 200)

FIELDS = ["part", "n_cells", "distance_m", "psi_deg", "chi", "incidence_deg", "delta_m", "side", "case", "dtype",
          "g", "samples", "s_exact", "s_ideal_mean", "s_map_mean", "err_mean", "err_max", "err_ideal_max",
          "missed", "missed_ideal", "missed_map", "map_hits", "node_spacing_cells", "strength_min", "strength_mean",
          "strength_max", "lit",
          "quantity", "values", "nan", "inf", "out_of_range",
          "beyond_1e6", "min", "max", "offset_m", "contact_max_m", "contact_mean_m", "leak_max_m", "leak_share"]


# --- geometry --------------------------------------------------------------------------------------------

def grid_frame(fi, fj):
    """(a, e_lon, e_lat): the unit direction of the map's fractional grid point (fi, fj) and the unit vectors
    along its row and its column there (``shaft_maps.point_map_directions``' grid)."""
    lo = -math.pi + 2.0 * math.pi * fi / (WIDTH - 1)
    la = -0.5 * math.pi + math.pi * fj / (HEIGHT - 1)
    a = np.array([math.cos(la) * math.cos(lo), math.cos(la) * math.sin(lo), math.sin(la)])
    e_lon = np.array([-math.sin(lo), math.cos(lo), 0.0])
    e_lat = np.array([-math.sin(la) * math.cos(lo), -math.sin(la) * math.sin(lo), math.cos(la)])
    return a, e_lon, e_lat


def sphere_first(origin, dirs, centre, radius):
    """The first positive crossing of a sphere (its far side from inside it), NO_HIT where none: what a BVH's
    ray cast returns from a light inside or on a closed mesh."""
    oc = np.asarray(origin, float) - np.asarray(centre, float)
    b = dirs @ oc
    c = oc @ oc - radius * radius
    disc = b * b - c
    root = np.sqrt(np.maximum(disc, 0.0))
    near, far = -b - root, -b + root
    t = np.where(near > 0, near, far)
    return np.where((disc > 0) & (t > 0), t, shaft_maps.NO_HIT)


_DIRS = None


def map_directions():
    global _DIRS
    if _DIRS is None:
        _DIRS = shaft_maps.point_map_directions(WIDTH, HEIGHT).reshape(-1, 3)
    return _DIRS


def bake(light, spheres=(), planes=(), hit=sphere_hit):
    """The point light's map (HEIGHT, WIDTH) float32 of ``spheres`` ((centre, radius)) and ``planes``
    ((point, normal)) at the map's grid points."""
    dirs = map_directions()
    depth = np.full(len(dirs), shaft_maps.NO_HIT)
    for centre, radius in spheres:
        depth = np.minimum(depth, hit(light, dirs, centre, radius))
    for point, normal in planes:
        depth = np.minimum(depth, plane_hit(light, dirs, point, normal))
    return depth.reshape(HEIGHT, WIDTH).astype(np.float32)


def plane_hit(origin, dirs, point, normal):
    """Distance along unit ``dirs`` from ``origin`` to a plane, NO_HIT where it runs away from it."""
    num = (np.asarray(point, float) - np.asarray(origin, float)) @ np.asarray(normal, float)
    den = dirs @ np.asarray(normal, float)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = num / den
    return np.where(np.isfinite(t) & (t > 0), t, shaft_maps.NO_HIT)


def glow(t, camera, e, light, beta):
    """e^{-beta (t + d)} / d^2 at the ray point t (the single-scattering integrand of a point light, g = 0)."""
    x = camera + t * e - light
    d = math.sqrt(float(x @ x))
    return math.exp(-beta * (t + d)) / (d * d)


def visible(t, camera, e, light, spheres):
    x = camera + t * e - light
    d = float(np.linalg.norm(x))
    if d == 0.0:
        return True
    u = (x / d)[None]
    return all(sphere_hit(light, u, c, r)[0] >= d for c, r in spheres)


def _roots(a, b, c, length):
    """Real roots in (0, length) of a t^2 + b t + c."""
    if abs(a) < 1e-300:
        return [-c / b] if abs(b) > 1e-300 and 0 < -c / b < length else []
    disc = b * b - 4 * a * c
    if disc < 0:
        return []
    q = -0.5 * (b + math.copysign(math.sqrt(disc), b))
    roots = [q / a] + ([c / q] if q != 0 else [])
    return [r for r in roots if 0 < r < length]


def crossings(camera, e, length, light, centre, radius):
    """Where the ray crosses the sphere and its shadow cone seen from the light (closed form)."""
    w0, oc = camera - light, camera - centre
    cuts = _roots(1.0, 2 * float(e @ oc), float(oc @ oc) - radius * radius, length)
    axis = centre - light
    dist = float(np.linalg.norm(axis))
    axis = axis / dist
    k2 = radius * radius / (dist * dist - radius * radius)   # tan^2 of the cone's half angle
    p, q = np.cross(w0, axis), np.cross(e, axis)
    s, u = float(w0 @ axis), float(e @ axis)
    cuts += _roots(float(q @ q) - k2 * u * u, 2 * (float(p @ q) - k2 * s * u), float(p @ p) - k2 * s * s, length)
    return cuts


def exact_share(camera, e, length, light, beta, spheres):
    """S by scipy quad with the exact visibility of ``spheres`` (module docstring)."""
    camera, e, light = (np.asarray(v, float) for v in (camera, e, light))
    t_c = float((light - camera) @ e)
    cuts = [0.0, length] + ([t_c] if 0 < t_c < length else [])
    for centre, radius in spheres:
        cuts += crossings(camera, e, length, light, np.asarray(centre, float), radius)
    cuts = sorted(set(cuts))
    lit = total = 0.0
    for a, b in zip(cuts[:-1], cuts[1:]):
        if b - a <= 1e-12 * max(1.0, b):
            continue
        checks = {visible(a + (b - a) * f, camera, e, light, spheres)
                  for f in (1e-6, 0.1, 0.3, 0.5, 0.7, 0.9, 1 - 1e-6)}
        if len(checks) != 1:
            raise RuntimeError(f"visibility changes inside the piece [{a}, {b}]")
        part = integrate.quad(glow, a, b, args=(camera, e, light, beta), epsabs=0, epsrel=1e-10, limit=200)[0]
        total += part
        lit += part if checks.pop() else 0.0
    return lit / total


@contextlib.contextmanager
def exact_map(spheres):
    """``shaft_maps.map_depth`` returns the exact distance to the first sphere in the node's own direction (an
    infinitely fine map) while inside."""
    original = shaft_maps.map_depth

    def depth(m, spec, spot, u):
        d = np.linalg.norm(u, axis=-1, keepdims=True)
        dirs = u / np.maximum(d, 1e-300)
        out = np.full(dirs.shape[:-1], shaft_maps.NO_HIT)
        for c, r in spheres:
            out = np.minimum(out, sphere_hit(LIGHT, dirs, c, r))
        return out
    shaft_maps.map_depth = depth
    try:
        yield
    finally:
        shaft_maps.map_depth = original


def interleaved(m, cameras, dirs, lengths, light, beta=BETA, nodes=K):
    """The mean of the 4 interleaved shares of each ray (the compositor's filter)."""
    return np.mean([shafts.lit_share(m, cameras, dirs, lengths, light, beta, (SPEC, None), nodes, shift=s)
                    for s in SHIFTS], axis=0)


def both_shares(depth, spheres, cameras, dirs, lengths):
    """(S_map, S_ideal) of each ray."""
    m = NumpyOps({SPEC.name: depth})
    s_map = interleaved(m, cameras, dirs, lengths, LIGHT)
    with exact_map(spheres):
        s_ideal = interleaved(m, cameras, dirs, lengths, LIGHT)
    return s_map, s_ideal


def _stats(s_exact, s_ideal, s_map):
    s_exact, s_ideal, s_map = (np.asarray(v, float) for v in (s_exact, s_ideal, s_map))
    shadowed = s_exact < 1.0 - 1e-9
    strength = (1.0 - s_map[shadowed]) / (1.0 - s_exact[shadowed])
    err = np.abs(s_map - s_exact)
    return dict(samples=len(s_map), s_exact=float(np.mean(s_exact)), s_ideal_mean=float(np.mean(s_ideal)),
                s_map_mean=float(np.mean(s_map)), err_mean=float(np.mean(err)), err_max=float(np.max(err)),
                err_ideal_max=float(np.max(np.abs(s_ideal - s_exact))),
                missed=float(np.mean((s_map == 1.0) & shadowed)),
                missed_ideal=float(np.mean((s_ideal == 1.0) & shadowed)),
                missed_map=float(np.mean((s_map == 1.0) & (s_ideal < 1.0) & shadowed)),
                strength_min=float(strength.min()) if strength.size else "",
                strength_mean=float(strength.mean()) if strength.size else "",
                strength_max=float(strength.max()) if strength.size else "")


# --- 1. occluder size x distance -------------------------------------------------------------------------

def size_map(samples):
    rows = []
    for n in SIZES:
        for r in DISTANCES:
            radius = r * math.sin(0.5 * n * CELL)
            exact = {}
            a, e_lon, e_lat = grid_frame(I0, J0)
            centre = LIGHT + r * a
            for c in CAMERAS:   # S_exact is the same in every frame: the scene is turned about the light
                exact[c] = exact_share(LIGHT + (r + BEHIND) * a - c * e_lon, e_lon, c + WALL, LIGHT, BETA,
                                       [(centre, radius)])
            all_exact, all_ideal, all_map, hits = [], [], [], []
            for px, py in PHASES:
                a, e_lon, e_lat = grid_frame(I0 + px, J0 + py)
                spheres = [(LIGHT + r * a, radius)]
                depth = bake(LIGHT, spheres)
                hits.append(bool((depth < shaft_maps.NO_HIT).any()))
                cams, dirs, lens, s_ex, keys = [], [], [], [], []
                for phi in ORIENTS:
                    e = math.cos(math.radians(phi)) * e_lon + math.sin(math.radians(phi)) * e_lat
                    for c in CAMERAS:
                        cams.append(LIGHT + (r + BEHIND) * a - c * e)
                        dirs.append(e)
                        lens.append(c + WALL)
                        s_ex.append(exact[c])
                        keys.append((phi, c))
                s_map, s_ideal = both_shares(depth, spheres, np.array(cams), np.array(dirs), np.array(lens))
                for (phi, c), se, si, sm in zip(keys, s_ex, s_ideal, s_map):
                    samples.append(dict(part="size", n_cells=n, distance_m=r, phase_x=px, phase_y=py, orient_deg=phi,
                                        camera_m=c, map_hits=int(hits[-1]), s_exact=se, s_ideal=float(si),
                                        s_map=float(sm)))
                all_exact += s_ex
                all_ideal += list(s_ideal)
                all_map += list(s_map)
            spacing = np.mean([math.atan(c / (r + BEHIND)) + math.atan(WALL / (r + BEHIND)) for c in CAMERAS]) / (4 * K)
            row = dict(part="size", n_cells=n, distance_m=r, map_hits=float(np.mean(hits)),
                       node_spacing_cells=spacing / CELL)
            row.update(_stats(all_exact, all_ideal, all_map))
            rows.append(row)
            print(f"size {n:5.2f} cells at {r:5.1f} m: S_exact {row['s_exact']:.5f}  err mean {row['err_mean']:.2e} "
                  f"max {row['err_max']:.2e}  missed {row['missed']:.2f} (nodes {row['missed_ideal']:.2f}, "
                  f"map {row['missed_map']:.2f}, "
                  f"map holds it {row['map_hits']:.2f})  strength {row['strength_min']:.2f}..{row['strength_max']:.2f}",
                  flush=True)
    return rows


# --- 2. grazing rays -------------------------------------------------------------------------------------

def grazing_ray(frame, azimuth, psi, chi):
    """(camera, unit direction, length) of the grazing ray in the frame (a, e_lon, e_lat) of the shadow's axis."""
    a, e_lon, e_lat = frame
    alpha = math.asin(GRAZE_R / GRAZE_DIST)
    radial = math.cos(azimuth) * e_lon + math.sin(azimuth) * e_lat
    g = math.cos(alpha) * a + math.sin(alpha) * radial       # the generator through the crossing
    n = -math.sin(alpha) * a + math.cos(alpha) * radial      # the cone's outward normal there
    around = np.cross(g, n)
    s, c = math.sin(math.radians(psi)), math.cos(math.radians(psi))
    e = s * n - c * g if chi == "generator" else s * n + c * around
    q = LIGHT + GRAZE_AT * g
    return q - GRAZE_CAMERA * e, e, GRAZE_CAMERA + GRAZE_END


def grazing(samples):
    cases = [(psi, chi) for chi in ("generator", "around") for psi in PSIS]
    frame0 = grid_frame(I0, J0)
    exact = {}
    for psi, chi in cases:
        cam, e, length = grazing_ray(frame0, 0.0, psi, chi)
        exact[psi, chi] = exact_share(cam, e, length, LIGHT, BETA, [(LIGHT + GRAZE_DIST * frame0[0], GRAZE_R)])
    got = {case: ([], []) for case in cases}
    for k, (px, py) in enumerate(PHASES16):
        frame = grid_frame(I0 + px, J0 + py)
        azimuth = 0.3 + k * math.pi * (3.0 - math.sqrt(5.0))
        spheres = [(LIGHT + GRAZE_DIST * frame[0], GRAZE_R)]
        depth = bake(LIGHT, spheres)
        rays = [grazing_ray(frame, azimuth, psi, chi) for psi, chi in cases]
        s_map, s_ideal = both_shares(depth, spheres, np.array([r[0] for r in rays]), np.array([r[1] for r in rays]),
                                     np.array([r[2] for r in rays]))
        for case, sm, si in zip(cases, s_map, s_ideal):
            got[case][0].append(float(sm))
            got[case][1].append(float(si))
            samples.append(dict(part="grazing", psi_deg=case[0], chi=case[1], phase_x=px, phase_y=py,
                                azimuth_deg=math.degrees(azimuth) % 360, s_exact=exact[case], s_ideal=float(si),
                                s_map=float(sm)))
    rows = []
    for psi, chi in cases:
        s_map, s_ideal = got[psi, chi]
        row = dict(part="grazing", psi_deg=psi, chi=chi)
        row.update(_stats([exact[psi, chi]] * len(s_map), s_ideal, s_map))
        rows.append(row)
        print(f"grazing {chi:9s} psi {psi:4.0f} deg: S_exact {row['s_exact']:.4f}  err mean {row['err_mean']:.2e} "
              f"max {row['err_max']:.2e} (nodes alone {row['err_ideal_max']:.2e})", flush=True)
    return rows


# --- 3. contact ------------------------------------------------------------------------------------------

def contact():
    rng = np.random.default_rng(27)
    a, e_lon, e_lat = grid_frame(I0, J0)
    offs = rng.uniform(-4.0, 4.0, (CONTACT_POINTS, 2)) * CELL
    u = a + offs[:, :1] * e_lon + offs[:, 1:] * e_lat
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    rows = []
    for dist in PLANE_DISTANCES:
        for inc in INCIDENCES:
            normal = -(math.cos(math.radians(inc)) * a + math.sin(math.radians(inc)) * e_lon)
            point = LIGHT + dist * a
            depth = bake(LIGHT, planes=[(point, normal)])
            surface = plane_hit(LIGHT, u, point, normal)   # exact distance in each fog point's direction
            for dtype in (np.float64, np.float32):
                m = NumpyOps({SPEC.name: depth}, dtype=dtype)
                for side, sign in (("front", -1.0), ("behind", 1.0)):
                    for delta in DELTAS:
                        d = surface + sign * delta
                        keep = d > 0
                        if not keep.any():
                            continue
                        uu, dd = u[keep].astype(dtype), d[keep].astype(dtype)
                        lit = shaft_maps.lit(m, dd, shaft_maps.map_depth(m, SPEC, None, uu))
                        rows.append(dict(part="contact", distance_m=dist, incidence_deg=inc, delta_m=delta, side=side,
                                         dtype=np.dtype(dtype).name, samples=int(keep.sum()),
                                         lit=float(np.mean(lit))))
                md = shaft_maps.map_depth(m, SPEC, None, u.astype(dtype))
                lo, hi = np.zeros(len(u)), surface + 10.0    # lit at 0, dark 10 m behind the surface
                for _ in range(64):
                    mid = 0.5 * (lo + hi)
                    ok = shaft_maps.lit(m, mid.astype(dtype), md) > 0.5
                    lo, hi = np.where(ok, mid, lo), np.where(ok, hi, mid)
                edge = lo - surface   # > 0: fog behind the surface lit up to it; < 0: fog in front in shadow
                rows.append(dict(part="contact_edge", distance_m=dist, incidence_deg=inc, dtype=np.dtype(dtype).name,
                                 samples=len(u), contact_max_m=float(max(0.0, -edge.min())),
                                 contact_mean_m=float(np.mean(np.maximum(-edge, 0.0))),
                                 leak_max_m=float(max(0.0, edge.max())), leak_share=float(np.mean(edge > 0))))
    for dtype in ("float64", "float32"):
        print(f"contact ({dtype}): fog in front of the surface in shadow (max, mean), fog behind it lit (max, share)")
        for r in rows:
            if r["part"] == "contact_edge" and r["dtype"] == dtype:
                print(f"  plane {r['distance_m']:4.1f} m, incidence {r['incidence_deg']:2.0f} deg: contact shadow "
                      f"{r['contact_max_m'] * 1e3:8.2f} mm (mean {r['contact_mean_m'] * 1e3:7.2f})  leak "
                      f"{r['leak_max_m'] * 1e3:8.2f} mm ({r['leak_share']:.1%} of directions)")
    for dtype in ("float64", "float32"):
        print(f"contact ({dtype}): the smallest delta from which every fog point is right (front: lit, behind: dark)")
        for dist in PLANE_DISTANCES:
            for inc in INCIDENCES:
                front, behind = (contact_start(rows, dist, inc, side, dtype) for side in ("front", "behind"))
                print(f"  plane {dist:4.1f} m, incidence {inc:2.0f} deg: front {front}  behind {behind}")
    return rows


def contact_start(rows, dist, inc, side, dtype="float64"):
    """The smallest delta (m) of the list from which every larger one classes all fog points right."""
    want = 1.0 if side == "front" else 0.0
    sel = sorted((r for r in rows if r["part"] == "contact" and float(r["distance_m"]) == dist
                  and float(r["incidence_deg"]) == inc and r["side"] == side and r["dtype"] == dtype),
                 key=lambda r: float(r["delta_m"]))
    start = None
    for r in reversed(sel):
        if float(r["lit"]) != want:
            break
        start = float(r["delta_m"])
    return start


# --- 4b. a ray aimed at a lamp hidden behind a wall ------------------------------------------------------

HIDDEN_WALLS = (0.5, 2.0, 5.0)                                  # m, the wall in front of the lamp
HIDDEN_OFFSETS = (0.0, 1e-5, 1e-4, 5e-4, 1e-3, 3e-3, 1e-2, 3e-2)  # m, the ray's distance to the lamp
HIDDEN_CAMERA = 10.0                                            # m, camera to lamp


def hidden():
    """A camera ray aimed (to ``offset``) at a lamp behind a wall, ending at the wall: the whole segment is in
    the wall's shadow, S = 0 exactly."""
    a, e_lon, e_lat = grid_frame(I0, J0)
    rows = []
    for wall in HIDDEN_WALLS:
        depth = bake(LIGHT, planes=[(LIGHT - wall * e_lon, e_lon)])
        cams = np.array([LIGHT - HIDDEN_CAMERA * e_lon + h * a for h in HIDDEN_OFFSETS])
        dirs = np.repeat(e_lon[None], len(cams), 0)
        lens = np.full(len(cams), HIDDEN_CAMERA - wall)
        for dtype in (np.float64, np.float32):
            m = NumpyOps({SPEC.name: depth}, dtype=dtype)
            got = np.mean([shafts.lit_share(m, cams.astype(dtype), dirs.astype(dtype), lens.astype(dtype),
                                            LIGHT.astype(dtype), dtype(BETA), (SPEC, None), K, shift=s)
                           for s in SHIFTS], axis=0)
            for h, v in zip(HIDDEN_OFFSETS, got):
                rows.append(dict(part="hidden", distance_m=wall, offset_m=h, dtype=np.dtype(dtype).name, s_exact=0.0,
                                 s_map_mean=float(v), err_max=float(v)))
            print(f"hidden lamp, wall {wall} m before it ({np.dtype(dtype).name}): S = "
                  + ", ".join(f"{v:.3f} (offset {h:g} m)" for h, v in zip(HIDDEN_OFFSETS, got)) + "  (exact 0)")
    return rows


# --- 4. finiteness ---------------------------------------------------------------------------------------

def _unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def finite_cases(rng, n=400):
    """name -> (cameras, directions, lengths, light, beta, map key)."""
    light = LIGHT
    cams = light + _unit(rng.normal(size=(n, 3))) * rng.uniform(0.5, 20.0, (n, 1))
    towards = _unit(light - cams)
    dist = np.linalg.norm(light - cams, axis=1)
    rand_dirs = _unit(rng.normal(size=(n, 3)))
    at_light = np.repeat(light[None], n, 0)
    near_dirs = _unit(towards + rng.normal(size=(n, 3)) * 1e-7)
    far_cams = light + _unit(rng.normal(size=(n, 3))) * rng.uniform(100.0, 1000.0, (n, 1))
    pole = light + np.array([0.0, 0.0, -5.0])
    return {
        "through the light, ends before it": (cams, towards, 0.5 * dist, light, BETA, "sphere"),
        "through the light, ends at it": (cams, towards, dist, light, BETA, "sphere"),
        "through the light, past it": (cams, towards, 2.0 * dist, light, BETA, "sphere"),
        "through the light, to the sky (1e6 m)": (cams, towards, np.full(n, 1e6), light, BETA, "sphere"),
        "1e-7 rad off the light": (cams, near_dirs, 2.0 * dist, light, BETA, "sphere"),
        "starting at the light": (at_light, rand_dirs, rng.uniform(0.1, 50.0, n), light, BETA, "sphere"),
        "starting at the light, to the sky": (at_light, rand_dirs, np.full(n, 1e6), light, BETA, "sphere"),
        "starting 1e-6 m from the light": (light + rand_dirs * 1e-6, rand_dirs, rng.uniform(0.1, 50.0, n), light,
                                           BETA, "sphere"),
        "zero length": (cams, rand_dirs, np.zeros(n), light, BETA, "sphere"),
        "zero length at the light": (at_light, rand_dirs, np.zeros(n), light, BETA, "sphere"),
        "occluder touching the light": (cams, rand_dirs, rng.uniform(0.0, 30.0, n), light, BETA, "touching"),
        "occluder touching, rays through the light": (cams, towards, 2.0 * dist, light, BETA, "touching"),
        "light inside an occluder": (cams, rand_dirs, rng.uniform(0.0, 30.0, n), light, BETA, "inside"),
        "dense fog far away (weights underflow)": (far_cams, _unit(light - far_cams), np.full(n, 1e6), light, 5.0,
                                                   "sphere"),
        "no fog (beta 0)": (cams, rand_dirs, rng.uniform(0.0, 30.0, n), light, 0.0, "sphere"),
        "camera 1e4 m away, to the sky": (light + rand_dirs * 1e4, -rand_dirs, np.full(n, 1e6), light, BETA, "sphere"),
        "through the map's pole": (np.repeat(pole[None], n, 0), np.repeat([[0.0, 0.0, 1.0]], n, 0),
                                   rng.uniform(0.0, 20.0, n), light, BETA, "sphere"),
    }


def finite_maps():
    radius = 0.5
    down = np.array([0.0, 0.3, -1.0]) / np.linalg.norm([0.0, 0.3, -1.0])
    return {"sphere": bake(LIGHT, [(LIGHT + np.array([0.4, 0.2, -1.0]), 0.5)]),
            "touching": bake(LIGHT, [(LIGHT + radius * down, radius)], hit=sphere_first),
            "inside": bake(LIGHT, [(LIGHT + 0.2 * down, radius)], hit=sphere_first)}


def _count(values):
    v = np.concatenate([np.ravel(np.asarray(x, float)) for x in values])
    ok = np.isfinite(v)
    return dict(values=int(v.size), nan=int(np.isnan(v).sum()), inf=int(np.isinf(v).sum()),
                out_of_range=int(((v < 0.0) | (v > 1.0)).sum()),
                beyond_1e6=int(((v < -1e-6) | (v > 1.0 + 1e-6)).sum()), min=float(v[ok].min()) if ok.any() else "",
                max=float(v[ok].max()) if ok.any() else "")


def finiteness():
    rng = np.random.default_rng(1127)
    maps = finite_maps()
    cases = finite_cases(rng)
    rows = []
    for dtype in (np.float64, np.float32):
        for g in (0.0, 0.7):
            for name, (cams, dirs, lens, light, beta, key) in cases.items():
                m = NumpyOps({SPEC.name: maps[key]}, dtype=dtype)
                near, far = [], []
                with np.errstate(all="ignore"):
                    for s in SHIFTS:
                        a, b = shafts.lit_share(m, cams.astype(dtype), dirs.astype(dtype), lens.astype(dtype),
                                                light.astype(dtype), dtype(beta), (SPEC, None), K, shift=s, g=g,
                                                tail_nodes=6, far=1e6)
                        near.append(a)
                        far.append(b)
                for quantity, values in (("S", near), ("S_far", far)):
                    row = dict(part="finite", case=name, quantity=quantity, dtype=np.dtype(dtype).name, g=g)
                    row.update(_count(values))
                    rows.append(row)
            # a surface's share at and beside the light
            n = 200
            normals = _unit(rng.normal(size=(n, 3)))
            viewer = LIGHT + np.array([5.0, -5.0, 2.0])
            for name, points in (("surface share at the light", np.repeat(LIGHT[None], n, 0)),
                                 ("surface share 1e-6 m from the light", LIGHT + normals * 1e-6),
                                 ("surface share on the touching occluder", LIGHT + normals * 1e-3)):
                key = "touching" if "touching" in name else "sphere"
                m = NumpyOps({SPEC.name: maps[key]}, dtype=dtype)
                values = []
                with np.errstate(all="ignore"):
                    for k in range(16):
                        values.append(shafts.surface_share(m, points.astype(dtype), normals.astype(dtype),
                                                           viewer.astype(dtype), LIGHT.astype(dtype), dtype(BETA),
                                                           (SPEC, None), shift=(k + 0.5) / 16, g=g))
                row = dict(part="finite", case=name, quantity="V", dtype=np.dtype(dtype).name, g=g)
                row.update(_count(values))
                rows.append(row)
    bad = [r for r in rows if r["nan"] or r["inf"] or r["out_of_range"]]
    print(f"finiteness: {sum(r['values'] for r in rows)} values, {sum(r['nan'] for r in rows)} NaN, "
          f"{sum(r['inf'] for r in rows)} Inf, {sum(r['out_of_range'] for r in rows)} out of [0, 1], "
          f"{sum(r['beyond_1e6'] for r in rows)} by more than 1e-6")
    for r in bad:
        print(f"  {r['case']} {r['quantity']} ({r['dtype']}, g {r['g']}): nan {r['nan']} inf {r['inf']} "
              f"out {r['out_of_range']} (beyond 1e-6 {r['beyond_1e6']}): {r['min']:.3g} .. {r['max']:.9g}")
    return rows


# --- chart -----------------------------------------------------------------------------------------------

def read_csv(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def chart(rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(2, 2, figsize=(13, 9.5))
    size = [r for r in rows if r["part"] == "size"]
    grid = np.array([[float(next(r["missed"] for r in size if float(r["n_cells"]) == n
                                 and float(r["distance_m"]) == d)) for n in SIZES] for d in DISTANCES])
    errs = np.array([[float(next(r["err_max"] for r in size if float(r["n_cells"]) == n
                                 and float(r["distance_m"]) == d)) for n in SIZES] for d in DISTANCES])
    strength = np.array([[(float(r["strength_min"]), float(r["strength_max"])) for n in SIZES for r in size
                          if float(r["n_cells"]) == n and float(r["distance_m"]) == d] for d in DISTANCES])
    a = ax[0, 0]
    im = a.imshow(grid, cmap="Reds", vmin=0, vmax=1, origin="lower", aspect="auto")
    for i in range(len(DISTANCES)):
        for j in range(len(SIZES)):
            a.text(j, i, f"{grid[i, j]:.0%}\n±{errs[i, j]:.3f}\n×{strength[i, j, 0]:.1f}–{strength[i, j, 1]:.1f}",
                   ha="center", va="center", fontsize=8)
    a.set_xticks(range(len(SIZES)), [f"{n:g}" for n in SIZES])
    a.set_yticks(range(len(DISTANCES)), [f"{d:g}" for d in DISTANCES])
    a.set_xlabel("occluder's angular diameter (map cells of 2π/1023 rad)")
    a.set_ylabel("occluder's distance to the light (m)")
    a.set_title("1. missed (S = 1, exact < 1); max |S - exact|; shadow depth × exact", fontsize=10)
    fig.colorbar(im, ax=a, label="share of samples missed")

    a = ax[0, 1]
    for d, color in zip(DISTANCES, ("C0", "C1", "C2", "C3")):
        sel = sorted((r for r in size if float(r["distance_m"]) == d), key=lambda r: float(r["n_cells"]))
        x = [float(r["n_cells"]) for r in sel]
        a.plot(x, [float(r["err_max"]) for r in sel], "o-", color=color, label=f"{d:g} m: max |S - exact|")
        a.plot(x, [1 - float(r["s_exact"]) for r in sel], ":", color=color, label=f"{d:g} m: exact 1 - S")
    a.set_xscale("log", base=2)
    a.set_yscale("log")
    a.set_xlabel("occluder's angular diameter (map cells)")
    a.set_ylabel("|S_map - S_exact|, and the shadow's depth 1 - S_exact")
    a.set_title("1. error of the lit share against the shadow it should show")
    a.legend(fontsize=7, ncol=2)

    a = ax[1, 0]
    graze = [r for r in rows if r["part"] == "grazing"]
    for chi, color in (("generator", "C0"), ("around", "C3")):
        sel = sorted((r for r in graze if r["chi"] == chi), key=lambda r: float(r["psi_deg"]))
        x = [float(r["psi_deg"]) for r in sel]
        a.plot(x, [float(r["err_max"]) for r in sel], "o-", color=color, label=f"{chi}: max |S_map - exact|")
        a.plot(x, [float(r["err_mean"]) for r in sel], "s--", color=color, label=f"{chi}: mean")
        a.plot(x, [float(r["err_ideal_max"]) for r in sel], ":", color=color, label=f"{chi}: nodes alone (max)")
    a.set_xscale("log")
    a.set_yscale("log")
    a.set_xlabel("ray's angle to the shadow's surface ψ (deg)")
    a.set_ylabel("error of S")
    a.set_title("2. grazing rays (1 m sphere 4 m from the light, crossing at 8 m)")
    a.legend(fontsize=7)

    a = ax[1, 1]
    edge = [r for r in rows if r["part"] == "contact_edge" and r["dtype"] == "float64"]
    for dist, color in zip(PLANE_DISTANCES, ("C0", "C1", "C2", "C3")):
        sel = sorted((r for r in edge if float(r["distance_m"]) == dist), key=lambda r: float(r["incidence_deg"]))
        x = [float(r["incidence_deg"]) for r in sel]
        a.plot(x, [1e3 * float(r["contact_max_m"]) for r in sel], "o-", color=color,
               label=f"{dist:g} m: fog in front in shadow (max)")
        a.plot(x, [1e3 * float(r["leak_max_m"]) or np.nan for r in sel], "s--", color=color,
               label=f"{dist:g} m: fog behind lit (max)")
    a.set_yscale("log")
    a.set_ylim(0.05, 5000)
    a.set_xlabel("the surface's incidence: its normal to the light's direction (deg)")
    a.set_ylabel("depth along the light's ray (mm)")
    a.set_title("3. contact: FOG_BIAS and the map's grid at a plane")
    a.legend(fontsize=6, ncol=2)
    fig.tight_layout()
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    print(f"wrote {path}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=pathlib.Path, default=OUT / "shafts_stability.csv")
    ap.add_argument("--samples", type=pathlib.Path, default=OUT / "shafts_stability_samples.csv")
    ap.add_argument("--chart", type=pathlib.Path, default=OUT / "shafts_stability.png")
    ap.add_argument("--chart-only", action="store_true")
    args = ap.parse_args(argv)
    if args.chart_only:   # a run of one's own in benchmarks/out if there is one, else the committed run
        chart(read_csv(args.out if args.out.exists() else KEPT), args.chart)
        return 0
    start = time.time()
    samples, rows = [], []
    for name, part in (("finiteness", finiteness), ("hidden", hidden), ("contact", contact),
                       ("size", lambda: size_map(samples)), ("grazing", lambda: grazing(samples))):
        t = time.time()
        rows += part()
        print(f"-- {name}: {time.time() - t:.1f} s", flush=True)
    csv_rows.write(args.out, rows, FIELDS, digits=6)
    csv_rows.write(args.samples, samples, ["part", "n_cells", "distance_m", "psi_deg", "chi", "phase_x", "phase_y",
                                           "orient_deg", "azimuth_deg", "camera_m", "map_hits", "s_exact", "s_ideal",
                                           "s_map"], digits=9)
    print(f"wrote {args.out} and {args.samples} ({time.time() - start:.0f} s)")
    chart(rows and read_csv(args.out), args.chart)
    return 0


if __name__ == "__main__":
    sys.exit(main())
