"""A lamp in dense fog (issue 28): a minimal scene, its path-traced multiple-scattering references and the
annulus profile that compares glows.

The scene is one point lamp of known power at the origin and a camera ``distance`` metres away on -Y looking
straight at it; nothing else, World black.  The lamp's optical distance from the camera is
T = density x distance.  The camera's field of view is set so that one pixel is DEG_PER_PX degrees at the image
centre (the lamp's image), so the annuli 2-50 px around the lamp span 0.2-5 degrees.

References are Cycles' World volume, path traced:

* fog of extinction ``density`` (1/m) and single-scattering albedo ``albedo``: Volume Scatter (Color white) of
  density albedo x density plus Volume Absorption (Color black) of density (1 - albedo) x density.  Volume
  Scatter's Color scales the density (it is not an albedo) and Volume Absorption absorbs density x (1 - Color);
  the add-on's fog colour multiplies the scattered light with the extinction left at ``density``, which is what
  this pair renders;
* Henyey-Greenstein ``anisotropy`` g;
* ``volume_bounces`` N: 0 is single scattering (one scatter event on each path), N > 0 adds up to N more
  volume events (multiple scattering); ``max_bounces`` is set to N as well, since it caps volume bounces too;
* camera clip start 1 mm (Cycles starts camera rays and their fog at the near clip), pixel-centre filter,
  no denoising, no clamping, fixed samples (``fog_addon.reference.set_single_scattering_integrator``);
* the mean of several renders with Cycles seeds 0, 1, ... (each kept under about ten minutes on 2 cores).

Multiple-scattering renders carry fireflies (paths scattering close to the lamp) that no per-pixel metric
survives, and a median is biased low on that skewed noise.  Glows are therefore compared by
:func:`ring_means`: the mean luminance over wide annuli around the lamp's image, leaving out each pixel brighter
than FIREFLY_FACTOR x its annulus' median.

Typical use::

    from fog_scenes import dense
    ref = dense.render_ms_reference(15.0, 0.3, 0.85, 0.9, volume_bounces=64)
    ours = dense.render_ours(15.0, 0.3, 0.85, 0.9, out)
    c = dense.lamp_image_centre()
    dense.ring_means(imageio.read_rgb(ref), c, dense.RING_EDGES_PX)

No bpy at import: every Blender job runs in a fresh process through ``render_harness``.  As a script
(``python -m fog_scenes.dense OUT.blend --distance 15 --power 1000``) it builds the scene's .blend, which
``python -m fog_addon render OUT.blend ...`` renders with the analytic fog.
"""
import argparse
import json
import math
import pathlib
import sys

import numpy as np

from fog_scenes import render_harness as h

RESOLUTION = (120, 120)        # px; even, so the lamp's image falls on a pixel corner, and 50 px fit on all sides
DEG_PER_PX = 0.1               # degrees per pixel at the image centre: 50 px = 5 degrees
SENSOR_WIDTH_MM = 36.0
LAMP_POWER_W = 1000.0          # radiant intensity I0 = P / (4 pi) = 79.6 W/sr
RING_EDGES_PX = (1.5, 3.5, 7.5, 15.0, 30.0, 50.0)   # the annuli of issue 28, radii in pixels from the lamp's image
FIREFLY_FACTOR = 20.0          # a pixel brighter than this x its annulus' median is left out of the annulus' mean
REC709 = (0.2126, 0.7152, 0.0722)

# The cached references (tests/references): (distance m, density 1/m, anisotropy g, albedo, volume bounces,
# samples per render, seeds).  Render times, noise and the ring tables:
# docs/measurements/2026-11-27-dense-fog-references.md.
REFERENCE_CASES = [
    (15.0, 0.3, 0.85, 0.9, 64, 2048, 4),    # issue 28's case, T = 4.5, multiple scattering
    (15.0, 0.3, 0.85, 0.9, 0, 4096, 2),     # the same, single scattering
    (15.0, 0.1, 0.85, 0.9, 64, 2048, 2),    # T = 1.5
    (15.0, 0.1, 0.85, 0.9, 0, 4096, 2),
    (20.0, 0.4, 0.85, 0.9, 64, 2048, 4),    # T = 8
    (20.0, 0.4, 0.85, 0.9, 0, 4096, 2),
]


def lens_mm(resolution=RESOLUTION, deg_per_px=DEG_PER_PX, sensor_width_mm=SENSOR_WIDTH_MM):
    """Focal length (mm) that makes one pixel at the image centre ``deg_per_px`` degrees wide: a pinhole's
    central pixel subtends atan(sensor / (width x lens)) (sensor fit to the image's wider side)."""
    w, hh = resolution
    px_mm = sensor_width_mm / max(w, hh)
    return px_mm / math.tan(math.radians(deg_per_px))


def pixel_angle_deg(r_px, resolution=RESOLUTION, deg_per_px=DEG_PER_PX):
    """Angle (degrees) between the view axis and a ray r_px pixels from the image centre (pinhole)."""
    return math.degrees(math.atan(float(r_px) * math.tan(math.radians(deg_per_px))))


def lamp_image_centre(resolution=RESOLUTION):
    """(x, y) in pixels (x from the left edge, y from the top edge, pixel i's centre at i + 0.5) of the lamp's
    image: the camera aims at the lamp, so it is the image centre.  :func:`lamp_image_centre_from_blend`
    measures it by Blender's projection."""
    w, hh = resolution
    return (0.5 * w, 0.5 * hh)


def optical_distance(distance, density):
    """T = density (1/m) x distance (m): the lamp's optical distance from the camera."""
    return float(density) * float(distance)


# -- the scene (bpy, in a Blender process) ----------------------------------------------------------------------

def build(scene, distance=15.0, power=LAMP_POWER_W, lamp_radius=0.0, resolution=RESOLUTION):
    """Fill ``scene``: a point lamp of ``power`` W and radius ``lamp_radius`` m at the origin, the camera at
    (0, -distance, 0) looking along +Y at it (clip 1 mm to 1e5 m), World black, Cycles.  Needs bpy."""
    from demo_scenes import add_camera, add_point_light, render_settings, set_world
    render_settings(scene, resolution=resolution)
    set_world(scene, color=(0.0, 0.0, 0.0))
    lamp = add_point_light(scene, "Lamp", (0.0, 0.0, 0.0), float(power))
    lamp.data.shadow_soft_size = float(lamp_radius)
    cam = add_camera(scene, (0.0, -float(distance), 0.0), (0.0, 0.0, 0.0), lens=lens_mm(resolution))
    cam.data.sensor_width = SENSOR_WIDTH_MM
    cam.data.clip_end = 1.0e5
    scene.view_settings.view_transform = 'Standard'
    return scene


def blend_path(distance, power=LAMP_POWER_W, lamp_radius=0.0, workdir=None):
    """Path of the scene's .blend in ``workdir`` (default: the harness's scratch folder), built if missing."""
    workdir = pathlib.Path(workdir) if workdir else pathlib.Path(h._env()["TMPDIR"]) / "fog_dense"
    workdir.mkdir(parents=True, exist_ok=True)
    blend = workdir / f"dense_d{float(distance):g}_P{float(power):g}_r{float(lamp_radius):g}.blend"
    if not blend.is_file():
        h.run(["-m", "fog_scenes.dense", blend, "--distance", repr(float(distance)), "--power",
               repr(float(power)), "--lamp-radius", repr(float(lamp_radius))])
    return blend


_PROJECT_CODE = r'''
import sys, json, bpy
from mathutils import Vector
from bpy_extras.object_utils import world_to_camera_view
bpy.ops.wm.open_mainfile(filepath=sys.argv[1])
scene = bpy.context.scene
w, h = int(sys.argv[2]), int(sys.argv[3])
scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = w, h, 100
pts = json.loads(sys.argv[4]) or [list(bpy.data.objects["Lamp"].matrix_world.translation)]
out = []
for p in pts:
    v = world_to_camera_view(scene, scene.camera, Vector(p))
    out.append([v.x * w, (1.0 - v.y) * h])
print("PROJECTED " + json.dumps(out))
'''


def project_from_blend(blend, points=None, resolution=RESOLUTION):
    """[(x, y)] pixels (as :func:`lamp_image_centre`) of world ``points`` (m) by Blender's camera projection of
    ``blend``'s scene camera; ``points`` None: the lamp."""
    proc = h.run_bpy_code(_PROJECT_CODE, blend, resolution[0], resolution[1],
                          json.dumps([list(map(float, p)) for p in points] if points else []))
    line = next(l for l in proc.stdout.splitlines() if l.startswith("PROJECTED "))
    return [tuple(xy) for xy in json.loads(line[len("PROJECTED "):])]


def lamp_image_centre_from_blend(blend, resolution=RESOLUTION):
    """(x, y) pixels (as :func:`lamp_image_centre`) of the lamp's image by Blender's camera projection."""
    return project_from_blend(blend, None, resolution)[0]


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
nt = scene.world.node_tree
vs = nt.nodes[reference.VOLUME_NODE_NAME]
out = vs.outputs["Volume"].links[0].to_node
if albedo < 1.0:
    ab = nt.nodes.new("ShaderNodeVolumeAbsorption")
    ab.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)       # absorbs density x (1 - Color)
    ab.inputs["Density"].default_value = beta * (1.0 - albedo)
    add = nt.nodes.new("ShaderNodeAddShader")
    nt.links.remove(vs.outputs["Volume"].links[0])
    nt.links.new(vs.outputs["Volume"], add.inputs[0])
    nt.links.new(ab.outputs["Volume"], add.inputs[1])
    nt.links.new(add.outputs["Shader"], out.inputs["Volume"])
c = scene.cycles
c.volume_bounces = n
c.max_bounces = n                  # max_bounces caps volume bounces too
c.diffuse_bounces = c.glossy_bounces = c.transmission_bounces = 0
c.seed = a["seed"]
c.use_animated_seed = False
assert abs(scene.camera.data.clip_start - 0.001) < 1e-9
if a.get("border"):                # (x0, x1, y0, y1) fractions, y from the bottom: render that crop only
    r = scene.render
    r.use_border = r.use_crop_to_border = True
    r.border_min_x, r.border_max_x, r.border_min_y, r.border_max_y = a["border"]
t0 = time.perf_counter()
measure.render_to_file(scene, a["out"])
print("RENDER_SECONDS %.2f" % (time.perf_counter() - t0))
'''


def reference_name(distance, density, anisotropy, albedo, volume_bounces, samples, seeds,
                   power=LAMP_POWER_W, lamp_radius=0.0, resolution=RESOLUTION):
    """File name of a cached reference, every parameter in it."""
    w, hh = resolution
    return (f"dense_d{float(distance):g}_beta{float(density):g}_g{float(anisotropy):g}_a{float(albedo):g}"
            f"_vb{int(volume_bounces)}_P{float(power):g}_r{float(lamp_radius):g}_{w}x{hh}"
            f"_{int(samples)}spp_x{int(seeds)}.exr")


def render_reference_seed(blend, out, density, anisotropy, albedo, volume_bounces, samples, seed,
                          resolution=RESOLUTION, log=None, border=None):
    """One Cycles render of the reference (see the module doc) with ``seed``; returns (path, seconds).
    ``border``: (x0, x1, y0, y1), fractions of the frame (y from the bottom), to render that crop only."""
    args = dict(blend=str(blend), out=str(out), density=float(density), anisotropy=float(anisotropy),
                albedo=float(albedo), volume_bounces=int(volume_bounces), samples=int(samples), seed=int(seed),
                resolution=list(resolution), border=list(border) if border else None)
    proc = h.run(["-c", _REFERENCE_CODE, json.dumps(args)], timeout=7200)
    if log is not None:
        log.append(proc.stdout + "\n" + proc.stderr)
    return pathlib.Path(out), h.render_seconds(proc)


seed_path = h.seed_path   # (re-exported: the other scene modules and the tests name it here)


def render_ms_reference(distance, density, anisotropy, albedo, volume_bounces=64, samples=1024, seeds=2,
                        power=LAMP_POWER_W, lamp_radius=0.0, resolution=RESOLUTION, regen=False,
                        directory=None, keep_seeds=True, times=None):
    """Path of the cached Cycles reference of the lamp in fog, rendering it if missing (or if ``regen``).

    ``distance`` m camera-lamp, ``density`` extinction 1/m, ``anisotropy`` Henyey-Greenstein g, ``albedo``
    single-scattering albedo, ``volume_bounces`` N (0: single scattering; N > 0: multiple scattering with
    max_bounces = N), ``samples`` spp per render, ``seeds`` renders (seeds 0 .. seeds-1) averaged, ``power`` W,
    ``lamp_radius`` m.  Cached as ``directory`` (default tests/references) / :func:`reference_name`; with
    ``keep_seeds`` each seed's render stays beside it (:func:`seed_path`; noise estimates) and is reused, unless
    ``regen``, by a reference of the same settings and more seeds.  ``times``: a list to which each new render's
    seconds are appended.
    """
    directory = pathlib.Path(directory) if directory else h.REFERENCES
    path = directory / reference_name(distance, density, anisotropy, albedo, volume_bounces, samples, seeds,
                                      power, lamp_radius, resolution)
    if path.is_file() and not regen:
        return path
    blend = blend_path(distance, power, lamp_radius)

    def render_seed(seed, out):
        return render_reference_seed(blend, out, density, anisotropy, albedo, volume_bounces, samples, seed,
                                     resolution)[1]

    return h.mean_of_seeds(path, render_seed, seeds, regen, times, keep_seeds)


# The lamp at optical distances T 1.5, 4.5 and 8 (tests/test_multiple_render.py, tools/prediction_chart.py): the
# cases' settings, and the seeds of their 64-bounce references (2 048 spp each)
GLOW_CASES = {1.5: dict(distance=15.0, density=0.1, anisotropy=0.85, albedo=0.9),
              4.5: dict(distance=15.0, density=0.3, anisotropy=0.85, albedo=0.9),
              8.0: dict(distance=20.0, density=0.4, anisotropy=0.85, albedo=0.9)}
GLOW_SEEDS = {1.5: 2, 4.5: 4, 8.0: 4}


def render_ours(distance, density, anisotropy, albedo, out, power=LAMP_POWER_W, lamp_radius=0.0,
                resolution=RESOLUTION, method="compositor", multiple_scattering="off", extra=(), log=None,
                blend=None):
    """Render the scene (``blend``, default :func:`blend_path`) with the analytic fog (``python -m fog_addon
    render``, Cycles, pixel centres) at the reference's settings; returns the path of ``out`` (.exr).
    ``multiple_scattering``: "off" (single scattering), "on" (the Dense Fog model) or None (the file's)."""
    blend = blend or blend_path(distance, power, lamp_radius)
    args = ["--anisotropy", repr(float(anisotropy)), "--color", ",".join([repr(float(albedo))] * 3)]
    return h.render_test("dense", density, out, engine="cycles", method=method, resolution=resolution,
                         blend=blend, extra=tuple(args) + tuple(extra), log=log,
                         multiple_scattering=multiple_scattering)


# -- the annulus profile (numpy) ------------------------------------------------------------------------------

def luminance(image):
    """Rec. 709 luminance of an (H, W, >=3) image (a 2-D array is taken as luminance already)."""
    a = np.asarray(image, dtype=np.float64)
    if a.ndim == 2:
        return a
    return a[..., 0] * REC709[0] + a[..., 1] * REC709[1] + a[..., 2] * REC709[2]


def pixel_radii(shape, centre_xy):
    """Distance (px) of every pixel centre (x + 0.5, y + 0.5; y from the top row) from ``centre_xy``."""
    hh, w = shape[:2]
    y, x = np.mgrid[0:hh, 0:w]
    return np.hypot(x + 0.5 - float(centre_xy[0]), y + 0.5 - float(centre_xy[1]))


def ring_means(image, centre_xy, edges_px=RING_EDGES_PX, firefly=FIREFLY_FACTOR, return_counts=False, mask=None):
    """Mean luminance over each annulus edges_px[i] <= r < edges_px[i+1] (r from ``centre_xy`` to pixel
    centres, see :func:`pixel_radii`), leaving out the pixels brighter than ``firefly`` x the annulus' median
    (``firefly`` None: keep every pixel).  Returns an array of len(edges_px) - 1 (NaN for an empty annulus);
    with ``return_counts`` also (pixels kept, pixels left out) per annulus.  ``mask``: only the pixels where it
    is true count (the firefly rule applied among them)."""
    lum = luminance(image)
    r = pixel_radii(lum.shape, centre_xy)
    inside = np.ones(lum.shape, bool) if mask is None else np.asarray(mask, bool)
    means, kept, dropped = [], [], []
    for lo, hi in zip(edges_px[:-1], edges_px[1:]):
        v = lum[(r >= lo) & (r < hi) & inside]
        if v.size == 0:
            means.append(np.nan), kept.append(0), dropped.append(0)
            continue
        keep = v <= firefly * np.median(v) if firefly is not None else np.ones(v.shape, bool)
        means.append(float(v[keep].mean()) if keep.any() else np.nan)
        kept.append(int(keep.sum()))
        dropped.append(int((~keep).sum()))
    means = np.array(means)
    return (means, np.array(kept), np.array(dropped)) if return_counts else means


def ring_labels(edges_px=RING_EDGES_PX):
    """'1.5-3.5', ... for each annulus."""
    return [f"{lo:g}-{hi:g}" for lo, hi in zip(edges_px[:-1], edges_px[1:])]


def main(argv=None):
    p = argparse.ArgumentParser(description="build the lamp-in-dense-fog scene's .blend")
    p.add_argument("out")
    p.add_argument("--distance", type=float, default=15.0, help="camera-lamp distance (m)")
    p.add_argument("--power", type=float, default=LAMP_POWER_W, help="lamp power (W)")
    p.add_argument("--lamp-radius", type=float, default=0.0, help="lamp radius (m)")
    p.add_argument("--resolution", default=f"{RESOLUTION[0]}x{RESOLUTION[1]}")
    a = p.parse_args(argv)
    import bpy
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    res = tuple(int(v) for v in a.resolution.lower().split("x"))
    build(scene, a.distance, a.power, a.lamp_radius, res)
    h.save_blend(a.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
