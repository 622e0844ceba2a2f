"""Area lights in fog (issue 28, item 3): an open-air scene with three area lights (square, disk, rectangle) and a
point lamp as a control, its Cycles single-scattering fog references and its fog-free render.

The scene (:func:`build`): a large grey ground (z = 0; Principled BSDF, base colour 0.5, roughness 1, Specular IOR
Level 0: Lambertian), no walls, World black, and the lights of ``LIGHTS``:

* ``AreaSquare``: a 1 m square, 500 W, 3 m high, 8 m ahead of the camera, facing straight down;
* ``AreaDisk``: a 0.5 m disk, 200 W, 2 m high, 5 m ahead and 2 m to the right, tilted 45 degrees from straight
  down towards the camera;
* ``AreaRect``: a 2 x 0.5 m rectangle (long side horizontal), 300 W, 4 m high, 12 m ahead and 2.5 m to the left,
  facing the camera (its emitting side towards -Y);
* ``Point``: a point lamp of 100 W (radius 0), 2.5 m high, 10 m ahead and 5 m to the left.

Each light's data in ``LIGHTS`` (location, XYZ Euler rotation, world normal = the light's local -Z, the side that
emits, shape, sizes, power) is what :func:`build` sets, so that the same scene can be built with the add-on's fog.
The area lights keep Blender's defaults otherwise: ``normalize`` on (the power is the light's total flux whatever
its size), ``spread`` 180 degrees, and the object's ``visible_camera`` off (a light's default; EEVEE never draws an
area light's surface anyway).  Blender 5.0's area light is then a one-sided Lambertian emitter of radiance
P / (pi A) on its front (local -Z) side: radiant intensity I(theta) = (P / pi) cos(theta) towards a direction
theta from its normal, nothing behind it; the point lamp's is P / (4 pi) (measured in
docs/measurements/2026-11-27-area-light-references.md).

The camera is 1.6 m above the ground at the origin, looking along +Y and CAMERA_PITCH_DEG down, lens LENS_MM on a
36 mm sensor (74 x 46 degrees at 160 x 90 px), clip 1 mm to 1000 m.

References (Cycles World volume, path traced; :func:`add_reference_fog`):

* fog of extinction DENSITY (1/m) and albedo ALBEDO: Volume Scatter (Color white) of density ALBEDO x DENSITY plus
  Volume Absorption (Color black) of density (1 - ALBEDO) x DENSITY; Henyey-Greenstein g;
* single scattering in ``fog_addon.reference``'s convention: ``volume_bounces`` 0 and one diffuse bounce
  (``max_bounces`` = ``diffuse_bounces`` = ``glossy_bounces`` = 1), so a camera ray that meets the ground takes
  the lights' direct light through the fog and the light the fog scatters onto it (Sun et al. 2005 Sec. 4);
* the add-on's test conventions (``--no-cast-shadows --no-interreflection``): the ground is hidden from shadow,
  diffuse, glossy and volume-scatter rays (in this open scene nothing casts a shadow and the ground cannot light
  itself, so this changes nothing but keeps the references comparable with the others);
* clip start 1 mm, pixel-centre filter, no denoising or clamping (``reference.configure_reference``);
* the mean of ``seeds`` renders with Cycles seeds 0, 1, ..., each seed's render kept beside it
  (``dense.seed_path``).

The fog-free render (:func:`render_clear`) is ``python -m fog_addon reference`` at density 0 (the same
integrator, no medium).

The camera rays that cross an area light's (invisible) surface run through the fog just in front of it, where
Cycles' light sampling without MIS (no phase-sampled ray at volume_bounces 0) is noisiest: several percent per pixel
after thousands of samples.  :func:`light_surface_mask` gives those pixels, to be left out of per-pixel
comparisons as a lamp's own pixels are; :func:`seed_noise` estimates a reference's noise from its seeds.

Typical use::

    from fog_scenes import area_lights as al
    ref = al.render_reference(0.0, samples=8192, seeds=2)     # tests/references/area_lights_...exr
    clear = al.render_clear()
    al.build_scene("/tmp/area.blend", with_fog=False)          # render it with the add-on's fog

No bpy at import: every Blender job runs in a fresh process through ``render_harness``.  As a script,
``python -m fog_scenes.area_lights OUT.blend [--fog --anisotropy G]`` builds the scene's .blend and
``python -m fog_scenes.area_lights --cases`` renders the missing cached references and prints their noise.
"""
import argparse
import json
import math
import os
import pathlib
import sys

import numpy as np

from fog_scenes import dense
from fog_scenes import render_harness as h

NAME = "area_lights"
RESOLUTION = (160, 90)         # px
LENS_MM = 24.0                 # on a 36 mm sensor: 73.7 x 45.7 degrees at 16:9
SENSOR_WIDTH_MM = 36.0
CAMERA_LOCATION = (0.0, 0.0, 1.6)   # m
CAMERA_PITCH_DEG = 3.0         # degrees below the horizon, looking along +Y
CLIP_START_M = 0.001
CLIP_END_M = 1000.0
GROUND = (-100.0, 100.0, -20.0, 200.0)   # x0, x1, y0, y1 (m) of the ground at z = 0
BASE_COLOR = 0.5
DENSITY = 0.1                  # 1/m
ALBEDO = 0.9
CLEAR_SAMPLES = 1024

# The lights: location (m), rotation (XYZ Euler, degrees), normal (world; the light's local -Z, the side that
# emits), shape, size / size_y (m; a disk's and an ellipse's are diameters), power (W).  The disk's rotation tilts
# its normal 45 degrees from straight down towards the camera: Rx(-45) then Rz(-atan(2 / 5)).
LIGHTS = [
    dict(name="AreaSquare", type="AREA", shape="SQUARE", size=1.0, size_y=1.0, energy_w=500.0,
         location=(0.0, 8.0, 3.0), rotation_euler_deg=(0.0, 0.0, 0.0), normal=(0.0, 0.0, -1.0),
         spread_deg=180.0, visible_camera=False),
    dict(name="AreaDisk", type="AREA", shape="DISK", size=0.5, size_y=0.5, energy_w=200.0,
         location=(2.0, 5.0, 2.0), rotation_euler_deg=(-45.0, 0.0, -math.degrees(math.atan2(2.0, 5.0))),
         normal=(-math.sqrt(0.5) * 2.0 / math.sqrt(29.0), -math.sqrt(0.5) * 5.0 / math.sqrt(29.0), -math.sqrt(0.5)),
         spread_deg=180.0, visible_camera=False),
    dict(name="AreaRect", type="AREA", shape="RECTANGLE", size=2.0, size_y=0.5, energy_w=300.0,
         location=(-2.5, 12.0, 4.0), rotation_euler_deg=(-90.0, 0.0, 0.0), normal=(0.0, -1.0, 0.0),
         spread_deg=180.0, visible_camera=False),
    dict(name="Point", type="POINT", radius=0.0, energy_w=100.0, location=(-5.0, 10.0, 2.5)),
]

# The cached references (tests/references): (anisotropy g, samples per render, seeds).  Render times and noise:
# docs/measurements/2026-11-27-area-light-references.md.
REFERENCE_CASES = [(0.0, 8192, 2), (0.7, 16384, 4)]


def euler_xyz_matrix(rotation_euler_deg):
    """3 x 3 rotation matrix of Blender's XYZ Euler angles (degrees): Rz @ Ry @ Rx."""
    rx, ry, rz = (math.radians(a) for a in rotation_euler_deg)
    cx, sx, cy, sy, cz, sz = math.cos(rx), math.sin(rx), math.cos(ry), math.sin(ry), math.cos(rz), math.sin(rz)
    mx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    my = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    mz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return mz @ my @ mx


def light_normal(light):
    """World unit normal (the emitting side: local -Z) of a ``LIGHTS`` entry, from its rotation."""
    return euler_xyz_matrix(light["rotation_euler_deg"]) @ np.array([0.0, 0.0, -1.0])


def area_m2(light):
    """Emitting area (m^2) of an area light of ``LIGHTS``: size x size_y, or pi/4 of it for a disk or ellipse."""
    a = float(light["size"]) * float(light["size_y"])
    return a * math.pi / 4.0 if light["shape"] in ("DISK", "ELLIPSE") else a


def radiant_intensity(light, direction):
    """Radiant intensity (W/sr) of a ``LIGHTS`` entry towards the world ``direction``: a point lamp P / (4 pi);
    an area light (normalize on, spread 180 degrees) (P / pi) max(cos theta, 0), theta from its normal."""
    d = np.asarray(direction, np.float64)
    d = d / np.linalg.norm(d)
    if light["type"] == "POINT":
        return light["energy_w"] / (4.0 * math.pi)
    return light["energy_w"] / math.pi * max(float(light_normal(light) @ d), 0.0)


# -- the scene (bpy, in a Blender process) ----------------------------------------------------------------------

def build(scene, resolution=RESOLUTION):
    """Fill ``scene`` (see the module doc) without fog; needs bpy."""
    import bpy
    from mathutils import Euler
    from demo_scenes import add_camera, add_plane, add_point_light, material, render_settings, set_world
    render_settings(scene, resolution=resolution)
    set_world(scene, color=(0.0, 0.0, 0.0))
    grey = material("Grey", (BASE_COLOR,) * 3, roughness=1.0, specular_ior_level=0.0)
    add_plane(scene, "Ground", *GROUND, 0.0, grey)
    for spec in LIGHTS:
        if spec["type"] == "POINT":
            ob = add_point_light(scene, spec["name"], spec["location"], spec["energy_w"])
            ob.data.shadow_soft_size = float(spec["radius"])
            continue
        ld = bpy.data.lights.new(spec["name"], 'AREA')
        ld.energy = spec["energy_w"]
        ld.shape = spec["shape"]
        ld.size = spec["size"]
        ld.size_y = spec["size_y"]
        ld.spread = math.radians(spec["spread_deg"])
        ld.normalize = True
        ld.use_shadow = True
        ld.color = (1.0, 1.0, 1.0)
        ob = bpy.data.objects.new(spec["name"], ld)
        ob.location = spec["location"]
        ob.rotation_euler = Euler([math.radians(a) for a in spec["rotation_euler_deg"]], 'XYZ')
        ob.visible_camera = spec["visible_camera"]
        scene.collection.objects.link(ob)
    pitch = math.radians(CAMERA_PITCH_DEG)
    x, y, z = CAMERA_LOCATION
    cam = add_camera(scene, CAMERA_LOCATION, (x, y + math.cos(pitch), z - math.sin(pitch)), lens=LENS_MM)
    cam.data.sensor_width = SENSOR_WIDTH_MM
    cam.data.clip_start = CLIP_START_M
    cam.data.clip_end = CLIP_END_M
    scene.view_settings.view_transform = 'Standard'
    bpy.context.view_layer.update()
    for spec in LIGHTS:   # the rotations give the normals LIGHTS states
        if spec["type"] == "AREA":
            n = scene.objects[spec["name"]].matrix_world.to_3x3().col[2] * -1.0
            assert max(abs(a - b) for a, b in zip(n.normalized(), spec["normal"])) < 1e-6, (spec["name"], n)
    return scene


def add_reference_fog(scene, anisotropy, density=DENSITY, albedo=ALBEDO, samples=1024, seed=0):
    """Make ``scene`` the single-scattering Cycles reference of fog ``density`` (1/m), ``albedo`` and
    Henyey-Greenstein ``anisotropy`` (see the module doc); needs bpy."""
    from fog_addon import reference
    reference.configure_reference(scene, density * albedo, anisotropy=anisotropy, samples=samples,
                                  single_scattering=True)
    reference.add_black_absorption(scene, density * (1.0 - albedo))
    reference.disable_cast_shadows(scene)
    reference.disable_interreflection(scene)
    reference.hide_from_volume_scatter(scene)
    c = scene.cycles
    c.volume_bounces = 0
    c.max_bounces = c.diffuse_bounces = c.glossy_bounces = 1
    c.transmission_bounces = 0
    c.seed = int(seed)
    c.use_animated_seed = False
    return scene


def build_scene(path, g=0.0, with_fog=True, density=DENSITY, albedo=ALBEDO):
    """Save the scene as ``path`` (.blend), with the reference fog of Henyey-Greenstein ``g`` (or none), in a
    fresh Blender process; returns the path."""
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    args = ["-m", "fog_scenes.area_lights", path]
    if with_fog:
        args += ["--fog", "--anisotropy", repr(float(g)), "--density", repr(float(density)),
                 "--albedo", repr(float(albedo))]
    h.run(args)
    return path


def _workdir():
    d = pathlib.Path(h._env()["TMPDIR"]) / "fog_area_lights"
    d.mkdir(parents=True, exist_ok=True)
    return d


def blend_path(g=None, workdir=None):
    """Path of the scene's .blend (``g`` None: without fog; else with the reference fog of that g) in
    ``workdir`` (default: the harness's scratch folder), built if missing."""
    workdir = pathlib.Path(workdir) if workdir else _workdir()
    tag = "clear" if g is None else f"beta{DENSITY:g}_g{float(g):g}_a{ALBEDO:g}"
    blend = workdir / f"{NAME}_{tag}_{RESOLUTION[0]}x{RESOLUTION[1]}.blend"
    if not blend.is_file():
        build_scene(blend, 0.0 if g is None else g, with_fog=g is not None)
    return blend


def light_pixels(blend=None):
    """{name: (x, y)} pixels (x from the left, y from the top) of each light's centre by Blender's camera
    projection (``dense.project_from_blend``)."""
    xy = dense.project_from_blend(blend or blend_path(None), [s["location"] for s in LIGHTS], RESOLUTION)
    return {s["name"]: p for s, p in zip(LIGHTS, xy)}


# -- references -----------------------------------------------------------------------------------------------

_SEED_CODE = r'''
import sys, json, time
import bpy
from fog_addon import measure
a = json.loads(sys.argv[1])
scene = measure.open_scene(a["blend"])
measure.set_resolution(scene, *a["resolution"])
c = scene.cycles
c.samples = a["samples"]
c.seed = a["seed"]
c.use_animated_seed = False
assert c.volume_bounces == 0 and c.max_bounces == 1 and not c.use_adaptive_sampling
assert abs(scene.camera.data.clip_start - 0.001) < 1e-9
t0 = time.perf_counter()
measure.render_to_file(scene, a["out"])
print("RENDER_SECONDS %.2f" % (time.perf_counter() - t0))
'''


def reference_name(g, samples, seeds, density=DENSITY, albedo=ALBEDO, resolution=RESOLUTION):
    """File name of a cached fog reference, its parameters in it."""
    w, hh = resolution
    return (f"{NAME}_beta{float(density):g}_g{float(g):g}_a{float(albedo):g}_vb0_{w}x{hh}"
            f"_{int(samples)}spp_x{int(seeds)}.exr")


def render_reference(g, samples=8192, seeds=2, regen=False, directory=None, times=None, timeout=3600):
    """Path of the cached single-scattering Cycles reference of the scene in fog of Henyey-Greenstein ``g``
    (DENSITY, ALBEDO), rendering its missing seeds (``samples`` spp each, seeds 0 .. seeds-1, kept beside it as
    ``dense.seed_path``) and their mean.  ``times``: a list to which each new render's seconds are appended."""
    directory = pathlib.Path(directory) if directory else h.REFERENCES
    path = directory / reference_name(g, samples, seeds)
    if path.is_file() and not regen:
        return path
    blend = blend_path(g)

    def render_seed(seed, out):
        args = dict(blend=str(blend), out=str(out), samples=int(samples), seed=int(seed), resolution=list(RESOLUTION))
        return h.render_seconds(h.run(["-c", _SEED_CODE, json.dumps(args)], timeout=timeout))

    return h.mean_of_seeds(path, render_seed, seeds, regen, times)


def reference_seeds(g, samples=8192, seeds=2, **kw):
    """The seeds' renders ((H, W, 3) arrays) of the cached reference (:func:`render_reference`)."""
    from fog_addon import imageio
    path = render_reference(g, samples, seeds, **kw)
    return [imageio.read_rgb(dense.seed_path(path, i)) for i in range(int(seeds))]


def clear_path(samples=CLEAR_SAMPLES, directory=None):
    """Where :func:`render_clear` caches the fog-free render."""
    w, hh = RESOLUTION
    return (pathlib.Path(directory) if directory else h.REFERENCES) / f"{NAME}_{w}x{hh}_{int(samples)}spp_clear.exr"


def render_clear(samples=CLEAR_SAMPLES, regen=False, directory=None):
    """Path of the cached fog-free render (``python -m fog_addon reference`` at density 0: the references'
    integrator and conventions, no medium), rendering it if missing or ``regen``."""
    path = clear_path(samples, directory)
    if path.is_file() and not regen:
        return path
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.stem + ".tmp.exr")
    h.render_reference(NAME, 0.0, tmp, samples=samples, resolution=RESOLUTION, blend=blend_path(None))
    os.replace(tmp, path)
    return path


# -- pixels and noise (numpy) ----------------------------------------------------------------------------------

def pixel_rays(resolution=RESOLUTION):
    """(H, W, 3) unit world directions of the camera rays through the pixel centres (row 0 = top): the camera
    looks along (0, cos p, -sin p), p = CAMERA_PITCH_DEG, its right is +X, the sensor LENS_MM / SENSOR_WIDTH_MM
    wide (horizontal fit).  Checked against Blender's projection of the lights' centres (``light_pixels``)."""
    w, hh = resolution
    p = math.radians(CAMERA_PITCH_DEG)
    fwd, right, up = np.array([0.0, math.cos(p), -math.sin(p)]), np.array([1.0, 0.0, 0.0]), \
        np.array([0.0, math.sin(p), math.cos(p)])
    t = SENSOR_WIDTH_MM / (2.0 * LENS_MM) / (w / 2.0)      # tan per pixel at the centre
    y, x = np.mgrid[0:hh, 0:w]
    d = fwd + ((x + 0.5 - w / 2.0) * t)[..., None] * right + ((hh / 2.0 - (y + 0.5)) * t)[..., None] * up
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def light_surface_mask(margin_m=0.0, names=None, resolution=RESOLUTION):
    """(H, W) bool: pixels whose centre ray crosses an area light's surface (grown by ``margin_m`` m on every side;
    ``names``: only those lights).  The lights are invisible to the camera, so these rays run through the fog
    just in front of the emitting surface, where Cycles' light sampling is noisiest: leave them out of per-pixel
    comparisons as a lamp's own pixels are."""
    rays = pixel_rays(resolution)
    cam = np.array(CAMERA_LOCATION)
    mask = np.zeros(rays.shape[:2], bool)
    for spec in LIGHTS:
        if spec["type"] != "AREA" or (names is not None and spec["name"] not in names):
            continue
        m = euler_xyz_matrix(spec["rotation_euler_deg"])
        n, c = m[:, 2], np.array(spec["location"], np.float64)
        with np.errstate(divide="ignore", invalid="ignore"):
            t = ((c - cam) @ n) / (rays @ n)
        q = cam + t[..., None] * rays - c
        u, v = q @ m[:, 0], q @ m[:, 1]
        hu, hv = 0.5 * spec["size"] + margin_m, 0.5 * spec["size_y"] + margin_m
        if spec["shape"] in ("DISK", "ELLIPSE"):
            inside = (u / hu) ** 2 + (v / hv) ** 2 <= 1.0
        else:
            inside = (np.abs(u) <= hu) & (np.abs(v) <= hv)
        mask |= np.isfinite(t) & (t > 0) & inside
    return mask


def glow_mask(pixels, radius_px=15.0, shape=(RESOLUTION[1], RESOLUTION[0])):
    """(H, W) bool: pixel centres within ``radius_px`` of any of ``pixels`` ((x, y) as :func:`light_pixels`)."""
    m = np.zeros(shape, bool)
    for xy in pixels:
        m |= dense.pixel_radii(shape, xy) < radius_px
    return m


def seed_noise(seed_images, mask=None):
    """Noise of a reference from its seeds' renders (n >= 2; RGB; over ``mask``): per pixel, the standard error of
    the seeds' mean, s = sqrt(sum_i |s_i - mean|^2 / (n (n - 1))).  Returns {"rel_rmse_mean": ||s|| / ||mean||
    (the cached mean's expected relative RMSE against the noiseless picture), "rel_rmse_seed": that x sqrt(n) (one
    seed's), "p50", "p95": percentiles of the per-pixel s / |mean|}."""
    imgs = np.stack([np.asarray(x, np.float64)[..., :3] for x in seed_images])
    n = imgs.shape[0]
    m = imgs.mean(axis=0)
    var = ((imgs - m) ** 2).sum(axis=(0, -1)) / (n * (n - 1))
    nm2 = (m ** 2).sum(axis=-1)
    if mask is not None:
        var, nm2 = var[mask], nm2[mask]
    r = float(np.sqrt(var.sum() / nm2.sum()))
    e = np.sqrt(var / np.maximum(nm2, 1e-60))
    return {"rel_rmse_mean": r, "rel_rmse_seed": r * math.sqrt(n), "p50": float(np.median(e)),
            "p95": float(np.percentile(e, 95))}


def main(argv=None):
    p = argparse.ArgumentParser(description="build the area-lights scene's .blend, or render its references")
    p.add_argument("out", nargs="?", help="the .blend to write")
    p.add_argument("--fog", action="store_true", help="add the reference fog (Cycles World volume)")
    p.add_argument("--anisotropy", type=float, default=0.0, help="Henyey-Greenstein g of the reference fog")
    p.add_argument("--density", type=float, default=DENSITY, help="extinction (1/m) of the reference fog")
    p.add_argument("--albedo", type=float, default=ALBEDO, help="single-scattering albedo of the reference fog")
    p.add_argument("--cases", action="store_true", help="render the clear image and REFERENCE_CASES if missing")
    a = p.parse_args(argv)
    if a.cases:
        from fog_addon import imageio
        print("clear", render_clear(), flush=True)
        px = light_pixels()
        print("light pixels", json.dumps({k: [round(v, 2) for v in xy] for k, xy in px.items()}), flush=True)
        surf = light_surface_mask()
        regions = {"picture": ~surf, "glow": glow_mask(px.values()) & ~surf, "surfaces": surf}
        for g, samples, seeds in REFERENCE_CASES:
            times = []
            ref = render_reference(g, samples, seeds, times=times)
            s = [imageio.read_rgb(dense.seed_path(ref, i)) for i in range(seeds)]
            print(ref.name, "new render seconds", times, flush=True)
            for k, m in regions.items():
                print("  noise", k, {a: round(b, 5) for a, b in seed_noise(s, m).items()}, flush=True)
        return 0
    if not a.out:
        p.error("give OUT.blend or --cases")
    import bpy
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    build(scene)
    if a.fog:
        add_reference_fog(scene, a.anisotropy, a.density, a.albedo)
    h.save_blend(a.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
