"""A spot light in dense fog (issue 28, item 1: "Spots: say what you do with the cone"): dense.py's scene with
its lamp turned into a spot, and the spot's path-traced single- and multiple-scattering references.

The scene is :func:`fog_scenes.dense.build`'s (camera DISTANCE_M = 15 m from the lamp on -Y looking along +Y at
it, 120 x 120 px, 0.1 degree per pixel at the image centre, World black), with three changes:

* the lamp is a SPOT of the same power (dense.LAMP_POWER_W = 1000 W; on its axis the intensity of the point
  lamp, P / 4 pi = 79.6 W/sr), radius 0 (dense.py's default, a true point), cone SPOT_SIZE_DEG = 60 degrees
  (half-angle 30 degrees) and blend SPOT_BLEND = 0.15.  Blender's falloff (docs: shared notes, measured per
  pixel) is f = smoothstep((c - cos 30 deg) / ((1 - cos 30 deg) x blend)) with c the cosine between the
  lamp-to-point direction and the spot's axis (its local -Z); no light at all outside the 60 degree cone;
* the spot's orientation is one of SPOTS (object rotation_euler, degrees, Euler XYZ, as data so the scene can
  be rebuilt anywhere; :func:`spot_axis` derives the axis from it):

  - ``side``: axis +Z (up), perpendicular to the view direction.  The camera sees the cone from the side: a
    wedge of +-30 degrees about the vertical above the lamp's image, lit by light scattered through about 90
    degrees;
  - ``toward``: the side axis tilted 45 degrees towards the camera, (0, -1, 1) / sqrt 2.  The camera is 45
    degrees off the axis, 15 degrees outside the cone's edge, and sees the cone's near side coming towards it;

* camera clip end 1000 m (clip start stays 1 mm: Cycles starts camera rays and their fog at the near clip).

The fog of each case (CASES) is dense.py's medium: extinction ``density`` (1/m), Henyey-Greenstein g, albedo
(Volume Scatter white of density albedo x density plus Volume Absorption black of density (1 - albedo) x
density), rendered by :func:`fog_scenes.dense.render_reference_seed` (pixel centres, clip start 1 mm,
``volume_bounces`` = ``max_bounces``, fixed samples, each seed's render kept).

Where the cone is lit: :func:`cone_mask` marks the pixels whose centre ray passes through the cone (c above
cos 30 degrees) at a point within REACH_MFP mean free paths of the lamp.  Outside it single scattering is
exactly zero, so a ring's median can be zero and :func:`fog_scenes.dense.ring_means`' firefly rule (leave out
pixels above 20 x the median) would then drop every lit pixel; :func:`region_ring_means` applies the rule
inside and outside the mask separately.

No bpy at import: every Blender job runs in a fresh process through ``render_harness``.  As a script,
``python -m fog_scenes.dense_spot OUT.blend --case side`` builds a case's .blend and
``python -m fog_scenes.dense_spot --cases`` renders every reference of REFERENCE_RUNS (and the centre crops of
CENTRE_RUNS) that is missing and prints the ring tables.  Measurements: docs/measurements/2026-11-27-dense-spot-references.md.
"""
import argparse
import math
import pathlib
import sys

import numpy as np

from fog_scenes import area_lights, dense
from fog_scenes import render_harness as h

RESOLUTION = dense.RESOLUTION
DISTANCE_M = 15.0
POWER_W = dense.LAMP_POWER_W
LAMP_RADIUS_M = 0.0            # dense.py's default: a true point
SPOT_SIZE_DEG = 60.0           # the full cone angle (Blender's spot_size)
SPOT_BLEND = 0.15
CLIP_END_M = 1000.0
REACH_MFP = 3.0                # cone_mask: the cone counts out to this many mean free paths from the lamp
LAMP_NAME = "Lamp"             # dense.build's lamp object (kept, so dense.project_from_blend finds it)

# The spot's orientation: the object's rotation_euler in degrees (Euler XYZ); the axis is the local -Z it maps
# to (spot_axis).  Camera at (0, -DISTANCE_M, 0) looking along +Y; image up is +Z.
SPOTS = {
    "side": {"rotation_euler_deg": (180.0, 0.0, 0.0)},      # axis (0, 0, 1): 90 deg from the lamp-camera line
    "toward": {"rotation_euler_deg": (-135.0, 0.0, 0.0)},   # axis (0, -1, 1)/sqrt 2: 45 deg from it
}

# The cases: a spot orientation and a fog.  T = density x DISTANCE_M.
CASES = {
    "side": {"spot": "side", "density": 0.3, "anisotropy": 0.85, "albedo": 0.9},         # T 4.5
    "toward": {"spot": "toward", "density": 0.3, "anisotropy": 0.85, "albedo": 0.9},     # T 4.5
    "side_thin": {"spot": "side", "density": 0.1, "anisotropy": 0.85, "albedo": 0.9},    # T 1.5
}

# The cached references (tests/references/dense_spot_*): (case, volume bounces, samples per render, seeds).
REFERENCE_RUNS = [
    ("side", 64, 2048, 4),
    ("side", 0, 4096, 2),
    ("toward", 64, 2048, 4),
    ("toward", 0, 4096, 2),
    ("side_thin", 64, 2048, 2),
    ("side_thin", 0, 4096, 2),
]


def _spot_name(case):
    """The SPOTS key of a case name or of a spot name."""
    if case in SPOTS:
        return case
    return CASES[case]["spot"]


def spot_axis(case):
    """Unit world direction of the spot's axis (its local -Z) for a case or spot name."""
    r = area_lights.euler_xyz_matrix(SPOTS[_spot_name(case)]["rotation_euler_deg"])
    a = r @ np.array([0.0, 0.0, -1.0])
    return a / np.linalg.norm(a)


def spot_falloff(cos_axis, spot_size_deg=SPOT_SIZE_DEG, blend=SPOT_BLEND):
    """Blender's spot falloff (no unit) at cosine ``cos_axis`` between the lamp-to-point direction and the axis:
    0 outside the cone, smoothstep((c - cos half) / ((1 - cos half) blend)) inside (measured in Cycles; shared
    notes, blender-facts section 1)."""
    c = np.asarray(cos_axis, dtype=np.float64)
    ch = math.cos(math.radians(0.5 * float(spot_size_deg)))
    if blend <= 0.0:
        return (c > ch).astype(np.float64)
    x = np.clip((c - ch) / ((1.0 - ch) * float(blend)), 0.0, 1.0)
    return np.where(c > ch, x * x * (3.0 - 2.0 * x), 0.0)


def camera_position(distance=DISTANCE_M):
    """The camera (m): on -Y, the lamp at the origin."""
    return np.array([0.0, -float(distance), 0.0])


def pixel_rays(resolution=RESOLUTION, deg_per_px=dense.DEG_PER_PX):
    """(H, W, 3) unit world directions of the pixel centres' rays (pinhole looking along +Y, image up +Z, row 0
    at the top, x to +X): (tan(deg_per_px) (x + 0.5 - cx), 1, tan(deg_per_px) (cy - y - 0.5)), normalised."""
    w, hh = resolution
    cx, cy = dense.lamp_image_centre(resolution)
    y, x = np.mgrid[0:hh, 0:w]
    t = math.tan(math.radians(deg_per_px))
    d = np.stack([t * (x + 0.5 - cx), np.ones((hh, w)), t * (cy - y - 0.5)], axis=-1)
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def cone_mask(case, reach_mfp=REACH_MFP, resolution=RESOLUTION):
    """(H, W) bool: the pixel's centre ray passes through the spot's cone (falloff > 0) at a point within
    ``reach_mfp`` mean free paths (reach_mfp / density m) of the lamp (``reach_mfp`` None: at any distance up to
    the clip end).

    Exact: with the lamp at the origin, the ray's point P(s) = C + s d is in the cone where P.a > cos(half) |P|,
    i.e. where Q(s) = (P.a)^2 - cos^2(half) |P|^2 > 0 on the part of the ray with P.a > 0.  Q is quadratic in s,
    so it is positive somewhere on the allowed interval of s (s >= 0, P.a > 0, |P| <= reach) iff it is positive
    at one of the interval's ends or, if Q opens downwards, at its vertex inside it."""
    spec = CASES[case] if case in CASES else {"spot": case, "density": None}
    a = spot_axis(spec["spot"])
    ch2 = math.cos(math.radians(0.5 * SPOT_SIZE_DEG)) ** 2
    reach = CLIP_END_M if reach_mfp is None else float(reach_mfp) / float(spec["density"])
    d = pixel_rays(resolution)
    cam = camera_position()
    ca, da, cd, cc = float(cam @ a), d @ a, d @ cam, float(cam @ cam)
    qa, qb, qc = da * da - ch2, 2.0 * (ca * da - ch2 * cd), ca * ca - ch2 * cc
    # |P|^2 = s^2 + 2 s C.d + |C|^2 <= reach^2
    disc = cd * cd - (cc - reach * reach)
    root = np.sqrt(np.maximum(disc, 0.0))
    lo = np.maximum(0.0, -cd - root)
    hi = np.minimum(CLIP_END_M, -cd + root)
    # P.a = C.a + s d.a > 0
    with np.errstate(divide="ignore", invalid="ignore"):
        s_half = -ca / da
    lo = np.where(da > 0.0, np.maximum(lo, s_half), lo)
    hi = np.where(da < 0.0, np.minimum(hi, s_half), hi)
    ok = (disc > 0.0) & (hi > lo) & ~((da == 0.0) & (ca <= 0.0))

    def q(s):
        return (qa * s + qb) * s + qc
    with np.errstate(divide="ignore", invalid="ignore"):
        sv = np.clip(-qb / (2.0 * qa), lo, hi)
    best = np.maximum(np.maximum(q(lo), q(hi)), np.where(qa < 0.0, q(sv), -np.inf))
    return ok & (best > 0.0)


# -- the scene (bpy, in a Blender process) ----------------------------------------------------------------------

def build(scene, case, resolution=RESOLUTION):
    """Fill ``scene``: :func:`fog_scenes.dense.build`'s scene (DISTANCE_M, POWER_W, LAMP_RADIUS_M) whose lamp
    is then made a spot of SPOT_SIZE_DEG and SPOT_BLEND turned as SPOTS[case's spot], clip end CLIP_END_M.
    Needs bpy."""
    import bpy
    spot = SPOTS[_spot_name(case)]
    dense.build(scene, DISTANCE_M, POWER_W, LAMP_RADIUS_M, resolution)
    as_spot(bpy.data.objects[LAMP_NAME], SPOT_SIZE_DEG, SPOT_BLEND, spot["rotation_euler_deg"], LAMP_NAME + "Spot")
    scene.camera.data.clip_end = CLIP_END_M
    return scene


def as_spot(ob, spot_size_deg, blend, rotation_euler_deg, name):
    """Make the point light object ``ob`` a spot light of the same power, colour and radius (its light data a new
    one named ``name``, shadows on), of cone ``spot_size_deg`` (full angle) and ``blend``, turned to
    ``rotation_euler_deg`` (Euler XYZ; the axis is the local -Z).  Needs bpy."""
    import bpy
    old = ob.data
    light = bpy.data.lights.new(name, 'SPOT')
    light.energy = old.energy
    light.shadow_soft_size = old.shadow_soft_size
    light.use_shadow = True
    light.color = old.color
    light.spot_size = math.radians(spot_size_deg)
    light.spot_blend = blend
    ob.data = light
    bpy.data.lights.remove(old)
    ob.rotation_mode = 'XYZ'
    ob.rotation_euler = tuple(math.radians(v) for v in rotation_euler_deg)


def blend_path(case, workdir=None):
    """Path of the case's .blend (one per spot orientation) in ``workdir`` (default: the harness's scratch
    folder), built if missing."""
    name = _spot_name(case)
    workdir = pathlib.Path(workdir) if workdir else pathlib.Path(h._env()["TMPDIR"]) / "fog_dense_spot"
    workdir.mkdir(parents=True, exist_ok=True)
    blend = workdir / f"dense_spot_{name}_d{DISTANCE_M:g}_P{POWER_W:g}_r{LAMP_RADIUS_M:g}.blend"
    if not blend.is_file():
        h.run(["-m", "fog_scenes.dense_spot", blend, "--case", name])
    return blend


# -- references -------------------------------------------------------------------------------------------------

def reference_name(case, volume_bounces, samples, seeds, resolution=RESOLUTION):
    """File name of a cached reference: ``dense_spot_<spot>_`` then dense.py's name of the same fog."""
    c = CASES[case]
    base = dense.reference_name(DISTANCE_M, c["density"], c["anisotropy"], c["albedo"], volume_bounces, samples,
                                seeds, POWER_W, LAMP_RADIUS_M, resolution)
    return f"dense_spot_{c['spot']}_" + base[len("dense_"):]


def render_reference(case, volume_bounces=64, samples=2048, seeds=2, regen=False, directory=None, times=None):
    """Path of the cached Cycles reference of ``case`` (CASES), rendering it if missing (or ``regen``).

    ``volume_bounces`` N (0: single scattering; N > 0: multiple, max_bounces = N), ``samples`` spp per render,
    ``seeds`` renders (seeds 0 .. seeds-1) averaged, each by :func:`fog_scenes.dense.render_reference_seed` and
    kept beside the mean (:func:`fog_scenes.dense.seed_path`), reused unless ``regen``.  Cached as ``directory``
    (default tests/references) / :func:`reference_name`.  ``times``: a list to which each new render's seconds
    are appended."""
    directory = pathlib.Path(directory) if directory else h.REFERENCES
    path = directory / reference_name(case, volume_bounces, samples, seeds)
    if path.is_file() and not regen:
        return path
    return render_case(path, blend_path(case), CASES[case], volume_bounces, samples, seeds, regen, times)


CENTRE_PX = 12   # the centre crop's side (px) about the lamp's image: rings 1.5-6 px (``render_centre_reference``)
CENTRE_RUNS = [("side", 64, 65536, 4)]   # (case, volume bounces, samples, seeds) of the centre crops


def centre_reference_name(case, volume_bounces, samples, seeds):
    """File name of a cached centre crop: :func:`reference_name` with ``_centre<CENTRE_PX>``."""
    return crop_name(reference_name(case, volume_bounces, samples, seeds))


def crop_name(frame_name):
    """A centre crop's file name from its frame reference's."""
    return frame_name.replace(".exr", f"_centre{CENTRE_PX}.exr")


def centre_slice():
    """(rows, columns) slices of the frame the centre crop covers (the lamp's image at the frame's centre)."""
    lo = RESOLUTION[0] // 2 - CENTRE_PX // 2
    return slice(lo, lo + CENTRE_PX), slice(lo, lo + CENTRE_PX)


def render_centre_reference(case, volume_bounces=64, samples=65536, seeds=4, regen=False, directory=None,
                            times=None):
    """Path of the cached Cycles reference of the CENTRE_PX square about the lamp's image (:func:`centre_slice`),
    rendered as :func:`render_reference` renders the frame but with Cycles' border cropped to it: the inner rings
    beside a beam hold 24 and 116 pixels whose path-traced means stay noisy at 2048 spp x 4 (the innermost read
    0.92 of this crop's 65536 x 4)."""
    directory = pathlib.Path(directory) if directory else h.REFERENCES
    return render_crop(directory / centre_reference_name(case, volume_bounces, samples, seeds), blend_path(case),
                       CASES[case], volume_bounces, samples, seeds, regen, times)


def render_crop(path, blend, case, volume_bounces, samples, seeds, regen=False, times=None):
    """Render (if missing or ``regen``) the centre crop ``path`` (:func:`centre_slice`) of ``blend`` as
    :func:`render_case` renders the frame."""
    path = pathlib.Path(path)
    if path.is_file() and not regen:
        return path
    rows, cols = centre_slice()
    w, hh = RESOLUTION
    border = (cols.start / w, cols.stop / w, 1.0 - rows.stop / hh, 1.0 - rows.start / hh)
    return render_case(path, blend, case, volume_bounces, samples, seeds, regen, times, border=border)


def render_case(path, blend, case, volume_bounces, samples, seeds, regen=False, times=None, border=None,
                before_seed=None):
    """Render ``path``: ``blend`` in the fog of ``case`` (a CASES entry: density, anisotropy, albedo) with
    ``volume_bounces``, ``samples`` spp and ``seeds`` seeds averaged (:func:`fog_scenes.dense.render_reference_seed`,
    each seed kept beside the mean and reused unless ``regen``); ``border``: that crop only; ``before_seed(seed)``:
    called before a seed's render (it may raise to stop)."""

    def render_seed(seed, out):
        if before_seed is not None:
            before_seed(seed)
        return dense.render_reference_seed(blend, out, case["density"], case["anisotropy"], case["albedo"],
                                           volume_bounces, samples, seed, RESOLUTION, border=border)[1]

    return h.mean_of_seeds(path, render_seed, seeds, regen, times)


def with_centre(image, centre):
    """A copy of the frame ``image`` with its centre square replaced by ``centre`` (a centre crop)."""
    out = np.array(image, copy=True)
    rows, cols = centre_slice()
    out[rows, cols] = np.asarray(centre)[..., :out.shape[-1]]
    return out


def seed_images(case, volume_bounces, samples, seeds):
    """The kept per-seed renders of a cached reference, as (H, W, 3) arrays."""
    from fog_addon import imageio
    path = h.REFERENCES / reference_name(case, volume_bounces, samples, seeds)
    return [imageio.read_rgb(dense.seed_path(path, s)) for s in range(int(seeds))]


# -- measures (numpy) -------------------------------------------------------------------------------------------

def region_ring_means(image, centre_xy, mask, edges_px=dense.RING_EDGES_PX, firefly=dense.FIREFLY_FACTOR):
    """Mean luminance over each annulus (:func:`fog_scenes.dense.ring_means`) of the pixels in ``mask`` only,
    the firefly rule (leave out pixels above ``firefly`` x the median) applied among those pixels: returns
    (means, pixels kept, pixels left out), NaN where the annulus holds none of them."""
    return dense.ring_means(image, centre_xy, edges_px, firefly, return_counts=True, mask=mask)


def sector_means(image, centre_xy, mask=None, edges_px=dense.RING_EDGES_PX, sectors=8,
                 firefly=dense.FIREFLY_FACTOR):
    """(rings, sectors) mean luminance over each annulus cut into ``sectors`` equal azimuth sectors, sector k
    centred on k x 360 / sectors degrees from image up (clockwise: 90 is image right).  A spot's glow is not
    round: this is its azimuthal structure.  The firefly rule is applied within each cell, separately to its
    pixels inside and outside ``mask`` (:func:`cone_mask`) when given: a cell across the cone's edge holds
    single scattering that is zero on one side."""
    lum = dense.luminance(image)
    hh, w = lum.shape
    y, x = np.mgrid[0:hh, 0:w]
    az = np.degrees(np.arctan2(x + 0.5 - float(centre_xy[0]), float(centre_xy[1]) - (y + 0.5))) % 360.0
    r = dense.pixel_radii(lum.shape, centre_xy)
    mask = np.zeros(lum.shape, bool) if mask is None else np.asarray(mask, bool)
    width = 360.0 / int(sectors)
    out = np.full((len(edges_px) - 1, int(sectors)), np.nan)
    for i, (lo, hi) in enumerate(zip(edges_px[:-1], edges_px[1:])):
        for k in range(int(sectors)):
            cell = (r >= lo) & (r < hi) & (((az - k * width + 0.5 * width) % 360.0) < width)
            kept = []
            for part in (cell & mask, cell & ~mask):
                v = lum[part]
                if v.size and firefly is not None:
                    v = v[v <= firefly * np.median(v)]
                kept.append(v)
            v = np.concatenate(kept)
            if v.size:
                out[i, k] = v.mean()
    return out


def emitted_fraction(spot_size_deg=SPOT_SIZE_DEG, blend=SPOT_BLEND):
    """The spot's emitted power as a fraction of the point lamp of the same Blender power (which it matches on
    its axis): (1/4 pi) int f dOmega = (1/2) int_{-1}^{1} f(c) dc (scipy quadrature of :func:`spot_falloff`)."""
    from scipy.integrate import quad
    ch = math.cos(math.radians(0.5 * float(spot_size_deg)))
    knee = ch + (1.0 - ch) * float(blend)
    return 0.5 * quad(lambda c: float(spot_falloff(c, spot_size_deg, blend)), ch, 1.0, points=[knee])[0]


def single_scattering_quadrature(case, pixels, resolution=RESOLUTION):
    """Single-scattering radiance (W m^-2 sr^-1) of ``case`` at pixel centres ``pixels`` [(x, y)] by adaptive
    quadrature along the ray (scipy): albedo beta I0 int f(c) p_HG(mu) exp(-beta (s + r)) / r^2 ds, with r the
    lamp-point distance, I0 = P / 4 pi, f the spot falloff, mu the cosine between the light's direction at the
    point and the direction back to the camera.  An independent check of the single-scattering references."""
    from scipy.integrate import quad
    c = CASES[case]
    beta, g, a = c["density"], c["anisotropy"], c["albedo"]
    axis = spot_axis(case)
    i0 = POWER_W / (4.0 * math.pi)
    d_all = pixel_rays(resolution)
    cam = camera_position()
    out = []
    for x, y in pixels:
        d = d_all[int(y), int(x)]

        def f(s, d=d):
            p = cam + s * d
            r = float(np.linalg.norm(p))
            w = p / r
            mu = float(-w @ d)
            phase = (1.0 - g * g) / (4.0 * math.pi * (1.0 + g * g - 2.0 * g * mu) ** 1.5)
            return float(spot_falloff(w @ axis)) * phase * math.exp(-beta * (s + r)) / (r * r)
        # closest approach to the lamp: split there (the integrand peaks near it)
        s0 = float(-cam @ d)
        pts = [0.0, s0 - 2.0, s0 - 0.5, s0, s0 + 0.5, s0 + 2.0, s0 + 20.0, s0 + 120.0]
        pts = sorted(p for p in pts if 0.0 <= p <= CLIP_END_M)
        total = sum(quad(f, lo, hi, limit=400, epsabs=0.0, epsrel=1e-8)[0] for lo, hi in zip(pts[:-1], pts[1:]))
        out.append(a * beta * i0 * total)
    return np.array(out)


def case_summary(case, ms_run=None, ss_run=None):
    """Ring and region figures of a case from its cached references (REFERENCE_RUNS by default): a dict of
    numpy arrays and floats (see :func:`print_summary`)."""
    from fog_addon import imageio
    ms_run = ms_run or next(r for r in REFERENCE_RUNS if r[0] == case and r[1] > 0)
    ss_run = ss_run or next(r for r in REFERENCE_RUNS if r[0] == case and r[1] == 0)
    ms = imageio.read_rgb(h.REFERENCES / reference_name(*ms_run))
    ss = imageio.read_rgb(h.REFERENCES / reference_name(*ss_run))
    c = dense.lamp_image_centre()
    mask = cone_mask(case)
    out = {"mask_pixels": int(mask.sum()), "mask_pixels_any_reach": int(cone_mask(case, None).sum()),
           "ss_lit_pixels": int((dense.luminance(ss) > 0).sum()),
           "ss_lit_outside_mask": int(((dense.luminance(ss) > 0) & ~cone_mask(case, None)).sum()),
           "mask_outside_ss_lit": int((~(dense.luminance(ss) > 0) & cone_mask(case, None)).sum())}
    for name, img in (("ms", ms), ("ss", ss)):
        out[name + "_rings"], out[name + "_kept"], out[name + "_dropped"] = dense.ring_means(
            img, c, return_counts=True)
        out[name + "_rings_all"] = dense.ring_means(img, c, firefly=None)
        out[name + "_in"] = region_ring_means(img, c, mask)
        out[name + "_out"] = region_ring_means(img, c, ~mask)
        lum = dense.luminance(img)
        out[name + "_whole"] = float(lum.mean())
        out[name + "_mask_mean"] = float(lum[mask].mean())
        out[name + "_outside_mean"] = float(lum[~mask].mean())
    seeds = seed_images(*ms_run)
    per = np.array([dense.ring_means(s, c) for s in seeds])
    per_in = np.array([region_ring_means(s, c, mask)[0] for s in seeds])
    per_out = np.array([region_ring_means(s, c, ~mask)[0] for s in seeds])
    n = len(seeds)
    for name, arr in (("", per), ("_in", per_in), ("_out", per_out)):
        out["ms_rel_se" + name] = np.std(arr, axis=0, ddof=1) / math.sqrt(n) / np.mean(arr, axis=0)
    wh = np.array([dense.luminance(s).mean() for s in seeds])
    out["ms_whole_rel_se"] = float(np.std(wh, ddof=1) / math.sqrt(n) / wh.mean())
    return out


def print_summary(case):
    """Print :func:`case_summary` as text tables."""
    s = case_summary(case)
    labels = dense.ring_labels()
    np.set_printoptions(linewidth=160)
    print(f"== {case}: {CASES[case]}  axis {np.round(spot_axis(case), 4)}")
    print(f"mask pixels (reach {REACH_MFP:g} mfp) {s['mask_pixels']}, any reach {s['mask_pixels_any_reach']}, "
          f"SS > 0 pixels {s['ss_lit_pixels']} (outside mask {s['ss_lit_outside_mask']}, mask but dark "
          f"{s['mask_outside_ss_lit']})")
    print("ring          " + "  ".join(f"{l:>10}" for l in labels))
    rows = [("ms rings", s["ms_rings"]), ("ss rings", s["ss_rings"]), ("ms/ss", s["ms_rings"] / s["ss_rings"]),
            ("ms all", s["ms_rings_all"]), ("ss all", s["ss_rings_all"]),
            ("ms/ss all", s["ms_rings_all"] / s["ss_rings_all"]),
            ("ms in", s["ms_in"][0]), ("ss in", s["ss_in"][0]), ("ms/ss in", s["ms_in"][0] / s["ss_in"][0]),
            ("ms out", s["ms_out"][0]), ("ss out", s["ss_out"][0]),
            ("ms se %", 100 * s["ms_rel_se"]), ("ms se in %", 100 * s["ms_rel_se_in"]),
            ("ms se out %", 100 * s["ms_rel_se_out"])]
    for name, v in rows:
        print(f"{name:<13} " + "  ".join(f"{x:10.4g}" for x in v))
    print("dropped ms", s["ms_dropped"], "ss", s["ss_dropped"], "| in ms", s["ms_in"][2], "ss", s["ss_in"][2],
          "| out ms", s["ms_out"][2], "| in kept", s["ms_in"][1], "out kept", s["ms_out"][1])
    print(f"whole: ms {s['ms_whole']:.5g} ss {s['ss_whole']:.5g} ratio {s['ms_whole'] / s['ss_whole']:.4g} "
          f"(ms se {100 * s['ms_whole_rel_se']:.2f} %)")
    print(f"mask: ms {s['ms_mask_mean']:.5g} ss {s['ss_mask_mean']:.5g} ratio "
          f"{s['ms_mask_mean'] / s['ss_mask_mean']:.4g}; outside: ms {s['ms_outside_mean']:.5g} "
          f"ss {s['ss_outside_mean']:.5g}", flush=True)
    return s


def main(argv=None):
    p = argparse.ArgumentParser(description="build a spot-in-dense-fog case's .blend, or render the references")
    p.add_argument("out", nargs="?", help="the .blend to write")
    p.add_argument("--case", default="side", help="a CASES or SPOTS name (the .blend depends only on the spot)")
    p.add_argument("--cases", action="store_true", help="render REFERENCE_RUNS if missing, print their tables")
    p.add_argument("--only", default=None, help="with --cases: a comma-separated list of cases")
    a = p.parse_args(argv)
    if a.cases:
        only = set(a.only.split(",")) if a.only else None
        done = []
        for run in REFERENCE_RUNS:
            if only and run[0] not in only:
                continue
            times = []
            ref = render_reference(*run, times=times)
            print(ref.name, "render seconds", times, flush=True)
            done.append(run[0])
        for run in CENTRE_RUNS:
            if not only or run[0] in only:
                times = []
                print(render_centre_reference(*run, times=times).name, "render seconds", times, flush=True)
        for case in dict.fromkeys(done):
            print_summary(case)
        return 0
    if not a.out:
        p.error("give OUT.blend or --cases")
    import bpy
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    build(scene, a.case)
    h.save_blend(a.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
