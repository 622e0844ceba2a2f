"""Speed versus accuracy: analytic fog against Cycles path tracing at equal error.

    .venv/bin/python benchmarks/speed_error.py [--resolution 160x90] [--quick] [--regen] [--repeats N]

For each demo scene case in ``SCENES`` (pixel-centre filter, cast shadows and
interreflection off, as tests/render_harness.py renders them):

* ground truth: the Cycles path-traced single-scattering reference
  (``python -m fog_addon reference``, seed 0) at ``gt_samples`` spp, cached as
  benchmarks/out/gt_<scene>_<beta>_<W>x<H>_<spp>spp.exr (``--regen`` re-renders);
* path tracing: the same reference set-up with seed 1 at each spp of ``ladder``;
* analytic fog: every (method, engine, spp) of ``METHODS`` through
  ``python -m fog_addon render``.  A method the add-on refuses (non-zero exit)
  is recorded as skipped.

Each (scene, method, engine) runs in ONE bpy process (a worker: this script
with ``--worker``): it runs the command line once (open the file, set up, first
"cold" render: EEVEE compiles its shaders here), then times ``repeats`` warm
calls of ``bpy.ops.render.render`` per spp (at least one; no more once a
point's renders took ``REPEAT_BUDGET_S``).  ``render_s`` is the MINIMUM of the
warm renders (the least disturbed by other processes on the machine),
``render_median_s`` their median.  Persistent Data stays off (Blender's
default), so every render re-syncs the scene and its shaders, as a still
render does (with it on, Cycles 5.0 ignored a change of samples).
``setup_s`` is from the end of loading the .blend to the start of the first
render (adding the fog, or configuring the reference, plus the shared
resolution / shadow settings); ``load_s`` is opening the .blend;
``process_s`` is the worker's wall time, Python start-up included;
``load_avg`` is the 1-minute load average when the worker ended.
Errors are fog_addon.compare metrics of each spp's image against the ground truth.

Equal-error speed-up: for each analytic point, the path-tracing render time at
the same relative RMSE, interpolated linearly in log(time)-log(error) between
ladder points (extrapolated from the nearest ladder segment outside the
ladder's range, flagged), divided by the analytic render time.
``gt_noise`` estimates the ground truth's own relative RMSE from the ladder's
highest spp s (independent seeds, error^2 = a (1/s + 1/S) for S gt spp).

Outputs: benchmarks/out/speed_error.csv, benchmarks/out/speed_error_summary.csv,
docs/figures/speed_error.png.
"""
import argparse
import csv
import json
import math
import os
import pathlib
import statistics
import sys
import tempfile
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))

import render_harness as h  # noqa: E402
from fog_addon import cli, compare  # noqa: E402  (no bpy at import)

OUT = ROOT / "benchmarks" / "out"
CSV = OUT / "speed_error.csv"
SUMMARY_CSV = OUT / "speed_error_summary.csv"
PNG = ROOT / "docs" / "figures" / "speed_error.png"

SCENES = [("street_lamps", 0.08), ("spheres", 0.15)]   # (demo scene, fog density 1/m)
PATH_TRACED = "path_traced"
# Analytic methods, one line per (method of `render --method`, engine, spp to time).
METHODS = [
    ("nodes", "cycles", (1, 4, 16)),
    ("nodes", "eevee", (1, 4)),
    ("osl", "cycles", (1, 4, 16)),
]
SETTINGS = {
    "full": dict(resolution=(160, 90), gt_samples=4096, ladder=(1, 4, 16, 64, 256, 1024), repeats=3,
                 max_spp_only=False),
    # Quick: each METHODS line only at its highest spp (every Cycles render of the fog
    # re-syncs its shaders: seconds per render even at 48x27).
    "quick": dict(resolution=(48, 27), gt_samples=512, ladder=(1, 16, 64), repeats=1, max_spp_only=True),
}
PT_SEED = 1   # the ground truth has the reference command's default seed, 0
REPEAT_BUDGET_S = 20.0
FIELDS = ["scene", "beta", "method", "engine", "spp", "render_s", "setup_s", "rel_rmse", "p95_rel",
          "mean_ratio", "render_median_s", "repeats", "first_render_s", "load_s", "process_s",
          "load_avg", "resolution", "gt_spp", "status", "note"]
SUMMARY_FIELDS = ["scene", "beta", "method", "engine", "spp", "render_s", "setup_s", "rel_rmse",
                  "pt_equal_error_s", "speedup", "extrapolated", "gt_noise"]


# ---------------------------------------------------------------- worker (inside bpy)

def worker(spec):
    """Run the CLI command ``spec["argv"]`` once, then time warm renders per spp; write JSON.

    The first render (inside the CLI) uses ``spec["samples"][0]``.  Exits with the
    CLI's code when it fails (e.g. a method that is not available).
    """
    import bpy
    from fog_addon import measure

    marks = {}
    for event in ("load_post", "render_pre", "render_post"):
        def mark(*_, event=event):
            marks.setdefault(event, time.perf_counter())   # first occurrence only
        getattr(bpy.app.handlers, event).append(bpy.app.handlers.persistent(mark))

    t0 = time.perf_counter()
    rc = cli.main(spec["argv"])
    if rc:
        sys.exit(rc)
    scene = bpy.context.scene   # after the CLI: the opened, set-up scene
    points = []
    for spp in spec["samples"]:
        measure.set_samples(scene, spp)
        times = []
        while len(times) < spec["repeats"] and (not times or sum(times) < REPEAT_BUDGET_S):
            t = time.perf_counter()
            bpy.ops.render.render(write_still=False, scene=scene.name)
            times.append(time.perf_counter() - t)
        image = os.path.join(spec["out_dir"], f"{spp}.exr")
        bpy.data.images["Render Result"].save_render(image, scene=scene)   # EXR settings from the CLI
        points.append({"spp": spp, "times": times, "image": image})
    result = {"load_s": marks["load_post"] - t0, "setup_s": marks["render_pre"] - marks["load_post"],
              "first_render_s": marks["render_post"] - marks["render_pre"], "points": points}
    pathlib.Path(spec["result"]).write_text(json.dumps(result))


# ---------------------------------------------------------------- driver

def common_flags(beta, resolution, samples, out):
    """CLI flags shared by ``render`` and ``reference`` (the test harness's measurement set-up)."""
    return ["--density", repr(float(beta)), "--resolution", f"{resolution[0]}x{resolution[1]}",
            "--samples", str(samples), "--no-cast-shadows", "--no-interreflection", "--out", str(out)]


def ground_truth(scene, beta, blend, cfg, regen):
    """Path of the cached ground-truth EXR, path-traced via the test harness if missing or ``regen``."""
    (w, hgt), spp = cfg["resolution"], cfg["gt_samples"]
    path = OUT / f"gt_{scene}_{h.density_tag(beta)}_{w}x{hgt}_{spp}spp.exr"
    if regen or not path.is_file():
        t = time.perf_counter()
        tmp = path.with_suffix(".tmp.exr")
        h.render_reference(scene, beta, tmp, samples=spp, resolution=(w, hgt), blend=blend)
        os.replace(tmp, path)
        print(f"{scene}: ground truth {spp} spp rendered in {time.perf_counter() - t:.1f} s -> {path.name}")
    return path


def measure_case(scene, beta, method, engine, samples, blend, gt, cfg, scratch):
    """Rows of one worker process: path tracing (``method == PATH_TRACED``) or an analytic method."""
    work = pathlib.Path(tempfile.mkdtemp(prefix=f"{scene}_{method}_{engine}_", dir=scratch))
    flags = common_flags(beta, cfg["resolution"], samples[0], work / "first.exr")
    if method == PATH_TRACED:
        argv = ["reference", str(blend), "--seed", str(PT_SEED)] + flags
    else:
        argv = ["render", str(blend), "--engine", engine, "--method", method, "--pixel-centre"] + flags
    spec = {"argv": argv, "samples": list(samples), "repeats": cfg["repeats"],
            "out_dir": str(work), "result": str(work / "result.json")}
    t = time.perf_counter()
    proc = h.run([__file__, "--worker", json.dumps(spec)], timeout=None, check=False)
    wall = time.perf_counter() - t
    base = {"scene": scene, "beta": beta, "method": method, "engine": engine, "process_s": wall,
            "load_avg": os.getloadavg()[0], "resolution": "{}x{}".format(*cfg["resolution"]),
            "gt_spp": cfg["gt_samples"]}
    if proc.returncode != 0:
        lines = [ln for ln in (proc.stderr.strip() or proc.stdout).splitlines() if ln.strip()]
        note = lines[-1] if lines else f"exit {proc.returncode}"
        print(f"{scene} {method}/{engine}: SKIPPED ({note}), process {wall:.1f} s")
        return [dict(base, status="skipped", note=note)]
    res = json.loads((work / "result.json").read_text())
    print(f"{scene} {method}/{engine}: process {wall:.1f} s (load {res['load_s']:.1f} s, "
          f"setup {res['setup_s']:.2f} s, first render {res['first_render_s']:.2f} s)")
    rows = []
    for p in res["points"]:
        m = compare.compare_files(p["image"], gt)
        rows.append(dict(base, spp=p["spp"], render_s=min(p["times"]),
                         render_median_s=statistics.median(p["times"]), repeats=len(p["times"]),
                         setup_s=res["setup_s"], first_render_s=res["first_render_s"],
                         load_s=res["load_s"], rel_rmse=m["rel_rmse"], p95_rel=m["p95_rel"],
                         mean_ratio=m["mean_ratio"], status="ok", note=""))
    return rows


def time_at_error(pt_rows, err):
    """(path-tracing render time at relative RMSE ``err``, extrapolated?), log-log interpolation."""
    pts = sorted((math.log(r["rel_rmse"]), math.log(r["render_s"])) for r in pt_rows)
    x, y = np.array(pts).T
    lx = math.log(err)
    if x[0] <= lx <= x[-1]:
        return math.exp(np.interp(lx, x, y)), False
    i = 0 if lx < x[0] else len(x) - 2
    slope = (y[i + 1] - y[i]) / (x[i + 1] - x[i])
    return math.exp(y[i] + slope * (lx - x[i])), True


def equal_error(rows, gt_spp):
    """Summary rows: each analytic point with the path-tracing time at equal error."""
    summary = []
    for scene, beta in SCENES:
        ok = [r for r in rows if r["scene"] == scene and r["status"] == "ok"]
        pt = [r for r in ok if r["method"] == PATH_TRACED]
        if len(pt) < 2:
            continue
        top = max(pt, key=lambda r: r["spp"])
        gt_noise = top["rel_rmse"] / math.sqrt(1.0 + gt_spp / top["spp"])
        for r in ok:
            if r["method"] == PATH_TRACED:
                continue
            t_pt, extrapolated = time_at_error(pt, r["rel_rmse"])
            summary.append({k: r[k] for k in ("scene", "beta", "method", "engine", "spp", "render_s",
                                              "setup_s", "rel_rmse")}
                           | {"pt_equal_error_s": t_pt, "speedup": t_pt / r["render_s"],
                              "extrapolated": extrapolated, "gt_noise": gt_noise})
    return summary


def write_csv(path, fields, rows):
    """Write ``rows`` (dicts) with floats to 6 significant digits."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields)
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()})


def chart(rows, summary, cfg):
    """rel RMSE (log) vs render time (log): a path-tracing line per scene, analytic markers,
    dotted lines from each analytic point to the path-tracing time at equal error, and the
    ground truth's estimated noise (errors near it are limited by the ground truth)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    markers = {(m, e): mk for (m, e, _), mk in zip(METHODS, "sD^vP*X")}
    fig, ax = plt.subplots(figsize=(9, 6))
    for i, (scene, beta) in enumerate(SCENES):
        colour = f"C{i}"
        ok = [r for r in rows if r["scene"] == scene and r["status"] == "ok"]
        pt = sorted((r for r in ok if r["method"] == PATH_TRACED), key=lambda r: r["spp"])
        ax.plot([r["render_s"] for r in pt], [r["rel_rmse"] for r in pt], "-o", color=colour, ms=4,
                label=f"{scene} \u03b2={beta:g}: path traced")
        for r in pt:
            ax.annotate(f"{r['spp']}", (r["render_s"], r["rel_rmse"]), xytext=(4, 2),
                        textcoords="offset points", fontsize=7, color=colour)
        for (method, engine), mk in markers.items():
            pts = [r for r in ok if r["method"] == method and r["engine"] == engine]
            if not pts:
                continue
            ax.plot([r["render_s"] for r in pts], [r["rel_rmse"] for r in pts], mk, color=colour,
                    mec="black", mew=0.6, ms=7, ls="none", label=f"{scene}: analytic {method}, {engine}")
            for r in pts:
                ax.annotate(f"{r['spp']}", (r["render_s"], r["rel_rmse"]), xytext=(4, -9),
                            textcoords="offset points", fontsize=7)
        for s in summary:
            if s["scene"] == scene:
                ax.plot([s["render_s"], s["pt_equal_error_s"]], [s["rel_rmse"]] * 2, ":",
                        color=colour, lw=0.8)
        noise = [s["gt_noise"] for s in summary if s["scene"] == scene]
        if noise:
            ax.axhline(noise[0], color=colour, ls="-.", lw=0.6,
                       label=f"{scene}: ground-truth noise (estimated)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("render time per frame (s): min of warm bpy.ops.render.render calls")
    ax.set_ylabel("relative RMSE vs path-traced ground truth")
    ax.set_title("Analytic fog vs Cycles path tracing at {}x{} (ground truth {} spp; labels: spp)"
                 .format(*cfg["resolution"], cfg["gt_samples"]), fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    PNG.parent.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    fig.savefig(PNG, dpi=130)
    plt.close(fig)


def print_summary(summary):
    print(f"\n{'scene':13} {'method':6} {'engine':6} {'spp':>4} {'render s':>9} {'setup s':>8} "
          f"{'rel RMSE':>9} {'PT s @ equal err':>17} {'speed-up':>9}")
    for s in summary:
        flag = " (extrapolated)" if s["extrapolated"] else ""
        print(f"{s['scene']:13} {s['method']:6} {s['engine']:6} {s['spp']:4d} {s['render_s']:9.3f} "
              f"{s['setup_s']:8.2f} {s['rel_rmse']:9.4f} {s['pt_equal_error_s']:17.2f} "
              f"{s['speedup']:9.3g}{flag}")
    for scene, noise in dict((s["scene"], s["gt_noise"]) for s in summary).items():
        print(f"{scene}: estimated ground-truth noise (rel RMSE) {noise:.4f}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--resolution", type=cli._resolution, metavar="WxH", help="default 160x90 (quick 48x27)")
    ap.add_argument("--quick", action="store_true",
                    help="tiny settings: 48x27, gt 512 spp, ladder 1,16,64, analytic at max spp, 1 repeat")
    ap.add_argument("--regen", action="store_true", help="re-render the cached ground truth")
    ap.add_argument("--repeats", type=cli._positive_int("repeats"),
                    help="warm renders per point (default 3, quick 1)")
    ap.add_argument("--worker", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.worker:
        return worker(json.loads(args.worker))
    cfg = dict(SETTINGS["quick" if args.quick else "full"])
    cfg["resolution"] = args.resolution or cfg["resolution"]
    cfg["repeats"] = args.repeats or cfg["repeats"]
    rows = []
    with tempfile.TemporaryDirectory(prefix="speed_error_") as scratch:
        for scene, beta in SCENES:
            blend = h.scene_blend(scene, scratch)
            gt = ground_truth(scene, beta, blend, cfg, args.regen)
            cases = [(PATH_TRACED, "cycles", cfg["ladder"])] + METHODS
            for method, engine, samples in cases:
                if cfg["max_spp_only"] and method != PATH_TRACED:
                    samples = samples[-1:]
                rows += measure_case(scene, beta, method, engine, samples, blend, gt, cfg, scratch)
    summary = equal_error(rows, cfg["gt_samples"])
    write_csv(CSV, FIELDS, rows)
    write_csv(SUMMARY_CSV, SUMMARY_FIELDS, summary)
    chart(rows, summary, cfg)
    print_summary(summary)
    print(f"\nwrote {CSV.relative_to(ROOT)}, {SUMMARY_CSV.relative_to(ROOT)}, {PNG.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
