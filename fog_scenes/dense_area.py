"""A small area light in dense fog (issue 28): dense_spot.py's scene with its spot replaced by a square AREA light,
and the area light's path-traced single- and multiple-scattering references.

The scene is :func:`fog_scenes.dense.build`'s (camera DISTANCE_M = 15 m from the lamp on -Y looking along +Y at
it, 120 x 120 px, 0.1 degree per pixel at the image centre, World black, camera clip start 1 mm, clip end
CLIP_END_M = 1000 m as in dense_spot), with the lamp turned into an AREA light:

* a SQUARE of side AREA_SIZE_M = 0.2 m centred on the origin, ``normalize`` on, ``spread`` 180 degrees (Blender's
  defaults), shadows on, invisible to the camera (``object.visible_camera`` False, a new light object's default:
  no emitter surface in the picture);
* Blender 5.0's convention (docs/measurements/2026-11-27-area-light-references.md): a one-sided Lambertian
  emitter of total flux P = POWER_W, radiance P / (pi A) on its front (local -Z) side, nothing behind it; far from
  it, its radiant intensity is I(theta) = (P / pi) max(cos theta, 0), theta from its normal (local -Z).
  POWER_W = 250 W makes the normal intensity P / pi = 79.6 W/sr, the spot's (and the 1000 W point lamp's)
  on-axis intensity 1000 / (4 pi);
* the area light's orientation is one of AREAS (the object's rotation_euler, degrees, Euler XYZ), the same
  rotations as dense_spot.SPOTS, so the area light's normal is the spot's axis (:func:`area_normal`):

  - ``side``: normal +Z (up), perpendicular to the view direction: the camera lies in the emitter's plane and
    sees it edge-on; the upper half of the picture looks through the lit (front) half-space, the lower half
    through the dark one;
  - ``toward``: normal (0, -1, 1) / sqrt 2, 45 degrees towards the camera: the camera is in the front
    half-space, 45 degrees off the normal.

Size: the 0.2 m square subtends 0.2 / 15 rad = 0.76 degrees = 7.6 px at 0.1 degree per pixel (edge-on in
``side``: a 7.6 px line; in ``toward``: 7.6 x 5.4 px).  The pixel-centre rays of the inner annuli (1.5-7.5 px,
0.04-0.2 m from the lamp at its distance) pass within the emitter's own size of it, where it is not a point.

The fog of each case (CASES) is dense.py's medium: extinction ``density`` (1/m), Henyey-Greenstein g, albedo
(Volume Scatter white of density albedo x density plus Volume Absorption black of density (1 - albedo) x
density), rendered by :func:`fog_scenes.dense.render_reference_seed` (pixel centres, clip start 1 mm,
``volume_bounces`` = ``max_bounces``, fixed samples, each seed's render kept).

Where single scattering lives: :func:`front_mask` marks the pixels whose centre ray passes through the emitter's
front half-space ((X - lamp) . n > 0) at a point within REACH_MFP mean free paths of the lamp (dense_spot's
cone_mask for a hemisphere).  Behind it single scattering is zero, so the rings are measured with
:func:`fog_scenes.dense_spot.region_ring_means` (the firefly rule applied inside and outside the mask
separately).  In ``toward`` every ray crosses the front half-space near the lamp: the mask is the whole picture.

No bpy at import: every Blender job runs in a fresh process through ``render_harness``.  As a script,
``python -m fog_scenes.dense_area OUT.blend --case side`` builds a case's .blend and
``python -m fog_scenes.dense_area --cases`` renders every reference of REFERENCE_RUNS that is missing (in order,
``--budget-minutes`` stops before a seed that would start after the budget) and prints the ring tables and the
single-scattering check.  Measurements: docs/measurements/2026-11-28-dense-area-references.md.
"""
import argparse
import math
import pathlib
import sys
import time

import numpy as np

from fog_scenes import area_lights, dense, dense_spot
from fog_scenes import render_harness as h

RESOLUTION = dense.RESOLUTION
DISTANCE_M = dense_spot.DISTANCE_M
AREA_SIZE_M = 0.2              # the square's side
POWER_W = 250.0                # P / pi = 79.58 W/sr = the spot's on-axis 1000 / (4 pi)
CLIP_END_M = dense_spot.CLIP_END_M
REACH_MFP = dense_spot.REACH_MFP   # front_mask: the front half-space counts out to this many mean free paths
LAMP_NAME = dense_spot.LAMP_NAME   # dense.build's lamp object (kept, so dense.project_from_blend finds it)

# The area light's orientation: the object's rotation_euler in degrees (Euler XYZ); the normal (emitting side) is
# the local -Z it maps to (area_normal).  The same rotations as dense_spot.SPOTS.
AREAS = {
    "side": {"rotation_euler_deg": dense_spot.SPOTS["side"]["rotation_euler_deg"]},      # normal (0, 0, 1)
    "toward": {"rotation_euler_deg": dense_spot.SPOTS["toward"]["rotation_euler_deg"]},  # (0, -1, 1)/sqrt 2
}

# The cases: an orientation and a fog (dense_spot's).  T = density x DISTANCE_M.
CASES = {
    "side": {"area": "side", "density": 0.3, "anisotropy": 0.85, "albedo": 0.9},         # T 4.5
    "toward": {"area": "toward", "density": 0.3, "anisotropy": 0.85, "albedo": 0.9},     # T 4.5
    "side_thin": {"area": "side", "density": 0.1, "anisotropy": 0.85, "albedo": 0.9},    # T 1.5
}

# The cached references (tests/references/dense_area_*): (case, volume bounces, samples per render, seeds), in
# the order --cases renders them.
REFERENCE_RUNS = [
    ("side", 64, 2048, 2),
    ("side", 0, 2048, 2),
    ("toward", 64, 2048, 2),
    ("toward", 0, 2048, 2),
    ("side_thin", 64, 2048, 2),
    ("side_thin", 0, 2048, 2),
]

QUADRATURE_PIXELS = 30         # the single-scattering check: random front pixels
QUADRATURE_SEED = 0


def _area_name(case):
    """The AREAS key of a case name or of an orientation name."""
    if case in AREAS:
        return case
    return CASES[case]["area"]


def area_rotation(case):
    """3 x 3 world rotation of the area light of a case or orientation name."""
    return area_lights.euler_xyz_matrix(AREAS[_area_name(case)]["rotation_euler_deg"])


def area_normal(case):
    """Unit world normal of the area light's emitting side (its local -Z) for a case or orientation name."""
    n = area_rotation(case) @ np.array([0.0, 0.0, -1.0])
    return n / np.linalg.norm(n)


def radiant_intensity(cos_normal, power=POWER_W):
    """Far-field radiant intensity (W/sr) of the area light at cosine ``cos_normal`` from its normal:
    (P / pi) max(cos, 0) (Blender 5.0, normalize on, spread 180 degrees)."""
    return float(power) / math.pi * np.maximum(np.asarray(cos_normal, dtype=np.float64), 0.0)


camera_position = dense_spot.camera_position
pixel_rays = dense_spot.pixel_rays


def front_mask(case, reach_mfp=REACH_MFP, resolution=RESOLUTION):
    """(H, W) bool: the pixel's centre ray passes through the emitter's front half-space ((X - lamp) . n > 0,
    lamp at the origin) at a point within ``reach_mfp`` mean free paths (reach_mfp / density m) of the lamp
    (``reach_mfp`` None: at any distance up to the clip end).  Exact: on the ray's interval with |P| <= reach
    and s >= 0, P . n is linear in s, so it is positive somewhere iff it is at one of the interval's ends."""
    spec = CASES[case] if case in CASES else {"area": case, "density": None}
    n = area_normal(spec["area"])
    reach = CLIP_END_M if reach_mfp is None else float(reach_mfp) / float(spec["density"])
    d = pixel_rays(resolution)
    cam = camera_position()
    cn, dn, cd, cc = float(cam @ n), d @ n, d @ cam, float(cam @ cam)
    disc = cd * cd - (cc - reach * reach)          # |P|^2 = s^2 + 2 s C.d + |C|^2 <= reach^2
    root = np.sqrt(np.maximum(disc, 0.0))
    lo = np.maximum(0.0, -cd - root)
    hi = np.minimum(CLIP_END_M, -cd + root)
    ok = (disc > 0.0) & (hi > lo)
    return ok & (np.maximum(cn + lo * dn, cn + hi * dn) > 0.0)


# -- the scene (bpy, in a Blender process) ----------------------------------------------------------------------

def build(scene, case, resolution=RESOLUTION):
    """Fill ``scene``: :func:`fog_scenes.dense.build`'s scene (DISTANCE_M) whose lamp is then made a square AREA
    light of AREA_SIZE_M and POWER_W (normalize on, spread 180 degrees, invisible to the camera) turned as
    AREAS[case's orientation], clip end CLIP_END_M.  Needs bpy."""
    import bpy
    spec = AREAS[_area_name(case)]
    dense.build(scene, DISTANCE_M, POWER_W, 0.0, resolution)
    ob = bpy.data.objects[LAMP_NAME]
    old = ob.data
    light = bpy.data.lights.new(LAMP_NAME + "Area", 'AREA')
    light.energy = POWER_W
    light.shape = 'SQUARE'
    light.size = AREA_SIZE_M
    light.size_y = AREA_SIZE_M
    light.spread = math.pi
    light.normalize = True
    light.use_shadow = True
    light.color = (1.0, 1.0, 1.0)
    ob.data = light
    bpy.data.lights.remove(old)
    ob.visible_camera = False
    ob.rotation_mode = 'XYZ'
    ob.rotation_euler = tuple(math.radians(v) for v in spec["rotation_euler_deg"])
    ob.scale = (1.0, 1.0, 1.0)
    scene.camera.data.clip_end = CLIP_END_M
    bpy.context.view_layer.update()
    n = -ob.matrix_world.to_3x3().col[2]
    want = area_normal(case)
    assert max(abs(a - b) for a, b in zip(n.normalized(), want)) < 1e-6, (tuple(n), want)
    return scene


def blend_path(case, workdir=None):
    """Path of the case's .blend (one per orientation) in ``workdir`` (default: the harness's scratch folder),
    built if missing."""
    name = _area_name(case)
    workdir = pathlib.Path(workdir) if workdir else pathlib.Path(h._env()["TMPDIR"]) / "fog_dense_area"
    workdir.mkdir(parents=True, exist_ok=True)
    blend = workdir / f"dense_area_{name}_d{DISTANCE_M:g}_P{POWER_W:g}_s{AREA_SIZE_M:g}.blend"
    if not blend.is_file():
        h.run(["-m", "fog_scenes.dense_area", blend, "--case", name])
    return blend


# -- references -------------------------------------------------------------------------------------------------

def reference_name(case, volume_bounces, samples, seeds, resolution=RESOLUTION):
    """File name of a cached reference: ``dense_area_<orientation>_d15_beta.._g.._a.._vbN_P250_s0.2_WxH_
    <spp>spp_x<seeds>.exr`` (dense.py's name of the same fog, the lamp radius tag replaced by the square's
    side)."""
    c = CASES[case]
    w, hh = resolution
    return (f"dense_area_{c['area']}_d{DISTANCE_M:g}_beta{float(c['density']):g}_g{float(c['anisotropy']):g}"
            f"_a{float(c['albedo']):g}_vb{int(volume_bounces)}_P{POWER_W:g}_s{AREA_SIZE_M:g}_{w}x{hh}"
            f"_{int(samples)}spp_x{int(seeds)}.exr")


class BudgetExhausted(RuntimeError):
    """A seed's render would have started after the deadline given to :func:`render_reference`."""


def render_reference(case, volume_bounces=64, samples=2048, seeds=2, regen=False, directory=None, times=None,
                     deadline=None):
    """Path of the cached Cycles reference of ``case`` (CASES), rendering it if missing (or ``regen``).

    ``volume_bounces`` N (0: single scattering; N > 0: multiple, max_bounces = N), ``samples`` spp per render,
    ``seeds`` renders (seeds 0 .. seeds-1) averaged, each by :func:`fog_scenes.dense.render_reference_seed` and
    kept beside the mean (:func:`fog_scenes.dense.seed_path`), reused unless ``regen``.  Cached as ``directory``
    (default tests/references) / :func:`reference_name`.  ``times``: a list to which each new render's seconds
    are appended.  ``deadline`` (time.time() seconds): raise :class:`BudgetExhausted` instead of starting a
    seed's render after it (the seeds already rendered stay)."""
    directory = pathlib.Path(directory) if directory else h.REFERENCES
    path = directory / reference_name(case, volume_bounces, samples, seeds)
    if path.is_file() and not regen:
        return path

    def before_seed(seed):
        if deadline is not None and time.time() > deadline:
            raise BudgetExhausted(f"{path.name}: seed {seed} not started (budget spent)")

    return dense_spot.render_case(path, blend_path(case), CASES[case], volume_bounces, samples, seeds, regen, times,
                                  before_seed=before_seed)


CENTRE_RUNS = [("side", 64, 65536, 4)]   # centre crops (``dense_spot.render_crop``): the inner rings, 64x the samples


def centre_reference_name(case, volume_bounces, samples, seeds):
    """File name of a cached centre crop (``dense_spot.crop_name``)."""
    return dense_spot.crop_name(reference_name(case, volume_bounces, samples, seeds))


def render_centre_reference(case, volume_bounces=64, samples=65536, seeds=4, regen=False, directory=None,
                            times=None):
    """Path of the cached Cycles reference of the centre crop about the emitter's image
    (``dense_spot.render_crop``), rendered if missing."""
    directory = pathlib.Path(directory) if directory else h.REFERENCES
    return dense_spot.render_crop(directory / centre_reference_name(case, volume_bounces, samples, seeds),
                                  blend_path(case), CASES[case], volume_bounces, samples, seeds, regen, times)


def seed_images(case, volume_bounces, samples, seeds):
    """The kept per-seed renders of a cached reference, as (H, W, 3) arrays."""
    from fog_addon import imageio
    path = h.REFERENCES / reference_name(case, volume_bounces, samples, seeds)
    return [imageio.read_rgb(dense.seed_path(path, s)) for s in range(int(seeds))]


# -- measures (numpy) -------------------------------------------------------------------------------------------

region_ring_means = dense_spot.region_ring_means
sector_means = dense_spot.sector_means


def _hg(g, mu):
    return (1.0 - g * g) / (4.0 * math.pi * (1.0 + g * g - 2.0 * g * mu) ** 1.5)


def single_scattering_quadrature(case, pixels, resolution=RESOLUTION, extended=False, nodes=48):
    """Single-scattering radiance (W m^-2 sr^-1) of ``case`` at pixel centres ``pixels`` [(x, y)] by adaptive
    quadrature along the pixel-centre ray (scipy).  An independent check of the single-scattering references.

    ``extended`` False (the emitter as a point at its centre): albedo beta int I(w) p_HG(mu) exp(-beta (s + r)) /
    r^2 ds, with r the lamp-point distance, w the lamp-to-point direction, I(w) = (P / pi) max(w . n, 0), mu the
    cosine between w and the direction back to the camera.  ``extended`` True: the square itself, I(w) / r^2
    replaced by the sum over ``nodes`` x ``nodes`` Gauss-Legendre points y of the square of
    L max(cos, 0) exp(-beta |x - y|) / |x - y|^2 dA (L = P / (pi A), the phase at each point's own direction and
    the point's own transmittance): exact to the rule's order where the point is farther from the square than a
    few node spacings (48: within 1e-5 of 96 at 1 px from the lamp's image in ``side``; where the ray crosses
    the square itself, :func:`emitter_pixels`, only to about 1 %)."""
    from scipy.integrate import quad
    c = CASES[case]
    beta, g, a = c["density"], c["anisotropy"], c["albedo"]
    n = area_normal(case)
    rot = area_rotation(case)
    d_all = pixel_rays(resolution)
    cam = camera_position()
    if extended:
        u, wq = np.polynomial.legendre.leggauss(int(nodes))
        u, wq = 0.5 * AREA_SIZE_M * u, 0.5 * AREA_SIZE_M * wq
        uu, vv = np.meshgrid(u, u, indexing="ij")
        ys = uu.ravel()[:, None] * rot[:, 0] + vv.ravel()[:, None] * rot[:, 1]      # (N, 3) points on the square
        wy = np.outer(wq, wq).ravel()
        radiance = POWER_W / (math.pi * AREA_SIZE_M * AREA_SIZE_M)
    out = []
    for x, y in pixels:
        d = d_all[int(y), int(x)]

        if extended:
            def f(s, d=d):
                p = cam + s * d
                v = p - ys
                r = np.sqrt((v * v).sum(axis=1))
                w = v / r[:, None]
                cos_l = np.maximum(w @ n, 0.0)
                mu = -(w @ d)
                val = radiance * wy * cos_l * _hg(g, mu) * np.exp(-beta * r) / (r * r)
                return float(val.sum()) * math.exp(-beta * s)
        else:
            def f(s, d=d):
                p = cam + s * d
                r = float(np.linalg.norm(p))
                w = p / r
                return float(radiant_intensity(w @ n)) * _hg(g, float(-w @ d)) * math.exp(-beta * (s + r)) / (r * r)
        # closest approach to the lamp: split there (the integrand peaks near it), at scales of the miss distance
        s0 = float(-cam @ d)
        b = float(np.linalg.norm(cam + s0 * d))
        steps = [0.5 * b, b, 3.0 * b, 0.5, 2.0, 20.0, 120.0]
        pts = [0.0, s0] + [s0 + k for k in steps] + [s0 - k for k in steps]
        # where the ray crosses the emitter's plane (the Lambertian factor's kink)
        dn = float(d @ n)
        if dn != 0.0:
            pts.append(float(-(cam @ n) / dn))
        pts = sorted(set(p for p in pts if 0.0 <= p <= CLIP_END_M))
        total = sum(quad(f, lo, hi, limit=400, epsabs=0.0, epsrel=1e-8)[0] for lo, hi in zip(pts[:-1], pts[1:]))
        out.append(a * beta * total)
    return np.array(out)


def emitter_pixels(case, margin_m=0.0, resolution=RESOLUTION):
    """(H, W) bool: pixels whose centre ray crosses the (invisible) emitter's square, grown by ``margin_m`` m on
    every side (none in ``side``: the camera lies in its plane)."""
    rot = area_rotation(case)
    nz = rot[:, 2]
    d = pixel_rays(resolution)
    cam = camera_position()
    with np.errstate(divide="ignore", invalid="ignore"):
        t = -(cam @ nz) / (d @ nz)
    q = cam + t[..., None] * d
    hs = 0.5 * AREA_SIZE_M + float(margin_m)
    return np.isfinite(t) & (t > 0) & (np.abs(q @ rot[:, 0]) <= hs) & (np.abs(q @ rot[:, 1]) <= hs)


def quadrature_pixels(case, count=QUADRATURE_PIXELS, seed=QUADRATURE_SEED):
    """``count`` random pixels (x, y) of :func:`front_mask` (numpy default_rng(seed), without replacement)."""
    ys, xs = np.nonzero(front_mask(case))
    rng = np.random.default_rng(seed)
    pick = rng.choice(len(xs), size=min(int(count), len(xs)), replace=False)
    return [(int(xs[i]), int(ys[i])) for i in pick]


def quadrature_check(case, run=None, count=QUADRATURE_PIXELS, seed=QUADRATURE_SEED):
    """Single-scattering reference (``run``, default the case's 0-bounce entry of REFERENCE_RUNS) against
    :func:`single_scattering_quadrature` at :func:`quadrature_pixels`: a dict with the pixels, their radii (px
    from the lamp's image), the reference's luminance and the point and extended quadratures' (luminance = the
    radiance, the light being white), and their ratios; "on_emitter": the pixel's ray crosses the square."""
    from fog_addon import imageio
    run = run or next(r for r in REFERENCE_RUNS if r[0] == case and r[1] == 0)
    ss = dense.luminance(imageio.read_rgb(h.REFERENCES / reference_name(*run)))
    px = quadrature_pixels(case, count, seed)
    ref = np.array([ss[y, x] for x, y in px])
    q_point = single_scattering_quadrature(case, px)
    q_ext = single_scattering_quadrature(case, px, extended=True)
    c = dense.lamp_image_centre()
    radii = np.array([math.hypot(x + 0.5 - c[0], y + 0.5 - c[1]) for x, y in px])
    on_emitter = emitter_pixels(case)
    return {"pixels": px, "radii": radii, "on_emitter": np.array([bool(on_emitter[y, x]) for x, y in px]),
            "ref": ref, "point": q_point, "extended": q_ext,
            "ratio_point": ref / q_point, "ratio_extended": ref / q_ext}


def case_summary(case, ms_run=None, ss_run=None):
    """Ring and region figures of a case from its cached references (REFERENCE_RUNS by default): a dict of
    numpy arrays and floats (see :func:`print_summary`).  "in" is :func:`front_mask`, "out" its complement."""
    from fog_addon import imageio
    ms_run = ms_run or next(r for r in REFERENCE_RUNS if r[0] == case and r[1] > 0)
    ss_run = ss_run or next(r for r in REFERENCE_RUNS if r[0] == case and r[1] == 0)
    ms = imageio.read_rgb(h.REFERENCES / reference_name(*ms_run))
    ss = imageio.read_rgb(h.REFERENCES / reference_name(*ss_run))
    c = dense.lamp_image_centre()
    mask = front_mask(case)
    lit = dense.luminance(ss) > 0
    out = {"mask_pixels": int(mask.sum()), "mask_pixels_any_reach": int(front_mask(case, None).sum()),
           "ss_lit_pixels": int(lit.sum()), "ss_lit_outside_mask": int((lit & ~front_mask(case, None)).sum()),
           "mask_outside_ss_lit": int((~lit & front_mask(case, None)).sum())}
    for name, img in (("ms", ms), ("ss", ss)):
        out[name + "_rings"], out[name + "_kept"], out[name + "_dropped"] = dense.ring_means(
            img, c, return_counts=True)
        out[name + "_rings_all"] = dense.ring_means(img, c, firefly=None)
        out[name + "_in"] = region_ring_means(img, c, mask)
        out[name + "_out"] = region_ring_means(img, c, ~mask)
        lum = dense.luminance(img)
        out[name + "_whole"] = float(lum.mean())
        out[name + "_mask_mean"] = float(lum[mask].mean()) if mask.any() else float("nan")
        out[name + "_outside_mean"] = float(lum[~mask].mean()) if (~mask).any() else float("nan")
    seeds = seed_images(*ms_run)
    per_in = np.array([region_ring_means(s, c, mask)[0] for s in seeds])
    per_out = np.array([region_ring_means(s, c, ~mask)[0] for s in seeds])
    n = len(seeds)
    with np.errstate(invalid="ignore", divide="ignore"):
        for name, arr in (("_in", per_in), ("_out", per_out)):
            out["ms_rel_se" + name] = np.std(arr, axis=0, ddof=1) / math.sqrt(n) / np.mean(arr, axis=0)
    wh = np.array([dense.luminance(s).mean() for s in seeds])
    out["ms_whole_rel_se"] = float(np.std(wh, ddof=1) / math.sqrt(n) / wh.mean())
    ss_seeds = seed_images(*ss_run)
    per_ss = np.array([region_ring_means(s, c, mask)[0] for s in ss_seeds])
    with np.errstate(invalid="ignore", divide="ignore"):
        out["ss_rel_se_in"] = np.std(per_ss, axis=0, ddof=1) / math.sqrt(len(ss_seeds)) / np.mean(per_ss, axis=0)
    return out


def print_summary(case):
    """Print :func:`case_summary` and :func:`quadrature_check` as text tables."""
    s = case_summary(case)
    labels = dense.ring_labels()
    np.set_printoptions(linewidth=160)
    print(f"== {case}: {CASES[case]}  normal {np.round(area_normal(case), 4)}")
    print(f"front mask pixels (reach {REACH_MFP:g} mfp) {s['mask_pixels']}, any reach {s['mask_pixels_any_reach']}, "
          f"SS > 0 pixels {s['ss_lit_pixels']} (outside mask {s['ss_lit_outside_mask']}, mask but dark "
          f"{s['mask_outside_ss_lit']})")
    print("ring          " + "  ".join(f"{l:>10}" for l in labels))
    with np.errstate(invalid="ignore", divide="ignore"):
        rows = [("ms all", s["ms_rings_all"]), ("ss all", s["ss_rings_all"]),
                ("ms/ss all", s["ms_rings_all"] / s["ss_rings_all"]),
                ("ms front", s["ms_in"][0]), ("ss front", s["ss_in"][0]),
                ("ms/ss front", s["ms_in"][0] / s["ss_in"][0]),
                ("ms behind", s["ms_out"][0]), ("ss behind", s["ss_out"][0]),
                ("ms/ss behind", s["ms_out"][0] / s["ss_out"][0]),
                ("ms se fr %", 100 * s["ms_rel_se_in"]), ("ms se be %", 100 * s["ms_rel_se_out"]),
                ("ss se fr %", 100 * s["ss_rel_se_in"])]
    for name, v in rows:
        print(f"{name:<13} " + "  ".join(f"{x:10.4g}" for x in v))
    print("dropped ms", s["ms_dropped"], "ss", s["ss_dropped"], "| front ms", s["ms_in"][2], "ss", s["ss_in"][2],
          "| behind ms", s["ms_out"][2], "| front kept", s["ms_in"][1], "behind kept", s["ms_out"][1])
    print(f"whole: ms {s['ms_whole']:.5g} ss {s['ss_whole']:.5g} ratio {s['ms_whole'] / s['ss_whole']:.4g} "
          f"(ms se {100 * s['ms_whole_rel_se']:.2f} %)")
    print(f"front: ms {s['ms_mask_mean']:.5g} ss {s['ss_mask_mean']:.5g} ratio "
          f"{s['ms_mask_mean'] / s['ss_mask_mean']:.4g}; behind: ms {s['ms_outside_mean']:.5g} "
          f"ss {s['ss_outside_mean']:.5g}", flush=True)
    q = quadrature_check(case)
    for k in ("point", "extended"):
        r = q["ratio_" + k]
        print(f"SS / quadrature ({k}) at {len(r)} front pixels: median {np.median(r):.5f} "
              f"min {r.min():.5f} max {r.max():.5f} (p5 {np.percentile(r, 5):.5f} p95 {np.percentile(r, 95):.5f})")
    order = np.argsort(q["radii"])
    print("  r px  " + " ".join(f"{v:7.1f}" for v in q["radii"][order]))
    print("  point " + " ".join(f"{v:7.4f}" for v in q["ratio_point"][order]))
    print("  ext   " + " ".join(f"{v:7.4f}" for v in q["ratio_extended"][order]))
    print("  on emitter " + str([q["pixels"][i] for i in order if q["on_emitter"][i]]), flush=True)
    return s, q


def main(argv=None):
    p = argparse.ArgumentParser(description="build an area-light-in-dense-fog case's .blend, or render the references")
    p.add_argument("out", nargs="?", help="the .blend to write")
    p.add_argument("--case", default="side", help="a CASES or AREAS name (the .blend depends only on the orientation)")
    p.add_argument("--cases", action="store_true", help="render REFERENCE_RUNS if missing, print their tables")
    p.add_argument("--only", default=None, help="with --cases: a comma-separated list of cases")
    p.add_argument("--budget-minutes", type=float, default=None,
                   help="with --cases: start no seed's render after this many minutes")
    p.add_argument("--no-summary", action="store_true", help="with --cases: render only")
    a = p.parse_args(argv)
    if a.cases:
        only = set(a.only.split(",")) if a.only else None
        deadline = time.time() + 60.0 * a.budget_minutes if a.budget_minutes else None
        done, missing = [], []
        for run in REFERENCE_RUNS:
            if only and run[0] not in only:
                continue
            if missing:
                missing.append(run)
                continue
            times = []
            try:
                ref = render_reference(*run, times=times, deadline=deadline)
            except BudgetExhausted as exc:
                print("BUDGET", exc, "render seconds", times, flush=True)
                missing.append(run)
                continue
            print(ref.name, "render seconds", times, flush=True)
            done.append(run)
        for run in CENTRE_RUNS:
            if not missing and (not only or run[0] in only):
                times = []
                print(render_centre_reference(*run, times=times).name, "render seconds", times, flush=True)
        if missing:
            print("MISSING", missing, flush=True)
        if not a.no_summary:
            for case in dict.fromkeys(r[0] for r in done):
                if sum(r[0] == case for r in done) == 2:
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
