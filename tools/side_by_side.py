"""README pictures: each demo scene without fog, with the analytic fog, and with
Cycles' path-traced World volume, side by side.

    .venv/bin/python tools/side_by_side.py [--resolution 480x270] [--quick]
                                           [--scenes street_lamps spheres] [--keep DIR]

For each demo scene (demo_scenes/<scene>.py, at its DEFAULT_DENSITY) the tool
builds the .blend and renders three EXRs, one Blender process each, one after
the other:

1. **no fog** -- the .blend rendered as it is (Cycles) by a small bpy script
   using fog_addon.measure.  ``render --density 0`` is *not* fog-free: the
   analytic model sees the World background through infinitely deep fog, so
   even at density 0 the background turns black while surfaces are unchanged;
2. **analytic fog** -- ``python -m fog_addon render --engine cycles --method nodes``
   at --samples (16);
3. **path-traced reference** -- ``python -m fog_addon reference`` at the same
   density and --reference-samples (1024), with cast shadows and
   interreflection left on (a picture, not a test).

All three use pixel-centre sampling with the denoiser off, because the
``reference`` command always sets that (fog_addon.reference); panels 1 and 2
get ``--pixel-centre`` / the same measure helper so only the fog differs.
Panels 1 and 2 keep the demo's own bounce settings; the reference uses the
single-scattering integrator (one surface bounce, no volume bounces).

Tone mapping, identical for the three panels of a scene: linear RGB x one
exposure per scene, then Reinhard x / (1 + x) per channel, then the sRGB
transfer curve.  The exposure puts the 99th percentile of the reference's
luminance at 1 (Reinhard 0.5), so glow cores saturate towards white.

Times in the captions: "render" is the render call inside Blender as the
command prints it (bpy.ops.render.render, including shader compilation and
scene sync); "process" is the whole subprocess (Python + Blender start, file
load, fog set-up, write).  They are wall-clock times on a shared machine.

Outputs: docs/figures/side_by_side_<scene>.png (with --quick: 160x90, low
sample counts, written to $TMPDIR/side_by_side_quick/ unless --out-dir is
given, so a smoke run never replaces the README pictures).
"""
import argparse
import json
import ast
import pathlib
import re
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))   # a script run by path: the repository root (fog_addon, fog_scenes)

from fog_scenes import render_harness as harness  # noqa: E402  (subprocess runner, scene builder)
from fog_addon import compare, imageio  # noqa: E402  (numpy only)
from fog_addon.precompute.core import presets  # noqa: E402  (Koschmieder visibility)

SCENES = ("street_lamps", "spheres")
FIGURES = ROOT / "docs" / "figures"
FULL = {"resolution": (480, 270), "samples": 16, "reference_samples": 1024, "plain_samples": 16}
QUICK = {"resolution": (160, 90), "samples": 16, "reference_samples": 64, "plain_samples": 16}
EXPOSURE_PERCENTILE = 99.0
MIN_PANEL_PX = 400        # smaller renders are shown at an integer zoom (captions need the width)
LUMA = np.array([0.2126, 0.7152, 0.0722])   # Rec. 709 / linear sRGB luminance weights

# Renders the .blend as it is (no fog) with the measurement helpers; prints the render call's time.
PLAIN_RENDER = """
import sys, time
from fog_addon import measure
blend, out, w, h, spp = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), int(sys.argv[5])
scene = measure.open_scene(blend)
measure.set_resolution(scene, w, h)
scene.render.engine = 'CYCLES'
measure.set_samples(scene, spp)
measure.set_cycles_cpu(scene)
measure.set_pixel_centre_filter(scene)
t0 = time.perf_counter()
measure.render_to_file(scene, out)
print(f"no fog rendered in {time.perf_counter() - t0:.2f} s")
"""


def default_density(scene):
    """DEFAULT_DENSITY of demo_scenes/<scene>.py, read without importing bpy."""
    src = (ROOT / "demo_scenes" / f"{scene}.py").read_text()
    for node in ast.parse(src).body:
        if isinstance(node, ast.Assign) and any(getattr(t, "id", None) == "DEFAULT_DENSITY" for t in node.targets):
            return float(ast.literal_eval(node.value))
    raise ValueError(f"demo_scenes/{scene}.py has no DEFAULT_DENSITY")


def _timed(args, pattern, timeout):
    """Run ``PYTHON *args``; return (render-call seconds parsed with ``pattern``, process seconds, stdout)."""
    t0 = time.perf_counter()
    proc = harness.run(args, timeout=timeout)
    wall = time.perf_counter() - t0
    m = re.search(pattern, proc.stdout)
    if m is None:
        raise RuntimeError(f"no render time in the output of {args[:3]}:\n{proc.stdout[-2000:]}")
    return float(m.group(1)), wall, proc.stdout


def render_three(scene, density, workdir, resolution, samples, reference_samples, plain_samples,
                 timeout=7200, reuse_reference=False):
    """Build ``scene`` and render the three EXRs; return {panel: (path, render s, process s)}.

    ``reuse_reference``: take the path-traced EXR already in ``workdir`` and the
    times recorded beside it (``<exr>.json``) instead of rendering it again.
    """
    blend = harness.build_scene(scene, workdir / f"{scene}.blend")
    res = f"{resolution[0]}x{resolution[1]}"
    out = {k: workdir / f"{scene}_{k}.exr" for k in ("plain", "fog", "reference")}
    runs = {}

    print(f"[{scene}] no fog ({plain_samples} spp) ...", flush=True)
    r, w, _ = _timed(["-c", PLAIN_RENDER, blend, out["plain"], resolution[0], resolution[1], plain_samples],
                     r"no fog rendered in ([0-9.]+) s", timeout)
    runs["plain"] = (out["plain"], r, w)

    print(f"[{scene}] analytic fog, density {density:g} ({samples} spp) ...", flush=True)
    r, w, _ = _timed(["-m", "fog_addon", "render", blend, "--engine", "cycles", "--method", "nodes",
                      "--density", repr(density), "--samples", samples, "--resolution", res,
                      "--pixel-centre", "--out", out["fog"]],
                     r"rendered in ([0-9.]+) s", timeout)
    runs["fog"] = (out["fog"], r, w)

    times = out["reference"].with_suffix(".json")
    if reuse_reference and times.is_file():
        r, w = json.loads(times.read_text())
        print(f"[{scene}] path-traced reference reused from {out['reference']}", flush=True)
    else:
        print(f"[{scene}] path-traced reference, density {density:g} ({reference_samples} spp) ...", flush=True)
        r, w, _ = _timed(["-m", "fog_addon", "reference", blend, "--density", repr(density),
                          "--samples", reference_samples, "--resolution", res, "--out", out["reference"]],
                         r"1/m, ([0-9.]+) s\)", timeout)
        times.write_text(json.dumps([r, w]))
    runs["reference"] = (out["reference"], r, w)
    for k, (_, r, w) in runs.items():
        print(f"[{scene}] {k:9s} render {r:7.2f} s   process {w:7.2f} s")
    return runs


def luminance(rgb):
    return rgb @ LUMA


def exposure_for(reference_rgb):
    """One exposure per scene: the reference's 99th-percentile luminance maps to 1."""
    p = float(np.percentile(luminance(reference_rgb), EXPOSURE_PERCENTILE))
    return 1.0 / p if p > 0 else 1.0


def srgb_encode(x):
    x = np.clip(x, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1.0 / 2.4) - 0.055)


def tone_map(rgb, exposure):
    """Exposure, Reinhard x / (1 + x) per channel, sRGB: display values in [0, 1]."""
    x = np.maximum(np.nan_to_num(rgb, nan=0.0, posinf=1e6), 0.0) * exposure
    return srgb_encode(x / (1.0 + x))


def figure(scene, density, runs, samples, reference_samples, plain_samples, png):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    imgs = {k: imageio.read_rgb(p) for k, (p, _, _) in runs.items()}
    exposure = exposure_for(imgs["reference"])
    m = compare.metrics(imgs["fog"], imgs["reference"])
    h, w = imgs["reference"].shape[:2]
    captions = {
        "plain": f"No fog (Cycles, {plain_samples} spp)",
        "fog": f"Analytic fog (Cycles, nodes, {samples} spp)\n"
               "no fog shadows: light passes through objects in the fog",
        "reference": f"Cycles path-traced World volume ({reference_samples} spp)\n"
                     "single scattering, with fog shadows and 1 surface bounce",
    }
    # Pixel-exact layout at 100 dpi: each panel shows the render at an integer zoom
    # (1 at 480x270, 3 at the --quick 160x90), never resampled by a fraction.
    dpi, gap, top, bottom = 100, 12, 104, 8
    zoom = max(1, -(-MIN_PANEL_PX // w))
    pw, ph = w * zoom, h * zoom
    fw, fh = 3 * pw + 4 * gap, ph + top + bottom
    fig = plt.figure(figsize=(fw / dpi, fh / dpi), dpi=dpi)
    for i, key in enumerate(("plain", "fog", "reference")):
        _, r, wall = runs[key]
        ax = fig.add_axes(((gap + i * (pw + gap)) / fw, bottom / fh, pw / fw, ph / fh))
        ax.imshow(tone_map(imgs[key], exposure), interpolation="nearest")
        ax.set_xticks([])
        ax.set_yticks([])
        ax.set_title(captions[key] + f"\nrender {r:.1f} s (whole process {wall:.1f} s)", fontsize=9)
    fig.suptitle(f"{scene.replace('_', ' ')}: fog density {density:g} 1/m (visibility "
                 f"{presets.visibility_from_density(density):.0f} m), {w}x{h} px, pixel-centre sampling, "
                 f"no denoiser; one exposure ({exposure:.3g}), Reinhard, sRGB for all three panels.\n"
                 f"Analytic vs path-traced: relative RMSE {100 * m['rel_rmse']:.1f} %, "
                 f"mean ratio {m['mean_ratio']:.3f}.  "
                 "Times: wall clock on 2 CPU cores shared with other jobs (under load).",
                 fontsize=8.5, y=1 - 6 / fh, va="top")
    png.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(png)
    plt.close(fig)
    print(f"[{scene}] exposure {exposure:.4g}; analytic vs reference: rel RMSE {m['rel_rmse']:.4f}, "
          f"mean ratio {m['mean_ratio']:.4f}, p95 per-pixel {m['p95_rel']:.3f}")
    print(f"wrote {png}")
    return exposure, m


def _resolution(s):
    w, h = (int(v) for v in s.lower().split("x"))
    if w <= 0 or h <= 0:
        raise argparse.ArgumentTypeError(f"bad resolution {s!r}")
    return (w, h)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true",
                    help="smoke run: 160x90, 64-spp reference, output to $TMPDIR/side_by_side_quick/")
    ap.add_argument("--resolution", type=_resolution, metavar="WxH", help="default 480x270 (160x90 with --quick)")
    ap.add_argument("--samples", type=int, help="analytic fog samples per pixel (default 16)")
    ap.add_argument("--reference-samples", type=int, help="path-traced samples (default 1024, 64 with --quick)")
    ap.add_argument("--plain-samples", type=int, help="no-fog samples per pixel (default 16)")
    ap.add_argument("--scenes", nargs="+", choices=SCENES, default=list(SCENES))
    ap.add_argument("--out-dir", type=pathlib.Path, help="where the PNGs go (default docs/figures)")
    ap.add_argument("--keep", type=pathlib.Path, metavar="DIR", help="keep the .blend and EXR files in DIR")
    ap.add_argument("--reuse-reference", action="store_true",
                    help="with --keep: reuse the path-traced EXRs (and their recorded times) found there")
    args = ap.parse_args(argv)

    cfg = dict(QUICK if args.quick else FULL)
    for key in ("resolution", "samples", "reference_samples", "plain_samples"):
        if getattr(args, key) is not None:
            cfg[key] = getattr(args, key)
    out_dir = args.out_dir or (pathlib.Path(tempfile.gettempdir()) / "side_by_side_quick" if args.quick
                               else FIGURES)
    try:   # which code rendered the pictures (read-only git query)
        head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True,
                              text=True).stdout.strip()
        print(f"fog_addon at commit {head or '?'} (plus any uncommitted changes)")
    except OSError:
        pass
    with tempfile.TemporaryDirectory(prefix="side_by_side_") as tmp:
        workdir = args.keep or pathlib.Path(tmp)
        workdir.mkdir(parents=True, exist_ok=True)
        for scene in args.scenes:
            density = default_density(scene)
            runs = render_three(scene, density, workdir, cfg["resolution"], cfg["samples"],
                                cfg["reference_samples"], cfg["plain_samples"],
                                reuse_reference=args.reuse_reference)
            figure(scene, density, runs, cfg["samples"], cfg["reference_samples"], cfg["plain_samples"],
                   out_dir / f"side_by_side_{scene}.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
