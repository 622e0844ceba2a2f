"""README picture of the fog passes: the street lamps' composite, Fog Light and Fog Transmittance.

    .venv/bin/python tools/fog_passes_figure.py [--resolution 480x270] [--samples 16]
                                                [--out docs/figures/fog_passes.png]

A Blender process builds demo_scenes/street_lamps.py, adds the fog at the scene's default density
with Cycles' denoiser left on as a new scene has it (so the fog's compositor set-up denoises only
what is not the fog) and renders a multilayer EXR; this process (without bpy: OpenImageIO crashed
reading multi-part EXRs in a process that had rendered) lays out the three panels:

1. the composite (the picture the render writes): the denoised surfaces plus the fog light as rendered;
2. Fog Light: the light the fog adds (glows, the background's airlight, fog light on the street);
3. Fog Transmittance: e^{-beta D} along each camera ray, black where the background is seen through
   infinite fog.

Panels 1 and 2 share one exposure (the 99th percentile of the composite's luminance at 1), then
Reinhard x / (1 + x) and the sRGB curve; panel 3 is linear grey.
"""
import argparse
import json
import pathlib
import subprocess
import sys
import tempfile

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def render(out, width, height, samples):
    """In a Blender process: the street lamps with fog, rendered to the multilayer EXR ``out``."""
    import time

    import bpy

    from demo_scenes import street_lamps
    from fog_addon.nodes import compositor
    from fog_addon.ops import apply

    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    street_lamps.build(scene)
    scene.render.resolution_x, scene.render.resolution_y = width, height
    scene.cycles.samples = samples
    notes = apply.apply_fog(scene, street_lamps.DEFAULT_DENSITY)
    im = scene.render.image_settings
    im.media_type = "MULTI_LAYER_IMAGE"
    im.file_format = "OPEN_EXR_MULTILAYER"
    im.color_depth = "32"
    scene.render.filepath = str(out)
    scene.render.use_file_extension = False
    t = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    print(json.dumps({"render_s": round(time.perf_counter() - t, 2), "set_up": compositor.is_set_up(scene),
                      "notes": notes, "density": street_lamps.DEFAULT_DENSITY}))


def tone(rgb, exposure):
    x = np.maximum(rgb * exposure, 0.0)
    x = x / (1.0 + x)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def compose(exr, info, out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from fog_addon import imageio

    layers = imageio.read_layers(exr)
    comp = layers["Composite.Combined"][..., :3]
    fog = layers["ViewLayer.Fog Light"][..., :3]
    trans = layers["ViewLayer.Fog Transmittance"][..., 0]
    lum = comp @ np.array([0.2126, 0.7152, 0.0722])
    exposure = 1.0 / max(float(np.percentile(lum, 99)), 1e-6)
    panels = [(tone(comp, exposure), "Combined (composite): surfaces denoised,\nthe fog's light as rendered"),
              (tone(fog, exposure), "Fog Light: airlight + fog light on surfaces"),
              (np.repeat(np.clip(trans, 0, 1)[..., None], 3, axis=-1), "Fog Transmittance: e^(-beta D)")]
    h, w = comp.shape[:2]
    fig, axes = plt.subplots(1, 3, figsize=(3 * w / 100 + 0.3, h / 100 + 0.75), dpi=100)
    for ax, (img, title) in zip(axes, panels):
        ax.imshow(np.clip(img, 0, 1), interpolation="nearest")
        ax.set_title(title, fontsize=9)
        ax.axis("off")
    fig.suptitle(f"Street lamps, beta = {info['density']} 1/m, Cycles {info['samples']} spp, the scene's denoiser on "
                 "(the fog's compositor set-up)", fontsize=9, y=0.02, va="bottom")
    fig.subplots_adjust(left=0.005, right=0.995, top=0.86, bottom=0.08, wspace=0.02)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out)
    print(f"wrote {out}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--resolution", default="480x270")
    ap.add_argument("--samples", type=int, default=16)
    ap.add_argument("--out", type=pathlib.Path, default=ROOT / "docs" / "figures" / "fog_passes.png")
    ap.add_argument("--render", type=pathlib.Path, help=argparse.SUPPRESS)   # inside the Blender process
    args = ap.parse_args(argv)
    width, height = (int(v) for v in args.resolution.lower().split("x"))
    if args.render:
        render(args.render, width, height, args.samples)
        return 0
    with tempfile.TemporaryDirectory() as tmp:
        exr = pathlib.Path(tmp) / "fog_passes.exr"
        r = subprocess.run([sys.executable, __file__, "--render", str(exr), "--resolution", args.resolution,
                            "--samples", str(args.samples)], capture_output=True, text=True, timeout=1800)
        if r.returncode != 0:
            sys.exit(f"render failed:\n{r.stderr[-3000:]}")
        info = json.loads([ln for ln in r.stdout.splitlines() if ln.startswith("{")][-1])
        if not info["set_up"]:
            sys.exit(f"the fog's compositor set-up was not made: {info['notes']}")
        info["samples"] = args.samples
        compose(exr, info, args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
