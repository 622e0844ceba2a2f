"""The glow's peaks: the compositor's fog light and the materials' (16 samples a pixel) against converged means.

    .venv/bin/python benchmarks/compositor_fog/peaks.py N EXACT.exr
Around each of the N lights' images (7 x 7 pixels, all seeing the sky), the pixel's mean glow under
Cycles' pixel filter (Blackman-Harris, support +-1.5 px, x and y drawn independently) is integrated on a
241 x 241 grid with the numpy twin of the background glow (Sun Eq. 12): independent of both renders.
Elsewhere the reference is the materials' Fog Light AOV (exact per sample; its 16 samples a pixel are
what the compositor's AOVs average too).  Prints one JSON line: the relative RMSE of each against that
reference, and the largest relative error in the peak windows.
"""
import json
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))   # a script run by path: the repository root (build.py is beside it)

import numpy as np  # noqa: E402

from fog_addon import imageio  # noqa: E402


def main(n, path):
    layers = imageio.read_layers(path)   # before bpy renders anything (imageio.read_layers)
    shader = layers["ViewLayer.Fog Light"][::-1, :, :3].astype(float)   # row 0 at the bottom, as Blender's
    comp = layers["Composite.Combined"][::-1, :, :3].astype(float)
    cover = layers["ViewLayer.Fog Coverage"][::-1, :, 0]
    import bpy
    import build
    from fog_scenes import many_lights
    from fog_addon import measure
    from fog_addon.ops import apply
    from fog_addon.precompute.model import pixel
    scene, _ = many_lights.build_scene(n, direct_light=True)
    measure.set_resolution(scene, build.W, build.H)
    bpy.context.view_layer.update()
    through, glow = many_lights.pixel_rays(scene, build.W, build.H), many_lights.sky_glow(scene)
    steps = 241
    s = (np.arange(steps) + 0.5) / steps * pixel.FILTER_WIDTH - pixel.FILTER_WIDTH / 2
    w = pixel.blackman_harris(s)
    weights = np.outer(w, w) / np.outer(w, w).sum()
    sx, sy = np.meshgrid(s, s)
    ref = shader.copy()
    window = np.zeros(cover.shape, bool)
    for light in apply.fog_lights(scene)[0]:
        lx, ly, _ = build.light_pixel(scene, light)
        for j in range(int(ly) - 3, int(ly) + 4):
            for i in range(int(lx) - 3, int(lx) + 4):
                if not (0 <= i < build.W and 0 <= j < build.H) or cover[j, i] > 0:
                    continue
                ref[j, i] = (glow(through(i, j, sx, sy)) * weights[..., None]).sum((0, 1))
                window[j, i] = True
    den = (ref ** 2).sum()

    def rel(img):
        return float(np.sqrt(((img - ref) ** 2).sum() / den))

    def worst(img):
        return float((np.abs(img - ref).max(-1) / ref.max(-1))[window].max())

    print(json.dumps({"n": n, "peak_pixels": int(window.sum()), "comp_rel_rmse": rel(comp),
                      "shader16_rel_rmse": rel(shader), "comp_peak_max_rel": worst(comp),
                      "shader16_peak_max_rel": worst(shader)}))


if __name__ == "__main__":
    main(int(sys.argv[-2]), sys.argv[-1])
