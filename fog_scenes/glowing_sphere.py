"""A glowing sphere seen through fog (issue 28, item 4: weather on photographs): the fog-free render with its
depth pass, and Cycles' path-traced fog of the same scene as the reference.

The scene is one emissive sphere (Emission shader, white, ``strength`` = its radiance in W/(m^2 sr)) of radius
``radius`` m at the origin and a camera ``distance`` metres away on -Y looking straight at it; no lights,
nothing else, World black.  The camera and pixel scale are those of :mod:`fog_scenes.dense` (120 x 120 px, one
pixel DEG_PER_PX = 0.1 degree at the image centre, so the sphere's image is centred on the pixel corner
(60, 60)); clip start 1 mm (Cycles starts camera rays and their fog at the near clip) and clip end 1000 m (a
clip ratio EEVEE copes with).  A sphere of uniform radiance L is a Lambertian emitter: its radiant intensity is
L pi R^2 in every direction, the intensity of a point lamp of power 4 pi^2 R^2 L (:func:`equivalent_power_w`),
so far from the sphere's image its glow scales as that of dense.py's lamp.

* :func:`render_clear` renders the scene without fog (Cycles, pixel centres, ``CLEAR_SAMPLES`` spp) with
  Blender's depth (Z) pass and writes three EXRs: the picture (R, G, B, A from Combined, plus Z), the depth
  alone (one channel: what Blender writes) and the camera distance alone (one channel, depth / cos of each
  pixel centre's angle to the view axis).  Cycles' Z pass of a perspective camera is the depth along the view
  axis, not the distance along the ray (docs/measurements/2026-11-27-glowing-sphere-references.md measures it
  against ray-sphere intersection); the background holds BACKGROUND_DEPTH = 1e10 in both files, as Blender
  writes it.
* :func:`render_fog_reference` renders the scene in Cycles' World-volume fog with
  :func:`fog_scenes.dense.render_reference_seed` (extinction ``density``, albedo as Volume Scatter + black Volume
  Absorption, Henyey-Greenstein g, ``volume_bounces`` = ``max_bounces``, pixel centres, clip start 1 mm) and
  caches the mean over seeds in tests/references, each seed's render beside it.
* Glows are compared by :func:`fog_scenes.dense.ring_means` around :func:`image_centre` (:func:`ring_means`:
  the same, optionally leaving out the pixels on the emitter's own image, :func:`emitter_mask`).

**The flat variant** (``shape="flat"``, every scene function takes the keyword; the default ``"sphere"`` is the
scene above, its file names unchanged): an emissive square (Emission shader, white, the same ``strength``, both
faces emit: ``emission_sampling`` FRONT_BACK) of side 2 x ``radius`` (0.3 m) centred where the sphere is, turned
about the vertical (Z) axis so that its normal is ``turn_deg`` (FLAT_TURN_DEG = 60) degrees from the line of
sight: its image is a rectangle 5.7 px wide and 11.5 px tall about the same centre, and most of its light goes
sideways (intensity L A |cos| about its normal: 9 W/sr along it, 4.5 W/sr towards the camera, against the
sphere's 7.07 W/sr everywhere).  Its files are named ``glowing_flat_d<m>_S<side>_L<radiance>_turn<deg>_<W>x<H>...``
(:func:`scene_tag`).  :func:`render_ours` renders either shape with the add-on's fog, :func:`compare_rings`
compares that with a reference ring by ring.

Typical use::

    from fog_scenes import glowing_sphere as gs
    clear = gs.render_clear()            # {"image": ..., "depth": ..., "distance": ...} paths
    ref = gs.render_fog_reference(0.3, 0.85, 0.9, volume_bounces=64, samples=1024, seeds=2)
    flat = gs.render_fog_reference(0.3, 0.85, 0.9, volume_bounces=64, samples=1024, seeds=2, shape="flat")
    ours = gs.render_ours(0.3, out, multiple_scattering="on", shape="flat")
    gs.compare_rings(ours, flat, 0.3, shape="flat")   # ours / path traced, ring by ring

and ``python -m fog_addon weather <clear["image"]> --depth <clear["distance"]> ...`` against ``ref``.

No bpy at import: every Blender job runs in a fresh process through ``render_harness``.  As a script
(``python -m fog_scenes.glowing_sphere OUT.blend [--shape flat]``) it builds the scene's .blend; with ``--cases``
it renders every case of REFERENCE_CASES (``--shape flat``: FLAT_REFERENCE_CASES) that is missing and prints their
ring means.
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

RESOLUTION = dense.RESOLUTION
DEG_PER_PX = dense.DEG_PER_PX
DISTANCE_M = 15.0
RADIUS_M = 0.15                # angular radius asin(0.15 / 15) = 0.573 deg = 5.73 px
RADIANCE = 100.0               # W/(m^2 sr): the Emission strength; intensity L pi R^2 = 7.07 W/sr
SEGMENTS, RINGS = 128, 64      # UV sphere; the polygon's projected area is within 0.1 % of pi R^2
CLIP_START_M = 0.001
CLIP_END_M = 1000.0
CLEAR_SAMPLES = 16             # one surface hit per pixel centre: the fog-free render is exact at any count
BACKGROUND_DEPTH = 1.0e10      # what Blender's Z pass holds where a ray hits nothing
SPHERE_NAME = "GlowingSphere"
SHAPES = ("sphere", "flat")
FLAT_NAME = "GlowingFlat"
FLAT_TURN_DEG = 60.0           # the flat emitter's normal from the line of sight (turned about the vertical axis)

# The cached references (tests/references): (density 1/m, anisotropy g, albedo, volume bounces, samples per
# render, seeds), at DISTANCE_M, RADIUS_M, RADIANCE.  Render times, noise and the ring tables:
# docs/measurements/2026-11-27-glowing-sphere-references.md.
REFERENCE_CASES = [
    (0.1, 0.85, 0.9, 64, 1024, 2),    # T = 1.5, multiple scattering
    (0.3, 0.85, 0.9, 64, 1024, 2),    # T = 4.5
    (0.1, 0.85, 0.9, 0, 4096, 2),     # T = 1.5, single scattering
]
# The flat variant's (shape="flat", FLAT_TURN_DEG, side 2 x RADIUS_M), in the order rendered:
# docs/measurements/2026-11-28-flat-emitter-references.md.
FLAT_REFERENCE_CASES = [
    (0.3, 0.85, 0.9, 64, 1024, 2),    # T = 4.5, multiple scattering
    (0.3, 0.85, 0.9, 0, 4096, 2),     # T = 4.5, single scattering
    (0.1, 0.85, 0.9, 64, 1024, 2),    # T = 1.5
    (0.1, 0.85, 0.9, 0, 4096, 2),
]


def _check_shape(shape):
    if shape not in SHAPES:
        raise ValueError(f"shape {shape!r}: one of {SHAPES}")
    return shape


def equivalent_power_w(radius=RADIUS_M, strength=RADIANCE):
    """Power (W) of the point lamp of the same radiant intensity as a sphere of uniform radiance ``strength``
    (W/(m^2 sr)) and radius ``radius`` (m): I = L pi R^2 = P / (4 pi), so P = 4 pi^2 R^2 L."""
    return 4.0 * math.pi ** 2 * float(radius) ** 2 * float(strength)


def sphere_pixel_radius(distance=DISTANCE_M, radius=RADIUS_M, deg_per_px=DEG_PER_PX):
    """Radius (px) of the sphere's image (pinhole, sphere on the view axis): its silhouette is the cone of
    half-angle asin(R / d), which meets the image plane tan(asin(R / d)) / tan(deg_per_px) pixels from the
    centre."""
    return math.tan(math.asin(float(radius) / float(distance))) / math.tan(math.radians(deg_per_px))


def image_centre(resolution=RESOLUTION):
    """(x, y) pixels of the sphere's centre's image (x from the left edge, y from the top): the image centre,
    as :func:`fog_scenes.dense.lamp_image_centre`."""
    return dense.lamp_image_centre(resolution)


def pixel_cos(resolution=RESOLUTION, deg_per_px=DEG_PER_PX):
    """(H, W) cosine of the angle between the view axis and each pixel centre's ray (pinhole, row 0 = top)."""
    w, hh = resolution
    cx, cy = image_centre(resolution)
    y, x = np.mgrid[0:hh, 0:w]
    t = math.tan(math.radians(deg_per_px))
    tan_a = t * np.hypot(x + 0.5 - cx, y + 0.5 - cy)
    return 1.0 / np.sqrt(1.0 + tan_a ** 2)


def depth_to_distance(depth, resolution=RESOLUTION, deg_per_px=DEG_PER_PX):
    """Camera distance (m) along each pixel centre's ray from Blender's Z (depth along the view axis, m):
    depth / cos(angle to the axis); the background (>= BACKGROUND_DEPTH) stays as it is."""
    z = np.asarray(depth, np.float64)
    d = z / pixel_cos(resolution, deg_per_px)
    return np.where(z >= BACKGROUND_DEPTH, z, d)


def sphere_depth_exact(distance=DISTANCE_M, radius=RADIUS_M, resolution=RESOLUTION, deg_per_px=DEG_PER_PX):
    """(distance, z) per pixel centre (H, W), m, of the ray's first hit on the ideal sphere (NaN where it misses):
    t = d cos a - sqrt(R^2 - d^2 sin^2 a), z = t cos a.  An independent check of Blender's Z pass."""
    c = pixel_cos(resolution, deg_per_px)
    s2 = 1.0 - c * c
    disc = float(radius) ** 2 - float(distance) ** 2 * s2
    t = np.where(disc >= 0.0, float(distance) * c - np.sqrt(np.maximum(disc, 0.0)), np.nan)
    return t, t * c


def flat_normal(turn_deg=FLAT_TURN_DEG):
    """World unit normal of the flat emitter's front face: -Y (towards the camera) turned ``turn_deg`` about +Z,
    (sin t, -cos t, 0).  Both faces emit."""
    t = math.radians(float(turn_deg))
    return np.array([math.sin(t), -math.cos(t), 0.0])


def flat_corners(radius=RADIUS_M, turn_deg=FLAT_TURN_DEG):
    """(4, 3) world corners (m) of the flat emitter: the square (+-radius, 0, +-radius) about the origin in the XZ
    plane, turned ``turn_deg`` about +Z (what :func:`build` makes with ``shape="flat"``)."""
    t = math.radians(float(turn_deg))
    r = float(radius)
    return np.array([[u * math.cos(t), u * math.sin(t), v] for u, v in ((-r, -r), (r, -r), (r, r), (-r, r))])


def _pixel_rays(resolution=RESOLUTION, deg_per_px=DEG_PER_PX):
    """(H, W, 3) world directions (not unit; +Y component 1) of each pixel centre's ray (camera on -Y looking along
    +Y, image x to +X, row 0 at the top, +Z up)."""
    w, hh = resolution
    cx, cy = image_centre(resolution)
    y, x = np.mgrid[0:hh, 0:w]
    t = math.tan(math.radians(deg_per_px))
    return np.stack([t * (x + 0.5 - cx), np.ones(x.shape), t * (cy - (y + 0.5))], axis=-1)


def emitter_depth_exact(distance=DISTANCE_M, radius=RADIUS_M, resolution=RESOLUTION, deg_per_px=DEG_PER_PX,
                        shape="sphere", turn_deg=FLAT_TURN_DEG):
    """(distance, z) per pixel centre (H, W), m, of the ray's first hit on the ideal emitter (NaN where it misses):
    :func:`sphere_depth_exact`, or the ray-square intersection of the flat one."""
    if _check_shape(shape) == "sphere":
        return sphere_depth_exact(distance, radius, resolution, deg_per_px)
    d = _pixel_rays(resolution, deg_per_px)
    o = np.array([0.0, -float(distance), 0.0])
    n = flat_normal(turn_deg)
    tt = math.radians(float(turn_deg))
    e_u = np.array([math.cos(tt), math.sin(tt), 0.0])          # the square's in-plane horizontal axis
    dn = d @ n
    with np.errstate(divide="ignore", invalid="ignore"):
        s = -(o @ n) / dn                                       # ray parameter (d has unit +Y: s is the depth)
    p = o + s[..., None] * d
    r = float(radius)
    hit = (s > 0.0) & (np.abs(p @ e_u) <= r) & (np.abs(p[..., 2]) <= r)
    z = np.where(hit, s, np.nan)
    return z * np.linalg.norm(d, axis=-1), z


def emitter_mask(distance=DISTANCE_M, radius=RADIUS_M, resolution=RESOLUTION, deg_per_px=DEG_PER_PX,
                 shape="sphere", turn_deg=FLAT_TURN_DEG):
    """(H, W) bool: the pixel centres on the emitter's own image (:func:`emitter_depth_exact`): 112 for the
    sphere, 72 (6 x 12) for the flat square turned 60 degrees."""
    return np.isfinite(emitter_depth_exact(distance, radius, resolution, deg_per_px, shape, turn_deg)[0])


def emitter_image_area_px(distance=DISTANCE_M, radius=RADIUS_M, resolution=RESOLUTION, deg_per_px=DEG_PER_PX,
                          shape="sphere", turn_deg=FLAT_TURN_DEG):
    """Area (px^2) of the emitter's image: pi x :func:`sphere_pixel_radius` ^ 2, or the flat square's projected
    quadrilateral (pinhole; 65.6 px^2 for the 0.3 m square at 60 degrees, against its 72 pixel centres)."""
    if _check_shape(shape) == "sphere":
        return math.pi * sphere_pixel_radius(distance, radius, deg_per_px) ** 2
    cx, cy = image_centre(resolution)
    t = math.tan(math.radians(deg_per_px))
    c = flat_corners(radius, turn_deg)
    depth = c[:, 1] + float(distance)
    x = cx + c[:, 0] / depth / t
    y = cy - c[:, 2] / depth / t
    return 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))


def ring_means(image, edges_px=dense.RING_EDGES_PX, leave_out_emitter=False, shape="sphere",
               turn_deg=FLAT_TURN_DEG, firefly=dense.FIREFLY_FACTOR, return_counts=False, mask=None):
    """:func:`fog_scenes.dense.ring_means` of ``image`` (an array or an EXR path) about :func:`image_centre`;
    ``leave_out_emitter``: without the pixels of :func:`emitter_mask` (``shape``; or of every shape named, given a
    tuple, e.g. ("sphere", "flat") to compare the two over the same pixels).  A ring wholly on the emitter is NaN
    (the flat's 1.5-3.5 ring).  ``mask``: further pixels to keep (True) or leave out."""
    from fog_addon import imageio
    img = imageio.read_rgb(image) if isinstance(image, (str, os.PathLike)) else np.asarray(image)
    keep = np.ones(img.shape[:2], bool) if mask is None else np.asarray(mask, bool).copy()
    if leave_out_emitter:
        for sh in ((shape,) if isinstance(shape, str) else tuple(shape)):
            keep &= ~emitter_mask(resolution=(img.shape[1], img.shape[0]), shape=sh, turn_deg=turn_deg)
    return dense.ring_means(img, image_centre((img.shape[1], img.shape[0])), edges_px, firefly, return_counts,
                            keep)


# -- the scene (bpy, in a Blender process) ----------------------------------------------------------------------

def build(scene, distance=DISTANCE_M, radius=RADIUS_M, strength=RADIANCE, resolution=RESOLUTION, shape="sphere",
          turn_deg=FLAT_TURN_DEG):
    """Fill ``scene``: an emissive UV sphere (Emission shader, white, ``strength`` W/(m^2 sr)) of ``radius`` m at
    the origin, the camera at (0, -distance, 0) looking along +Y at it (dense.py's lens; clip 1 mm to 1000 m),
    World black, no lights, Cycles, view transform Standard.  ``shape="flat"``: instead of the sphere, the square
    of side 2 x ``radius`` (object FLAT_NAME, both faces emitting, light sampling FRONT_BACK), upright, its normal
    turned ``turn_deg`` about +Z from -Y (:func:`flat_normal`, :func:`flat_corners`).  Needs bpy."""
    import bpy
    from demo_scenes import add_camera, add_plane, add_sphere, render_settings, set_world
    _check_shape(shape)
    render_settings(scene, resolution=resolution)
    set_world(scene, color=(0.0, 0.0, 0.0))
    mat = bpy.data.materials.new(SPHERE_NAME if shape == "sphere" else FLAT_NAME)
    if mat.node_tree is None:
        mat.use_nodes = True
    nt = mat.node_tree
    for n in list(nt.nodes):
        nt.nodes.remove(n)
    em = nt.nodes.new("ShaderNodeEmission")
    em.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    em.inputs["Strength"].default_value = float(strength)
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    nt.links.new(em.outputs["Emission"], out.inputs["Surface"])
    if shape == "sphere":
        add_sphere(scene, SPHERE_NAME, (0.0, 0.0, 0.0), float(radius), mat, segments=SEGMENTS, rings=RINGS)
    else:
        mat.cycles.emission_sampling = 'FRONT_BACK'   # both faces emit (Emission shader); sample both as lights
        r = float(radius)
        flat = add_plane(scene, FLAT_NAME, -r, r, -r, r, 0.0, mat)        # normal +Z
        flat.rotation_euler = (math.pi / 2.0, 0.0, math.radians(float(turn_deg)))   # X 90: normal -Y; then Z
    cam = add_camera(scene, (0.0, -float(distance), 0.0), (0.0, 0.0, 0.0), lens=dense.lens_mm(resolution))
    cam.data.sensor_width = dense.SENSOR_WIDTH_MM
    cam.data.clip_start = CLIP_START_M
    cam.data.clip_end = CLIP_END_M
    scene.view_settings.view_transform = 'Standard'
    return scene


def scene_tag(distance=DISTANCE_M, radius=RADIUS_M, strength=RADIANCE, resolution=RESOLUTION, shape="sphere",
              turn_deg=FLAT_TURN_DEG):
    """The scene's part of every file name: glowing_sphere_d<m>_R<m>_L<radiance>_<W>x<H>, or for the flat variant
    glowing_flat_d<m>_S<side m>_L<radiance>_turn<deg>_<W>x<H>."""
    w, hh = resolution
    if _check_shape(shape) == "flat":
        return (f"glowing_flat_d{float(distance):g}_S{2.0 * float(radius):g}_L{float(strength):g}"
                f"_turn{float(turn_deg):g}_{w}x{hh}")
    return f"glowing_sphere_d{float(distance):g}_R{float(radius):g}_L{float(strength):g}_{w}x{hh}"


def blend_path(distance=DISTANCE_M, radius=RADIUS_M, strength=RADIANCE, workdir=None, shape="sphere",
               turn_deg=FLAT_TURN_DEG):
    """Path of the scene's .blend in ``workdir`` (default: the harness's scratch folder), built if missing."""
    workdir = pathlib.Path(workdir) if workdir else pathlib.Path(h._env()["TMPDIR"]) / "fog_glowing_sphere"
    workdir.mkdir(parents=True, exist_ok=True)
    blend = workdir / f"{scene_tag(distance, radius, strength, shape=shape, turn_deg=turn_deg)}.blend"
    if not blend.is_file():
        args = ["-m", "fog_scenes.glowing_sphere", blend, "--distance", repr(float(distance)), "--radius",
                repr(float(radius)), "--strength", repr(float(strength))]
        if shape != "sphere":
            args += ["--shape", shape, "--turn", repr(float(turn_deg))]
        h.run(args)
    return blend


# -- the fog-free render with depth -----------------------------------------------------------------------------

_CLEAR_CODE = r'''
import sys, json, time
import bpy
from fog_addon import measure, reference
a = json.loads(sys.argv[1])
scene = measure.open_scene(a["blend"])
measure.set_resolution(scene, *a["resolution"])
reference.set_single_scattering_integrator(scene, a["samples"])   # pixel centres, no denoising, no clamping
assert scene.world.node_tree.nodes.get(reference.VOLUME_NODE_NAME) is None
assert abs(scene.camera.data.clip_start - 0.001) < 1e-9
for vl in scene.view_layers:
    vl.use_pass_combined = True
    vl.use_pass_z = True
im = scene.render.image_settings
im.media_type = 'MULTI_LAYER_IMAGE'
im.file_format = 'OPEN_EXR_MULTILAYER'
im.color_depth = '32'
im.exr_codec = 'ZIP'
scene.render.filepath = a["out"]
scene.render.use_file_extension = False
scene.render.film_transparent = False
t0 = time.perf_counter()
bpy.ops.render.render(write_still=True, scene=scene.name)
print("RENDER_SECONDS %.2f" % (time.perf_counter() - t0))
'''


def clear_paths(distance=DISTANCE_M, radius=RADIUS_M, strength=RADIANCE, resolution=RESOLUTION, directory=None,
                shape="sphere", turn_deg=FLAT_TURN_DEG):
    """{"image", "depth", "distance"}: where :func:`render_clear` writes by default (tests/references)."""
    directory = pathlib.Path(directory) if directory else h.REFERENCES
    stem = f"{scene_tag(distance, radius, strength, resolution, shape, turn_deg)}_clear"
    return {"image": directory / f"{stem}.exr", "depth": directory / f"{stem}_depth.exr",
            "distance": directory / f"{stem}_distance.exr"}


def _write_channels(path, arr, names):
    """A single-part float32 EXR of (H, W, C) ``arr`` with channel ``names``."""
    from fog_addon import imageio
    o = imageio.oiio()
    a = np.ascontiguousarray(arr, dtype=np.float32)
    spec = o.ImageSpec(a.shape[1], a.shape[0], a.shape[2], "float")
    spec.attribute("compression", "zip")
    spec.channelnames = tuple(names)
    imageio._write(path, spec, a)


def render_clear(out=None, distance=DISTANCE_M, radius=RADIUS_M, strength=RADIANCE, resolution=RESOLUTION,
                 samples=CLEAR_SAMPLES, regen=False, times=None, shape="sphere", turn_deg=FLAT_TURN_DEG):
    """The fog-free render and its depth, rendering them if missing (or if ``regen``); returns
    {"image", "depth", "distance"} paths.

    ``out`` (.exr; default :func:`clear_paths`' image in tests/references): R, G, B, A from Combined (linear
    radiance) and Z (Blender's depth pass, m).  Beside it, ``<out stem>_depth.exr``: Z alone, one channel, as
    Blender writes it (the depth along the view axis; BACKGROUND_DEPTH where the ray hits nothing) and
    ``<out stem>_distance.exr``: the camera distance along each pixel centre's ray, one channel
    (:func:`depth_to_distance`; the background stays BACKGROUND_DEPTH).  Cycles, pixel-centre filter,
    ``samples`` spp, no fog.  ``times``: a list to which the render's seconds are appended.  ``shape``,
    ``turn_deg``: the variant (:func:`build`).
    """
    from fog_addon import imageio
    if out is None:
        paths = clear_paths(distance, radius, strength, resolution, shape=shape, turn_deg=turn_deg)
    else:
        out = pathlib.Path(out)
        paths = {"image": out, "depth": out.with_name(f"{out.stem}_depth.exr"),
                 "distance": out.with_name(f"{out.stem}_distance.exr")}
    if all(p.is_file() for p in paths.values()) and not regen:
        return paths
    paths["image"].parent.mkdir(parents=True, exist_ok=True)
    blend = blend_path(distance, radius, strength, shape=shape, turn_deg=turn_deg)
    raw = paths["image"].with_name(paths["image"].stem + ".multilayer.tmp.exr")
    args = dict(blend=str(blend), out=str(raw), samples=int(samples), resolution=list(resolution))
    proc = h.run(["-c", _CLEAR_CODE, json.dumps(args)], timeout=3600)
    secs = h.render_seconds(proc)
    if times is not None:
        times.append(secs)
    layers = imageio.read_layers(raw)   # (this process has not rendered)
    comb = next(v for k, v in layers.items() if k.endswith("Combined"))
    z = next(v for k, v in layers.items() if k.endswith("Depth") or k.endswith(".Z"))[..., 0]
    _write_channels(paths["image"], np.dstack([comb[..., :4], z]), ("R", "G", "B", "A", "Z"))
    _write_channels(paths["depth"], z[..., None], ("Z",))
    _write_channels(paths["distance"], depth_to_distance(z, resolution)[..., None], ("Z",))
    os.remove(raw)
    return paths


# -- the fog references -----------------------------------------------------------------------------------------

def reference_name(density, anisotropy, albedo, volume_bounces, samples, seeds, distance=DISTANCE_M,
                   radius=RADIUS_M, strength=RADIANCE, resolution=RESOLUTION, shape="sphere", turn_deg=FLAT_TURN_DEG):
    """File name of a cached fog reference, every parameter in it."""
    return (f"{scene_tag(distance, radius, strength, resolution, shape, turn_deg)}"
            f"_beta{float(density):g}_g{float(anisotropy):g}"
            f"_a{float(albedo):g}_vb{int(volume_bounces)}_{int(samples)}spp_x{int(seeds)}.exr")


seed_file = h.seed_path


def render_fog_reference(density, anisotropy=0.85, albedo=0.9, volume_bounces=64, samples=1024, seeds=2,
                         distance=DISTANCE_M, radius=RADIUS_M, strength=RADIANCE, resolution=RESOLUTION,
                         regen=False, directory=None, times=None, shape="sphere", turn_deg=FLAT_TURN_DEG):
    """Path of the cached Cycles reference of the glowing sphere (``shape="flat"``: the flat variant) in fog,
    rendering it if missing (or ``regen``).

    ``density`` extinction 1/m, ``anisotropy`` Henyey-Greenstein g, ``albedo`` single-scattering albedo,
    ``volume_bounces`` N (0: single scattering; N > 0: multiple scattering, max_bounces = N), ``samples`` spp
    per render, ``seeds`` renders (seeds 0 .. seeds-1) averaged.  The medium and integrator are
    :func:`fog_scenes.dense.render_reference_seed`'s.  Cached as ``directory`` (default tests/references) /
    :func:`reference_name`; each seed's render stays beside it (:func:`seed_file`) and is reused unless
    ``regen``.  ``times``: a list to which each new render's seconds are appended.
    """
    directory = pathlib.Path(directory) if directory else h.REFERENCES
    path = directory / reference_name(density, anisotropy, albedo, volume_bounces, samples, seeds, distance,
                                      radius, strength, resolution, shape, turn_deg)
    if path.is_file() and not regen:
        return path
    blend = blend_path(distance, radius, strength, shape=shape, turn_deg=turn_deg)

    def render_seed(seed, out):
        return dense.render_reference_seed(blend, out, density, anisotropy, albedo, volume_bounces, samples, seed,
                                           resolution)[1]

    return h.mean_of_seeds(path, render_seed, seeds, regen, times)


def render_ours(density, out, multiple_scattering="off", anisotropy=0.85, albedo=0.9, engine="cycles",
                method=None, distance=DISTANCE_M, radius=RADIUS_M, strength=RADIANCE, resolution=RESOLUTION,
                extra=(), log=None, blend=None, shape="sphere", turn_deg=FLAT_TURN_DEG):
    """Render the scene (``blend``, default :func:`blend_path` of ``shape``) with the add-on's fog (``python -m
    fog_addon render``, pixel centres; as tests/test_emitter_glow.py does) at the references' settings: extinction
    ``density``, ``anisotropy`` g, colour ``albedo`` x 3, ``multiple_scattering`` "off" (single scattering), "on"
    (Dense Fog) or None (the file's).  Returns the path of ``out`` (.exr).  ``log``: a list to which the
    process's output is appended (check it with ``render_harness.log_errors``)."""
    blend = blend or blend_path(distance, radius, strength, shape=shape, turn_deg=turn_deg)
    args = ["--anisotropy", repr(float(anisotropy)), "--color", ",".join([repr(float(albedo))] * 3)]
    if multiple_scattering is not None:
        args += ["--multiple-scattering", multiple_scattering]
    return h.render_test(f"glowing_{shape}", density, out, engine=engine, method=method, resolution=resolution,
                         blend=blend, extra=tuple(args) + tuple(extra), log=log)


def area_scaled(ours, density, clear=None, shape="sphere", turn_deg=FLAT_TURN_DEG, resolution=RESOLUTION):
    """Ours (an image) with its glow scaled to the emitter's image area.  Both renders sample pixel centres, so the
    Emission pass holds (pixel centres on the emitter) / (its image's area) times the light it sends into the fog:
    the glow (ours less the fog-free render dimmed by e^(-density x each pixel's camera distance); ``clear``: a
    :func:`render_clear` dict of paths, default that of ``shape``) is scaled by :func:`emitter_image_area_px` /
    the pixel count of :func:`emitter_mask` (the sphere's test does this with a uniform 15 m)."""
    from fog_addon import imageio
    paths = clear or render_clear(resolution=resolution, shape=shape, turn_deg=turn_deg)
    clear_img = imageio.read_rgb(paths["image"])
    dist = imageio.read(paths["distance"])[..., 0]
    direct = clear_img[..., :3] * np.exp(-float(density) * np.minimum(dist, 1e6))[..., None]
    scale = emitter_image_area_px(resolution=resolution, shape=shape, turn_deg=turn_deg) / np.count_nonzero(
        emitter_mask(resolution=resolution, shape=shape, turn_deg=turn_deg))
    return direct + (np.asarray(ours)[..., :3] - direct) * scale


def compare_rings(ours, reference, density, clear=None, shape="sphere", turn_deg=FLAT_TURN_DEG,
                  area_scaled_glow=True, leave_out_emitter=False, edges_px=dense.RING_EDGES_PX, mask=None):
    """Ours / the path-traced ``reference`` ring by ring (:func:`ring_means`; images or EXR paths), ours' glow
    scaled to the emitter's area with ``area_scaled_glow`` (:func:`area_scaled`).  ``mask``: only these pixels
    (:func:`ring_means`)."""
    from fog_addon import imageio
    read = lambda a: imageio.read_rgb(a) if isinstance(a, (str, os.PathLike)) else np.asarray(a, np.float64)
    ours_img, ref_img = read(ours), read(reference)
    if area_scaled_glow:
        ours_img = area_scaled(ours_img, density, clear, shape, turn_deg, (ref_img.shape[1], ref_img.shape[0]))
    kw = dict(edges_px=edges_px, leave_out_emitter=leave_out_emitter, shape=shape, turn_deg=turn_deg, mask=mask)
    return ring_means(ours_img, **kw) / ring_means(ref_img, **kw)


def main(argv=None):
    p = argparse.ArgumentParser(description="build the glowing-sphere (or flat emitter) scene's .blend, or render "
                                "the references")
    p.add_argument("out", nargs="?", help="the .blend to write")
    p.add_argument("--distance", type=float, default=DISTANCE_M, help="camera-sphere distance (m)")
    p.add_argument("--radius", type=float, default=RADIUS_M, help="sphere radius (flat: half its side) (m)")
    p.add_argument("--strength", type=float, default=RADIANCE, help="sphere radiance (Emission strength)")
    p.add_argument("--resolution", default=f"{RESOLUTION[0]}x{RESOLUTION[1]}")
    p.add_argument("--shape", choices=SHAPES, default="sphere", help="the emitter: the sphere or the flat square")
    p.add_argument("--turn", type=float, default=FLAT_TURN_DEG,
                   help="flat: its normal's angle from the line of sight (deg, about the vertical axis)")
    p.add_argument("--cases", action="store_true", help="render the clear image and REFERENCE_CASES "
                   "(--shape flat: FLAT_REFERENCE_CASES) if missing")
    a = p.parse_args(argv)
    if a.cases:
        from fog_addon import imageio
        c = image_centre()
        sk = dict(shape=a.shape, turn_deg=a.turn)
        clear = render_clear(**sk)
        print("clear", clear["image"], np.round(dense.ring_means(imageio.read_rgb(clear["image"]), c), 5))
        for case in (REFERENCE_CASES if a.shape == "sphere" else FLAT_REFERENCE_CASES):
            times = []
            ref = render_fog_reference(*case, times=times, **sk)
            print(ref.name, times, np.round(dense.ring_means(imageio.read_rgb(ref), c), 5), flush=True)
        return 0
    if not a.out:
        p.error("give OUT.blend or --cases")
    import bpy
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    res = tuple(int(v) for v in a.resolution.lower().split("x"))
    build(scene, a.distance, a.radius, a.strength, res, shape=a.shape, turn_deg=a.turn)
    h.save_blend(a.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
