"""Flicker of light shafts (issue 27, "No banding and no flicker"): 8 frames of a slow camera move through a
shadowed scene, the frame-to-frame change of each pixel with shafts on against the same move with them off.

    .venv/bin/python benchmarks/shafts_flicker.py [--resolutions 192x108,512x288,640x360] [--samples 16]
                                                  [--frames 8] [--step 0.036] [--out CSV]

The scene is demo_scenes/shaft_wall.py (a lamp behind a wall with a window, a lamp under a hood; density 0.1/m),
Cycles, Method Compositor, cast shadows on.  The camera moves ``step`` m a frame sideways (its own x axis),
keyed before the fog is added so its windows cover the move.  Each worker (this script with ``--worker``) renders
the frames with shafts on, then off, in one process.  Per pixel and pair of frames: |b - a| / max(a, b, floor),
floor 1 % of the frame's mean (dark pixels' noise is no flicker); its mean, p99 and max over the picture.  Below
144 px on the shorter side the shafts' shares are at full resolution, from 144 at half, from 288 at a quarter
(``comp_shafts.halved``), so the resolutions show each.

Outputs: benchmarks/out/shafts_flicker.csv (one row per resolution and shafts on/off); figures and their reading:
docs/measurements/2026-11-26-shafts-cost.md.  Smoke mode (``FOG_BENCH_SMOKE=1``, benchmarks/smoke.py): 16x8 px,
1 sample, 2 frames.
"""
import argparse
import json
import pathlib
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import smoke  # noqa: E402

OUT = smoke.out(ROOT / "benchmarks" / "out" / "shafts_flicker.csv")
SCENE, DENSITY = "shaft_wall", 0.1
FLOOR = 0.01   # of the frame's mean: the change of a pixel darker than this counts against this


def worker(spec):
    import bpy
    import numpy as np
    from fog_addon import imageio
    from fog_addon.ops import apply
    from fog_addon.precompute.core.spec import FogSpec
    from fog_scenes import render_harness as h

    tmp = pathlib.Path(spec["tmp"])
    blend = h.build_scene(SCENE, tmp / f"{SCENE}.blend")
    rows = []
    for shafts in (True, False):
        bpy.ops.wm.open_mainfile(filepath=str(blend))
        scene = bpy.context.scene
        scene.render.engine = "CYCLES"
        scene.cycles.device = "CPU"
        scene.cycles.samples = spec["samples"]
        scene.cycles.use_denoising = False
        scene.render.resolution_x, scene.render.resolution_y = spec["resolution"]
        scene.render.resolution_percentage = 100
        scene.render.image_settings.file_format = "OPEN_EXR"
        scene.render.image_settings.color_depth = "32"
        cam = scene.camera
        side = np.asarray(cam.matrix_world.to_3x3().col[0])
        start = np.asarray(cam.location)
        scene.frame_start, scene.frame_end = 1, spec["frames"]
        for f in range(1, spec["frames"] + 1):
            cam.location = tuple(start + side * spec["step"] * (f - 1))
            cam.keyframe_insert("location", frame=f)
        scene.frame_set(1)
        apply.apply(scene, FogSpec(density=DENSITY, method="compositor", shafts=shafts))
        frames = []
        for f in range(1, spec["frames"] + 1):
            scene.frame_set(f)
            scene.render.filepath = str(tmp / f"frame_{int(shafts)}_{f}.exr")
            bpy.ops.render.render(write_still=True)
            frames.append(imageio.read_rgb(scene.render.filepath).mean(axis=2))
        changes = []
        for a, b in zip(frames[:-1], frames[1:]):
            floor = FLOOR * 0.5 * (a.mean() + b.mean())
            changes.append(np.abs(b - a) / np.maximum(np.maximum(a, b), floor))
        c = np.stack(changes)
        rows.append({"resolution": "x".join(map(str, spec["resolution"])), "shafts": "on" if shafts else "off",
                     "frames": spec["frames"], "step_m": spec["step"], "samples": spec["samples"],
                     "mean": float(c.mean()), "p99": float(np.percentile(c, 99)), "max": float(c.max()),
                     "finite": bool(all(np.isfinite(x).all() for x in frames))})
    print("FLICKER_JSON " + json.dumps(rows), flush=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--resolutions", default=smoke.pick("192x108,512x288,640x360", "16x8"))
    ap.add_argument("--samples", type=int, default=smoke.pick(16, 1))
    ap.add_argument("--frames", type=int, default=smoke.pick(8, 2))
    ap.add_argument("--step", type=float, default=0.036, help="m the camera moves a frame")
    ap.add_argument("--out", type=pathlib.Path, default=OUT)
    ap.add_argument("--worker")
    args = ap.parse_args(argv)
    if args.worker:
        return worker(json.loads(args.worker))
    import csv
    from fog_scenes import render_harness as h
    rows = []
    for res in args.resolutions.split(","):
        spec = {"resolution": [int(v) for v in res.split("x")], "samples": args.samples, "frames": args.frames,
                "step": args.step, "tmp": tempfile.mkdtemp(prefix="shafts_flicker_")}
        proc = subprocess.run([h.PYTHON, str(pathlib.Path(__file__).resolve()), "--worker", json.dumps(spec)],
                              cwd=str(ROOT), env=h._env(), capture_output=True, text=True, timeout=3600)
        smoke.echo(proc.stdout, proc.stderr)
        lines = [ln for ln in proc.stdout.splitlines() if ln.startswith("FLICKER_JSON ")]
        if proc.returncode != 0 or not lines:
            print(proc.stdout[-3000:], proc.stderr[-3000:])
            return 1
        for row in json.loads(lines[-1].split(" ", 1)[1]):
            rows.append(row)
            print(f"{row['resolution']:>8} shafts {row['shafts']:3}: mean {row['mean']:.2%}, p99 {row['p99']:.2%}, "
                  f"max {row['max']:.2f}, finite {row['finite']}", flush=True)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    with open(args.out, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
