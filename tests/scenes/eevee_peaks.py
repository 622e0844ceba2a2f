"""The glow's peaks in EEVEE: the Compositor method with and without its peak factor, and the node groups
(per sample) at many samples, against the pixel means of EEVEE's film filter.

    .venv/bin/python tests/scenes/eevee_peaks.py OUT_DIR [N_LIGHTS [FILTER_SIZE [RUNS]]]

The many-lights scene (N_LIGHTS, default 4), fog only (the lights kept out of the surfaces' lighting, a
black World), EEVEE at W x H with filter size FILTER_SIZE (px, default 1.5, EEVEE's).  Around each light's
image (7 x 7 pixels that see the sky) the reference is the pixel's mean glow under EEVEE's film filter as
Blender 5.0 writes it (``film_filter_weight``: a Gaussian of sigma 0.284 x the filter's radius, cut at the
radius; the samples jittered over the whole pixel, so the weights apply to offsets spread evenly over the
plane), integrated on a 241 x 241 grid with the numpy twin of the background glow (Sun Eq. 12): independent
of the renders and of ``pixel.bake_eevee_filter``.  RUNS, comma-separated (default "compositor"):
"compositor" (16 samples), "compositor_nopeak" (the same without the factor: the glow at each pixel's
centre), "nodes:S" (the node groups, Quality Exact, S samples: EEVEE's own film over the per-sample glow,
which checks the filter's model).  Prints one line ``EEVEE_PEAKS_JSON {...}``: per render the relative
RMSE over the peak pixels, the largest relative error of a pixel's mean over its channels there, and the
mean ratio render / reference (``tests/test_compositor_peaks.py``; README, The Compositor method, In EEVEE).
"""
import json
import math
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import bpy  # noqa: E402
import numpy as np  # noqa: E402

from fog_scenes import many_lights  # noqa: E402
from fog_scenes.probe_common import light_pixel  # noqa: E402
from fog_addon import imageio, measure  # noqa: E402
from fog_addon.nodes import comp_lights  # noqa: E402
from fog_addon.ops import apply  # noqa: E402

W, H = 96, 54
SIGMA = 0.284   # EEVEE's film filter: a Gaussian of sigma SIGMA x its radius (Blender 5.0)


def render(out, n, method, samples, radius, peak=True):
    scene, _ = many_lights.build_scene(n)
    scene.render.filter_size = radius
    scene.render.engine = "BLENDER_EEVEE"
    measure.set_resolution(scene, W, H)
    measure.set_samples(scene, samples)
    scene.eevee.light_threshold = 1e-6
    found = comp_lights.pixel_filter
    if not peak:
        comp_lights.pixel_filter = lambda scene: None
    try:
        apply.apply_fog(scene, many_lights.BETA, albedo=many_lights.ALBEDO, method=method, error="exact")
    finally:
        comp_lights.pixel_filter = found
    path = out / f"{method}_{samples}_{'peak' if peak else 'nopeak'}.exr"
    im = scene.render.image_settings
    im.file_format, im.color_depth, im.color_mode = "OPEN_EXR", "32", "RGB"
    scene.render.filepath = str(path)
    bpy.ops.render.render(write_still=True)
    return scene, imageio.read_rgb(path)[::-1].astype(float)   # row 0 at the bottom, as the picture's v


def reference(scene, radius):
    """(the filtered means at the peak pixels, the mask of those pixels)."""
    through, glow = many_lights.pixel_rays(scene, W, H), many_lights.sky_glow(scene)
    steps = 241
    s = (np.arange(steps) + 0.5) / steps * 2 * radius - radius
    sx, sy = np.meshgrid(s, s)
    r2 = sx ** 2 + sy ** 2
    weights = np.where(r2 <= radius ** 2, np.exp(-0.5 * r2 / (SIGMA * radius) ** 2), 0.0)
    weights /= weights.sum()
    ref, mask = np.zeros((H, W, 3)), np.zeros((H, W), bool)
    for light in apply.fog_lights(scene)[0]:
        lx, ly, _ = light_pixel(scene, light)
        for j in range(int(ly) - 3, int(ly) + 4):
            for i in range(int(lx) - 3, int(lx) + 4):
                if not (0 <= i < W and 0 <= j < H):
                    continue
                d = through(i, j, sx, sy)
                if (d[..., 2] < 0).any():   # a ray that can meet the ground: not a sky pixel
                    continue
                ref[j, i] = (glow(d) * weights[..., None]).sum((0, 1))
                mask[j, i] = True
    return ref, mask


def main(out, n, radius, runs):
    out.mkdir(parents=True, exist_ok=True)
    result, ref, mask = {"n": n, "size": [W, H], "filter_size": radius}, None, None
    for name in runs.split(","):
        method, _, samples = name.partition(":")
        settings = {"compositor": ("compositor", 16, True), "compositor_nopeak": ("compositor", 16, False),
                    "nodes": ("nodes", int(samples or 64), True)}[method]
        scene, img = render(out, n, *settings[:2], radius, settings[2])
        if ref is None:
            ref, mask = reference(scene, radius)
            result["peak_pixels"] = int(mask.sum())
        a, b = img[mask], ref[mask]
        lum_a, lum_b = a.mean(-1), b.mean(-1)
        result[name] = {"rel_rmse": float(math.sqrt(((a - b) ** 2).sum() / (b ** 2).sum())),
                        "max_rel": float((np.abs(lum_a - lum_b) / lum_b).max()),
                        "mean_ratio": float(lum_a.sum() / lum_b.sum())}
    print("EEVEE_PEAKS_JSON", json.dumps(result))


if __name__ == "__main__":
    args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    main(pathlib.Path(args[0]), *(f(a) for f, a in zip((int, float, str),
                                                         args[1:] + ["4", "1.5", "compositor"][len(args) - 1:])))
