"""Surfaces in dense fog (issue 28): a grey ground and wall lit by a point lamp in fog of optical thickness ~3,
path-traced references with and without volume bounces, and the region metrics that compare our renders to them.

The scene: a large grey diffuse ground (z = 0), a grey wall behind the lamp (its face the plane y = WALL_Y,
facing the camera), one 1000 W point lamp (radius 0) LAMP_HEIGHT m above the ground at the origin's x, y, and the
camera CAMERA_DISTANCE m in front of the lamp at CAMERA_HEIGHT m looking at it; World black.  The material is a
Principled BSDF with base colour 0.5, roughness 1 and Specular IOR Level 0 (Lambertian: no grazing specular
that the engines would render differently).  At density 0.25/m the lamp is T = 3 from the camera.

References (Cycles World volume, path traced), as ``fog_scenes/dense.py``'s but with surfaces:

* fog of extinction ``density`` and albedo ``albedo``: Volume Scatter (Color white) of density albedo x density
  plus Volume Absorption (Color black) of density (1 - albedo) x density; Henyey-Greenstein g;
* ``volume_bounces`` N, ``diffuse_bounces`` = ``glossy_bounces`` = 1 and ``max_bounces`` = N + 1: a camera ray
  that meets a surface takes the lamp's direct light (through the fog) and one diffuse bounce into the fog, whose
  path then scatters up to N + 1 times, each event sampling the lamp.  N = 0 is ``fog_addon.reference``'s
  single-scattering convention (direct light + the singly scattered fog light a surface receives, Sun et al.
  2005 Sec. 4); N = 64 adds the multiply scattered field's irradiance (0.9^64 = 1e-3 left out);
* the add-on's test conventions, as ``python -m fog_addon reference --no-cast-shadows --no-interreflection``:
  objects hidden from shadow rays (no cast shadows; the lamp keeps its shadows, which carry the fog's
  extinction) and from diffuse/glossy rays (no surface-to-surface light, the fog hemisphere unoccluded); to
  volume-scatter rays they are black (``reference.absorb_scattered_rays``): the ground and the wall stop the
  scattered light, as Dense Fog's scale beside surfaces models (``fog_addon/escape.py``), and reflect none of
  it back into the fog, which the model leaves out (the references before 2026-11-30 hid them from those rays:
  the unbounded medium's field, file names without ABSORBING_TAG);
* clip start 1 mm, pixel-centre filter, no denoising or clamping (``reference.configure_reference``);
* the mean of ``seeds`` renders with Cycles seeds 0, 1, ...

Comparisons (:func:`compare`): the whole picture's relative RMSE (||ours - ref|| / ||ref|| over RGB) with the
lamp's own pixels left out, raw and with each seed's fireflies clipped before the seeds are averaged (a pixel's
RGB scaled down to FIREFLY_FACTOR x the 5x5 median of luminance around it), the same over 4x4 block means, the
part of each that the reference's own noise accounts for, and the mean ratio ours / reference over the ground
and the wall regions (each a band of whole pixel rows, MARGIN_PX rows away from the ground-wall edge, lamp
pixels left out; fireflies clipped as above).

The spot variant (``spot=True`` on :func:`build`, :func:`blend_path`, :func:`reference_name`,
:func:`render_reference`, :func:`reference_seeds`, :func:`render_ours`, :func:`geometry`; ``--spot`` on the
command line): the same scene with the lamp a SPOT of the same power at the same place, pointing straight down
(rotation 0: Blender's spot axis is its local -Z), cone SPOT_SIZE_DEG = 90 degrees (full angle) and blend
SPOT_BLEND = 0.15, radius 0.  Within the cone's core it shines as the point lamp does; the camera, 86 degrees
off the axis, does not see the lamp itself.  Its files carry SPOT_TAG after NAME; the point lamp's names are
unchanged.  :func:`compare` needs no flag: the camera and so :func:`geometry` are the same.
Measurements: docs/measurements/2026-11-28-dense-spot-surface-references.md.

No bpy at import: every Blender job runs in a fresh process through ``render_harness``.  As a script
(``python -m fog_scenes.dense_surfaces OUT.blend [--spot]``) it builds the scene's .blend.
"""
import argparse
import json
import pathlib
import sys

import numpy as np

from fog_scenes import dense
from fog_scenes import render_harness as h

RESOLUTION = (120, 68)         # px
LENS_MM = 28.0                 # on a 36 mm sensor: 65 x 39 degrees
LAMP_POWER_W = 1000.0
LAMP_HEIGHT = 2.5              # m above the ground
CAMERA_DISTANCE = 12.0         # m, horizontal, camera to lamp
CAMERA_HEIGHT = 1.7            # m
WALL_Y = 3.0                   # m behind the lamp: the wall's face
WALL_HEIGHT = 12.0             # m
BASE_COLOR = 0.5
DENSITY = 0.25                 # 1/m: T = 3.0 camera-lamp
ANISOTROPY = 0.85
ALBEDO = 0.9
FIREFLY_FACTOR = 20.0          # a reference pixel above this x its 5x5 median luminance is clipped to it
LAMP_HALF_PX = 1.5             # pixels of the lamp's image left out: centres within this in x and y
BLOCK_PX = 4                   # block means for a whole-picture RMSE that survives the references' noise
MARGIN_PX = 1                  # rows next to the ground-wall edge left out of both regions
NAME = "dense_surfaces"
SPOT_SIZE_DEG = 90.0           # the spot variant: full cone angle (Blender's spot_size), axis straight down
SPOT_BLEND = 0.15
SPOT_TAG = "_spot90"           # in the spot variant's file names, after NAME

# The cached references (tests/references): (volume bounces, samples per render, seeds); the same for the
# spot variant (spot=True).
REFERENCE_CASES = [(64, 2048, 4), (0, 2048, 2)]


def _tag(spot):
    return SPOT_TAG if spot else ""


# -- the scene (bpy, in a Blender process) ----------------------------------------------------------------------

def build(scene, resolution=RESOLUTION, power=LAMP_POWER_W, spot=False):
    """Fill ``scene`` (see the module doc); ``spot``: the lamp is the spot variant's.  Needs bpy."""
    from demo_scenes import add_box_between, add_camera, add_plane, add_point_light, material, render_settings, \
        set_world
    render_settings(scene, resolution=resolution)
    set_world(scene, color=(0.0, 0.0, 0.0))
    grey = material("Grey", (BASE_COLOR,) * 3, roughness=1.0, specular_ior_level=0.0)
    add_plane(scene, "Ground", -60.0, 60.0, -40.0, 60.0, 0.0, grey)
    # the wall: its face at y = WALL_Y, its foot under the ground (no face coplanar with the ground)
    add_box_between(scene, "Wall", -40.0, 40.0, WALL_Y, WALL_Y + 0.2, -0.5, WALL_HEIGHT, grey)
    lamp = add_point_light(scene, "Lamp", (0.0, 0.0, LAMP_HEIGHT), float(power))
    lamp.data.shadow_soft_size = 0.0
    if spot:   # (the point lamp's radius is 0, so is the spot's; rotation 0: the axis, local -Z, straight down)
        from fog_scenes import dense_spot
        old_name = lamp.data.name
        dense_spot.as_spot(lamp, SPOT_SIZE_DEG, SPOT_BLEND, (0.0, 0.0, 0.0), old_name + " Spot")
        lamp.data.name = old_name
    cam = add_camera(scene, (0.0, -CAMERA_DISTANCE, CAMERA_HEIGHT), (0.0, 0.0, LAMP_HEIGHT), lens=LENS_MM)
    cam.data.sensor_width = 36.0
    cam.data.clip_start = 0.001
    cam.data.clip_end = 1000.0
    scene.view_settings.view_transform = 'Standard'
    return scene


def blend_path(workdir=None, spot=False):
    """Path of the scene's .blend in ``workdir`` (default: the harness's scratch folder), built if missing;
    ``spot``: the spot variant's."""
    workdir = pathlib.Path(workdir) if workdir else pathlib.Path(h._env()["TMPDIR"]) / "fog_dense_surfaces"
    workdir.mkdir(parents=True, exist_ok=True)
    blend = workdir / f"{NAME}{_tag(spot)}_{RESOLUTION[0]}x{RESOLUTION[1]}.blend"
    if not blend.is_file():
        h.run(["-m", "fog_scenes.dense_surfaces", blend] + (["--spot"] if spot else []))
    return blend


# -- references -----------------------------------------------------------------------------------------------

_REFERENCE_CODE = r'''
import sys, json, time
import bpy
from fog_addon import measure, reference
a = json.loads(sys.argv[1])
scene = measure.open_scene(a["blend"])
measure.set_resolution(scene, *a["resolution"])
beta, albedo, g, n = a["density"], a["albedo"], a["anisotropy"], a["volume_bounces"]
reference.configure_reference(scene, beta * albedo, anisotropy=g, samples=a["samples"], single_scattering=True)
reference.add_black_absorption(scene, beta * (1.0 - albedo))
reference.disable_cast_shadows(scene)
reference.disable_interreflection(scene)
reference.absorb_scattered_rays(scene)
c = scene.cycles
c.volume_bounces = n
c.diffuse_bounces = c.glossy_bounces = 1
c.transmission_bounces = 0
c.max_bounces = n + 1              # max_bounces caps volume bounces too; + 1 for the surface's bounce
c.seed = a["seed"]
c.use_animated_seed = False
assert abs(scene.camera.data.clip_start - 0.001) < 1e-9
t0 = time.perf_counter()
measure.render_to_file(scene, a["out"])
print("RENDER_SECONDS %.2f" % (time.perf_counter() - t0))
'''


ABSORBING_TAG = "_absorbing"   # a multiple-scattering reference whose surfaces absorb the scattered light


def reference_name(volume_bounces, samples, seeds, density=DENSITY, anisotropy=ANISOTROPY, albedo=ALBEDO,
                   resolution=RESOLUTION, spot=False):
    """File name of a cached reference, its parameters in it (``spot``: SPOT_TAG after NAME)."""
    w, hh = resolution
    walls = ABSORBING_TAG if volume_bounces > 0 else ""
    return (f"{NAME}{_tag(spot)}_beta{float(density):g}_g{float(anisotropy):g}_a{float(albedo):g}"
            f"_vb{int(volume_bounces)}{walls}_{w}x{hh}_{int(samples)}spp_x{int(seeds)}.exr")


def render_reference(volume_bounces, samples, seeds, density=DENSITY, anisotropy=ANISOTROPY, albedo=ALBEDO,
                     regen=False, directory=None, times=None, timeout=900, spot=False, log=None):
    """Path of the cached Cycles reference (see the module doc), rendering missing seeds (kept beside it as
    ``dense.seed_path``).  ``times``: a list to which each new render's seconds are appended; ``log``: one to
    which each new render's stdout + stderr is appended.  ``spot``: the spot variant's."""
    directory = pathlib.Path(directory) if directory else h.REFERENCES
    path = directory / reference_name(volume_bounces, samples, seeds, density, anisotropy, albedo, spot=spot)
    if path.is_file() and not regen:
        return path
    blend = blend_path(spot=spot)

    def render_seed(seed, out):
        args = dict(blend=str(blend), out=str(out), density=float(density), anisotropy=float(anisotropy),
                    albedo=float(albedo), volume_bounces=int(volume_bounces), samples=int(samples), seed=seed,
                    resolution=list(RESOLUTION))
        proc = h.run(["-c", _REFERENCE_CODE, json.dumps(args)], timeout=timeout)
        if log is not None:
            log.append(proc.stdout + "\n" + proc.stderr)
        return h.render_seconds(proc)

    return h.mean_of_seeds(path, render_seed, seeds, regen, times)


def reference_seeds(volume_bounces, samples, seeds, regen=False, **kw):
    """The seeds' renders (list of (H, W, 3) arrays) of the cached reference (:func:`render_reference`)."""
    from fog_addon import imageio
    path = render_reference(volume_bounces, samples, seeds, regen=regen, **kw)
    return [imageio.read_rgb(dense.seed_path(path, i)) for i in range(int(seeds))]


def render_ours(out, multiple_scattering="on", method="compositor", density=DENSITY, anisotropy=ANISOTROPY,
                albedo=ALBEDO, log=None, spot=False):
    """Our render of the scene (``python -m fog_addon render``, Cycles, pixel centres, no cast shadows, no
    interreflection, no light shafts: the references' conventions); returns the path of ``out``.  ``spot``: the
    spot variant's scene."""
    args = ("--anisotropy", repr(float(anisotropy)), "--color", ",".join([repr(float(albedo))] * 3),
            "--multiple-scattering", multiple_scattering, "--shafts", "off")
    return h.render_test(NAME, density, out, engine="cycles", method=method, resolution=RESOLUTION,
                         blend=blend_path(spot=spot), extra=args, log=log)


# -- regions and metrics (numpy) ------------------------------------------------------------------------------

def geometry(blend=None, spot=False):
    """{'lamp': (x, y) px of the lamp's image, 'edge_y': y px (from the top) of the ground-wall edge} by Blender's
    projection of the scene's camera (the same in the spot variant)."""
    blend = blend or blend_path(spot=spot)
    pts = [(0.0, 0.0, LAMP_HEIGHT), (-1.0, WALL_Y, 0.0), (1.0, WALL_Y, 0.0)]
    (lx, ly), (_, e0), (_, e1) = dense.project_from_blend(blend, pts, RESOLUTION)
    return {"lamp": (lx, ly), "edge_y": 0.5 * (e0 + e1)}


def masks(geom, shape=None):
    """{'picture', 'ground', 'wall'}: boolean (H, W) masks.  'picture' is every pixel but the lamp's (those whose
    centres lie within LAMP_HALF_PX of its image in x and y: 3x3 if it falls on a pixel centre, 4x4 on a
    corner); the ground is the rows whose centres lie more than MARGIN_PX below the edge, the wall those more
    than MARGIN_PX above it, both without the lamp's pixels."""
    w, hh = RESOLUTION if shape is None else (shape[1], shape[0])
    yc, xc = np.mgrid[0:hh, 0:w] + 0.5
    lx, ly = (round(float(v), 3) for v in geom["lamp"])
    picture = ~((np.abs(xc - lx) <= LAMP_HALF_PX) & (np.abs(yc - ly) <= LAMP_HALF_PX))
    ground = picture & (yc > geom["edge_y"] + MARGIN_PX)
    wall = picture & (yc < geom["edge_y"] - MARGIN_PX)
    return {"picture": picture, "ground": ground, "wall": wall}


def clip_fireflies(image, factor=FIREFLY_FACTOR, size=5):
    """``image`` (H, W, 3) with every pixel whose luminance exceeds ``factor`` x the median luminance of the
    size x size pixels around it scaled down to that bound; returns (clipped image, number of pixels clipped)."""
    from scipy.ndimage import median_filter
    a = np.asarray(image, dtype=np.float64)[..., :3]
    lum = dense.luminance(a)
    bound = factor * median_filter(lum, size=size, mode="nearest")
    hot = lum > bound
    scale = np.ones_like(lum)
    scale[hot] = bound[hot] / lum[hot]
    return a * scale[..., None], int(hot.sum())


def rel_rmse(ours, ref, mask=None):
    """||ours - ref|| / ||ref|| over the RGB of the pixels in ``mask`` (None: every one)."""
    a, b = np.asarray(ours, np.float64)[..., :3], np.asarray(ref, np.float64)[..., :3]
    if mask is not None:
        a, b = a[mask], b[mask]
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


def block_means(image, mask, size=BLOCK_PX):
    """(blocks, 3) RGB means of the size x size pixel blocks (from the top-left corner) that lie whole in
    ``mask``."""
    a = np.asarray(image, np.float64)[..., :3]
    hh, w = (a.shape[0] // size) * size, (a.shape[1] // size) * size
    b = a[:hh, :w].reshape(hh // size, size, w // size, size, 3).mean(axis=(1, 3))
    keep = np.asarray(mask)[:hh, :w].reshape(hh // size, size, w // size, size).all(axis=(1, 3))
    return b[keep]


def compare(ours, seeds, geom):
    """Dict of the comparison figures of ``ours`` against a reference given as its seeds' renders ``seeds``
    (a list of (H, W, >=3) arrays; one array is taken as a single seed):

    * rel_rmse_raw: relative RMSE against the plain mean of the seeds, lamp pixels left out;
    * rel_rmse_clipped: the same against the mean of the seeds each with its fireflies clipped
      (:func:`clip_fireflies`); clipped: the pixels clipped over all seeds;
    * rel_rmse_blocks: the relative RMSE of the BLOCK_PX x BLOCK_PX block means (clipped reference; blocks
      touching the lamp's pixels left out);
    * noise_clipped, noise_blocks (two seeds or more): the relative RMSE the clipped reference's own noise
      accounts for (:func:`reference_noise`), and excess_clipped, excess_blocks: sqrt(rmse^2 - noise^2) (0 when
      the noise accounts for all of it), the error left to ours;
    * ground_ratio, wall_ratio: mean luminance ours / clipped reference over the region; ground_ref, wall_ref:
      the clipped reference's region means.
    """
    seeds = [seeds] if np.asarray(seeds[0]).ndim == 2 else list(seeds)
    m = masks(geom, np.asarray(seeds[0]).shape)
    ours = np.asarray(ours, np.float64)[..., :3]
    raw = np.mean([np.asarray(a, np.float64)[..., :3] for a in seeds], axis=0)
    clipped = [clip_fireflies(a) for a in seeds]
    refc = np.mean([c[0] for c in clipped], axis=0)
    out = {"rel_rmse_raw": rel_rmse(ours, raw, m["picture"]),
           "rel_rmse_clipped": rel_rmse(ours, refc, m["picture"]),
           "clipped": int(sum(c[1] for c in clipped)),
           "rel_rmse_blocks": rel_rmse(block_means(ours, m["picture"]), block_means(refc, m["picture"]))}
    if len(seeds) > 1:
        for kind, blocks in (("clipped", False), ("blocks", True)):
            noise = reference_noise(seeds, geom, clip=True, blocks=blocks)
            out[f"noise_{kind}"] = noise
            out[f"excess_{kind}"] = float(np.sqrt(max(out[f"rel_rmse_{kind}"] ** 2 - noise ** 2, 0.0)))
    for region in ("ground", "wall"):
        lo, lr = dense.luminance(ours)[m[region]].mean(), dense.luminance(refc)[m[region]].mean()
        out[f"{region}_ratio"] = float(lo / lr)
        out[f"{region}_ref"] = float(lr)
    return out


def reference_noise(seed_images, geom, clip=True, blocks=False):
    """Relative RMSE that the mean of ``seed_images`` (the renders of one reference with different seeds) is
    expected to have against the noiseless picture, over :func:`masks`' 'picture': sqrt(sum of the per-pixel
    sample variance (ddof 1) / seeds) / ||mean||, fireflies clipped in each seed's render first if ``clip``.
    A comparison's relative RMSE against the reference cannot be expected to fall below this.  ``blocks``: the
    same for the BLOCK_PX block means (``compare``'s rel_rmse_blocks)."""
    m = masks(geom, np.asarray(seed_images[0]).shape)["picture"]
    parts = [clip_fireflies(s)[0] if clip else np.asarray(s, np.float64)[..., :3] for s in seed_images]
    parts = np.array([block_means(p, m) if blocks else p[m] for p in parts])
    var = parts.var(axis=0, ddof=1) / len(parts)
    return float(np.sqrt(var.sum()) / np.linalg.norm(parts.mean(axis=0)))


def main(argv=None):
    p = argparse.ArgumentParser(description="build the surfaces-in-dense-fog scene's .blend")
    p.add_argument("out")
    p.add_argument("--spot", action="store_true", help="the spot variant (a 90-degree spot pointing down)")
    a = p.parse_args(argv)
    import bpy
    bpy.ops.wm.read_factory_settings(use_empty=True)
    build(bpy.context.scene, spot=a.spot)
    h.save_blend(a.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
