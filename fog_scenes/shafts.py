"""Light-shaft test scenes (issue 27) and their path-traced references, with objects casting shadows.

The cases are demo scenes whose fog is cut by shadows: windows (``window_room``), columns (``colonnade``), a hood
and a hole in a wall (``hooded_lamp``), a picket fence and a thin pole (``fence``), a pergola's slats under a low
spot, a stairwell with a shaded pendant, a lantern among thin trunks, a lit bus shelter by a street lamp
(``pergola``, ``stairwell``, ``forest``, ``bus_shelter``: built after the shafts were tuned on the others), the
colonnade raked by an area light (``softbox_colonnade``: an area light's shafts), plus
the open street (``street_lamps``), where the lamp posts' shadows are all there is to model.  Each reference is Cycles'
path-traced World volume with single scattering and interreflection off, as the other references
(fog_addon/reference.py), but with every object casting shadows into the fog and onto the surfaces: that is what
the shafts must reproduce.  The lamps' own pixels and their 8 neighbours may be left out of comparisons
(:func:`lamp_mask`), as the issue allows.

Typical use in a test::

    from fog_scenes import shafts
    ref = shafts.ensure_shaft_reference("window_room", 0.1, regen=regen)
    img = h.render_test("window_room", 0.1, out, cast_shadows=True, resolution=shafts.SHAFT_RESOLUTION, samples=16)
    h.assert_close(img, ref, name="window_room", rel_rmse=0.05, mask=shafts.lamp_mask(imageio.read_rgb(ref)))

No bpy at import (every render runs in a fresh process through render_harness).
"""
import os
import pathlib

import numpy as np

from fog_scenes import render_harness as h

SHAFT_RESOLUTION = (128, 72)

# (scene, density in 1/m, Henyey-Greenstein anisotropy)
SHAFT_CASES = [
    ("window_room", 0.1, 0.0),
    ("colonnade", 0.08, 0.0),
    ("hooded_lamp", 0.08, 0.0),
    ("fence", 0.05, 0.0),
    ("pergola", 0.08, 0.0),   # (issue 46: scenes the shafts were not tuned on)
    ("stairwell", 0.1, 0.0),
    ("forest", 0.06, 0.0),
    ("bus_shelter", 0.07, 0.0),
    ("softbox_colonnade", 0.08, 0.0),   # (an area light's shafts)
]
# The open street, its posts casting shadows, stored apart from the shadowless street_lamps_0.08.exr.
OPEN_CASES = [("street_lamps", 0.08, 0.0)]

# Samples per pixel of one render, and how many renders with independent Cycles seeds (0, 1, ...) a reference
# averages.  Together they keep each reference's own noise below 0.7 % relative RMSE (SHAFT_REFERENCE_NOISE);
# averaging seeds keeps every render under about 6 minutes on 2 cores.  Where the fog is cut by shadows the noise
# falls more slowly than 1 / sqrt(N) (colonnade: 2.1 % at 256 spp, 0.89 % at 4096): a few pixels where a camera
# ray meets a thin lit sliver near a lamp, or a bounce ray from a dark wall finds a beam, carry most of it.
SHAFT_SAMPLES = {
    "window_room": 16384,
    "colonnade": 4096,
    "hooded_lamp": 16384,
    "fence": 4096,
    "street_lamps": 4096,
    "pergola": 4096,
    "stairwell": 4096,
    "forest": 4096,
    "bus_shelter": 4096,
    "softbox_colonnade": 4096,
}
SHAFT_SEEDS = {"window_room": 2, "colonnade": 4, "pergola": 2, "stairwell": 2, "forest": 2, "bus_shelter": 2,
               "softbox_colonnade": 4}

# Measured noise of ONE cached reference (all its seeds averaged), lamps' 3x3 pixels left out, as (relative RMSE,
# p95 per-pixel relative error, max per-pixel relative error).  With one seed: from a second render with seed 1
# (difference / sqrt 2).  With k seeds: the spread of the k renders about their mean, / sqrt k.  One render alone
# left 0.75 % (window room, 16384 spp) and 0.68-0.98 % (colonnade, 4096 spp).  Render times on the 2 shared
# cores (load average 4-7 from other jobs): docs/measurements/2026-11-26-shaft-scenes.md.
SHAFT_REFERENCE_NOISE = {
    ("window_room", 0.1): (0.0053, 0.039, 0.44),
    ("colonnade", 0.08): (0.0038, 0.016, 0.19),
    ("hooded_lamp", 0.08): (0.0049, 0.019, 0.17),
    ("fence", 0.05): (0.0037, 0.016, 0.42),
    ("street_lamps", 0.08): (0.0032, 0.012, 0.16),
    ("pergola", 0.08): (0.0017, 0.054, 0.71),   # (2026-11-30: 31 s and 35 s a seed)
    ("stairwell", 0.1): (0.0024, 0.018, 0.25),   # (2026-11-30: 52 s a seed)
    ("forest", 0.06): (0.0019, 0.005, 0.09),   # (37 s a seed)
    ("bus_shelter", 0.07): (0.0031, 0.013, 0.31),   # (42 s a seed)
    ("softbox_colonnade", 0.08): (0.0031, 0.014, 0.14),   # (2026-12-01: 46 s a seed)
}

SHADOWS_SUFFIX = "_shadows"


def shaft_reference_path(scene, density, anisotropy=0.0):
    """Where the reference of a case lives: the shaft scenes under render_harness's usual name, the open scenes
    (whose shadowless reference already has that name) with ``_shadows`` appended."""
    path = h.reference_path(scene, density, anisotropy)
    if scene in {c[0] for c in OPEN_CASES}:
        path = path.with_name(path.stem + SHADOWS_SUFFIX + path.suffix)
    return path


def render_reference_seed(scene, density, out, seed, samples=None, anisotropy=0.0, blend=None):
    """One reference render of a case (cast shadows on, interreflection off, SHAFT_RESOLUTION) with Cycles seed
    ``seed``: what ``render_harness.render_reference(..., cast_shadows=True)`` renders, with the seed given."""
    blend = blend or h.scene_blend(scene)
    samples = samples or SHAFT_SAMPLES.get(scene, 4096)
    w, hh = SHAFT_RESOLUTION
    args = ["-m", "fog_addon", "reference", blend, "--density", repr(float(density)), "--samples", int(samples),
            "--resolution", f"{w}x{hh}", "--out", out, "--no-interreflection", "--seed", int(seed)]
    if anisotropy:
        args += ["--anisotropy", repr(float(anisotropy))]
    h.run(args, timeout=7200)
    return pathlib.Path(out)


def seed_renders_path(scene, density, anisotropy, seed):
    """Scratch path of one seed's render of a multi-seed reference."""
    path = shaft_reference_path(scene, density, anisotropy)
    return path.with_name(f"{path.stem}.seed{seed}.tmp.exr")


_REGENERATED = set()


def ensure_shaft_reference(scene, density, regen=False, anisotropy=0.0, keep_seeds=False):
    """Path of the cached cast-shadow reference of ``scene`` at ``density``, rendering it (at SHAFT_RESOLUTION,
    SHAFT_SAMPLES per render, the mean of SHAFT_SEEDS renders) if missing, or if ``regen`` and not yet
    re-rendered in this process.  ``keep_seeds``: leave each seed's render beside it (noise measurements)."""
    samples = SHAFT_SAMPLES.get(scene, 4096)
    seeds = SHAFT_SEEDS.get(scene, 1)
    path = shaft_reference_path(scene, density, anisotropy)
    if seeds == 1 and path == h.reference_path(scene, density, anisotropy):
        return h.ensure_reference(scene, density, regen=regen, cast_shadows=True, resolution=SHAFT_RESOLUTION,
                                  samples=samples, anisotropy=anisotropy)
    if path.is_file() and not (regen and path not in _REGENERATED):
        return path
    from fog_addon import imageio   # (numpy + OpenImageIO, no bpy)
    path.parent.mkdir(parents=True, exist_ok=True)
    blend = h.scene_blend(scene)
    parts = []
    for seed in range(seeds):
        tmp = seed_renders_path(scene, density, anisotropy, seed)
        render_reference_seed(scene, density, tmp, seed, samples=samples, anisotropy=anisotropy, blend=blend)
        parts.append(imageio.read(tmp))
        if not keep_seeds:
            os.remove(tmp)
    tmp = path.with_name(path.stem + ".tmp.exr")
    imageio.write_exr(tmp, np.mean(parts, axis=0, dtype=np.float64).astype(np.float32))
    os.replace(tmp, path)
    _REGENERATED.add(path)
    return path


GRAIN_BOUND = 2.5   # ``interleave_excess``: measured 0.77-1.89 on the shaft scenes (the largest of 9 frequencies'
#                     noise: about 2 where there is none), 20-42 with the interleaved shares left unfiltered, 2.9-3.4
#                     with the surfaces' 4 x 4 shares averaged over 2 x 2 only (2026-12-01)


def interleave_excess(ours, ref, mask):
    """How strongly a regular pattern of the compositor's interleaved shares is left in ``ours`` (H, W, 3): the
    largest amplitude of the 2D Fourier transform of ours - ``ref`` (the path-traced reference, whose structure it
    takes away) at the patterns' frequencies off the axes (periods of 2 and 4 pixels in both x and y: the 2 x 2
    Bayer pattern of the ray's shares, the 4 x 4 one of the surfaces'), over the median amplitude of all its
    frequencies (the two pictures' noise and their smooth differences).  About 1 where no pattern is left; the axes'
    frequencies are left out (a column's edge puts energy along them).  ``mask``: the pixels to take (the lamps'
    left out, as 0 difference)."""
    d = np.where(mask, ours.mean(axis=-1) - ref.mean(axis=-1), 0.0).astype(float)
    h, w = (n // 4 * 4 for n in d.shape)
    amplitude = np.abs(np.fft.fft2(d[:h, :w]))
    floor = float(np.median(amplitude))
    return max(float(amplitude[fy, fx]) for fy in (h // 4, h // 2, 3 * h // 4) for fx in (w // 4, w // 2, 3 * w // 4)) \
        / max(floor, 1e-30)


def lamp_mask(ref):
    """True except on the lamps' pixels (luminance 20x the picture's median) and their 8 neighbours."""
    lum = np.asarray(ref, dtype=np.float64)[..., :3].mean(axis=-1)
    hot = lum > 20.0 * np.median(lum)
    grown = hot.copy()
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            grown |= np.roll(np.roll(hot, dy, 0), dx, 1)
    return ~grown


_LAMP_PIXELS_CODE = r'''
import sys, json, bpy
from bpy_extras.object_utils import world_to_camera_view
bpy.ops.wm.open_mainfile(filepath=sys.argv[1])
scene = bpy.context.scene
w, h = int(sys.argv[2]), int(sys.argv[3])
scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = w, h, 100
cam = scene.camera
deps = bpy.context.evaluated_depsgraph_get()
out = []
for ob in scene.objects:
    if ob.type != 'LIGHT':
        continue
    p = ob.matrix_world.translation
    v = world_to_camera_view(scene, cam, p)
    if v.z <= 0 or not (0.0 <= v.x < 1.0 and 0.0 <= v.y < 1.0):
        continue
    c = cam.matrix_world.translation
    d = p - c
    hit = scene.ray_cast(deps, c, d.normalized(), distance=d.length - 1e-4)[0]
    if not hit:
        out.append([ob.name, int((1.0 - v.y) * h), int(v.x * w)])
print("LAMP_PIXELS " + json.dumps(out))
'''


def lamp_pixels(scene, resolution=SHAFT_RESOLUTION, blend=None):
    """[(light name, row from the top, column)] of the lights the camera sees directly in demo ``scene``."""
    import json
    blend = blend or h.scene_blend(scene)
    proc = h.run_bpy_code(_LAMP_PIXELS_CODE, blend, resolution[0], resolution[1])
    line = next(l for l in proc.stdout.splitlines() if l.startswith("LAMP_PIXELS "))
    return [tuple(x) for x in json.loads(line[len("LAMP_PIXELS "):])]


def lamp_pixel_mask(scene, resolution=SHAFT_RESOLUTION, blend=None):
    """True except on the 3x3 pixels around each light the camera sees directly (by projection, so a lit floor
    patch brighter than 20x the median, which :func:`lamp_mask` leaves out, stays in)."""
    w, hh = resolution
    mask = np.ones((hh, w), dtype=bool)
    for _, r, c in lamp_pixels(scene, resolution, blend):
        mask[max(r - 1, 0):r + 2, max(c - 1, 0):c + 2] = False
    return mask


_MS_REFERENCE_CODE = r'''
import sys, bpy
sys.path.insert(0, sys.argv[1])
bpy.ops.wm.open_mainfile(filepath=sys.argv[2])
from fog_addon import reference
scene = bpy.context.scene
scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = (int(sys.argv[6]),
                                                                                            int(sys.argv[7]), 100)
reference.configure_reference(scene, float(sys.argv[4]), samples=int(sys.argv[5]), single_scattering=False)
c = scene.cycles
c.volume_bounces = int(sys.argv[8])
c.max_bounces, c.diffuse_bounces, c.glossy_bounces, c.transmission_bounces = c.volume_bounces + 1, 1, 1, 0
reference.disable_interreflection(scene)   # (objects stay visible to volume-scatter rays: in the fog's way)
reference.absorb_scattered_rays(scene)     # (black to them: no light reflected into the fog)
scene.render.image_settings.file_format, scene.render.image_settings.color_depth = "OPEN_EXR", "32"
scene.render.filepath = sys.argv[3]
bpy.ops.render.render(write_still=True)
'''


def render_ms_reference(scene, density, out, samples, volume_bounces=32, resolution=SHAFT_RESOLUTION, blend=None):
    """A cast-shadow reference of demo ``scene`` with ``volume_bounces`` volume bounces and every object in the way
    of the scattered light, black to it (the multiply scattered field of the scene, not of unbounded fog, without the
    light its surfaces would reflect into the fog; white fog, albedo 1):
    what Dense Fog's surplus near surfaces is measured against (``tests/test_dense_surplus.py``)."""
    blend = blend or h.scene_blend(scene)
    h.run_bpy_code(_MS_REFERENCE_CODE, h.ROOT, blend, out, float(density), int(samples), resolution[0], resolution[1],
                   int(volume_bounces), timeout=7200)
    return pathlib.Path(out)
