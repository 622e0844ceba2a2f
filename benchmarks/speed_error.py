"""Speed versus accuracy: analytic fog (per Quality) against Cycles path tracing and EEVEE's
volumetrics at equal error.

    .venv/bin/python benchmarks/speed_error.py [--resolution 160x90] [--quick] [--regen] [--repeats N]
        [--threads N] [--scenes a,b] [--ladder 1,4,...] [--qualities draft,final,exact] [--time cpu|wall]
        [--methods path_traced,compositor/cycles,...] [--update]
    .venv/bin/python benchmarks/speed_error.py --replot [--time cpu|wall]   # summary + chart from the CSV

For each demo scene case in ``SCENES`` (pixel-centre filter, cast shadows and
interreflection off, as fog_scenes/render_harness.py renders them), all at one resolution:

* ground truth: the Cycles path-traced single-scattering reference
  (``python -m fog_addon reference``, seed 0) at ``gt_samples`` spp, cached as
  benchmarks/out/gt_<scene>_<beta>_<W>x<H>_<spp>spp.exr (``--regen`` re-renders);
* path tracing (method ``path_traced``): the same reference set-up with seed 1 at
  each spp of ``ladder``;
* analytic fog: every (method, engine, spp) of ``METHODS`` at every Quality of
  ``QUALITIES`` through ``python -m fog_addon render --error draft|final|exact``:
  each point is the add-on's automatic choice of models at that Quality (method
  column ``nodes/draft`` etc., the Quality also in ``setting``; ``note`` keeps the
  CLI's ``models:`` line).  A method the add-on refuses (non-zero exit) is
  recorded as skipped;
* EEVEE's own volumetrics (method ``eevee_volumetrics``): the reference set-up
  itself (World volume: Volume Scatter, Color white, density beta; light
  shadows on, objects hidden from shadow rays) rendered with engine
  BLENDER_EEVEE at the settings of ``EEVEE_VOLUMETRICS_SETTINGS`` (``setting``
  low, default, high; ``spp`` = TAA render samples).  EEVEE 5.0 does render a
  World volume (checked at 160x90: the airlight, the lamps' glows and the fog's
  extinction appear; overall brightness 0.85-0.98 of the reference's), so no
  stand-in volume object is needed.  Common to all
  three: Custom Range on, from ``EEVEE_VOLUME_START`` to ``EEVEE_VOLUME_DEPTH``
  / beta (fog transmittance e^-7 < 1e-3 there: further fog adds < 0.1 %),
  volumetric shadows on (the fog's extinction between the light and each
  scatter point, part of single scattering), no light clamps, light threshold
  1e-4 (as the add-on's EEVEE renders).  EEVEE's froxel grid cannot resolve
  a point light's glow peak, whose few bright pixels dominate the relative
  RMSE (median per-pixel errors are a few %; see ``median_rel``).

Each (scene, method, engine[, Quality]) runs in ONE bpy process (a worker: this
script with ``--worker``): it runs the command line once (open the file, set
up, first "cold" render: EEVEE compiles its shaders here; for EEVEE's
volumetrics the CLI's first render is the Cycles reference at 1 spp and an
untimed cold EEVEE render follows), then times ``repeats`` warm calls of
``bpy.ops.render.render`` per point (at least one; no more once a point's
renders took ``REPEAT_BUDGET_S``).  ``render_s`` is the MINIMUM of the warm
renders' wall times (the least disturbed by other processes on the machine),
``render_median_s`` their median, ``render_cpu_s`` the process CPU time (all
threads) of that fastest render.  Persistent Data stays off (Blender's
default), so every render re-syncs the scene and its shaders, as a still
render does (with it on, Cycles 5.0 ignored a change of samples).
``setup_s`` is from the end of loading the .blend to the start of the first
render (adding the fog, or configuring the reference, plus the shared
resolution / shadow settings); ``load_s`` is opening the .blend;
``process_s`` is the worker's wall time, Python start-up included;
``load_avg`` is the 1-minute load average when the worker ended.
Errors are fog_addon.compare metrics of each point's image against the ground truth.

Threads (``--threads N``, default 1, recorded in the ``threads`` column): every
render, the ground truth's included, runs with ``threads_mode='FIXED'``,
``threads=N``, ``LP_NUM_THREADS=N`` (llvmpipe, EEVEE) and the worker pinned
to the N least busy CPUs (``cpus`` column), and one worker runs at a time.
The pinning is needed: in bpy 5.0.1 the cores a Cycles render used did not
reliably follow ``scene.render.threads`` when it changed within a process (a
render set to 1 thread used both cores, one set to 2 used one: CPU time vs
wall time), while under a one-CPU affinity every render used one core
(CPU time = wall time).  ``--threads 0``: Blender's automatic count, no pinning.

Equal-error speed-up: for each non-path-traced point (every Quality and every
EEVEE volumetrics setting), the path-tracing render time at the same relative
RMSE, interpolated linearly in log(time)-log(error) between ladder points
(extrapolated from the nearest ladder segment outside the ladder's range,
flagged ``extrapolated``), divided by the point's render time.  Render time
here (and on the chart) is ``render_cpu_s`` by default (``--time cpu``): with
one pinned thread it is the render's time on an idle core whatever else the
machine runs; ``speedup_wall`` is the same ratio from the wall times ``render_s``.
``gt_noise`` estimates the ground truth's own relative RMSE from the ladder's
highest spp s (independent seeds, error^2 = a (1/s + 1/S) for S gt spp).

Outputs: benchmarks/out/speed_error.csv, benchmarks/out/speed_error_summary.csv,
docs/figures/speed_error.png (one panel per scene, log time vs log error).
Smoke mode (``FOG_BENCH_SMOKE=1``, benchmarks/smoke.py): the street lamps at 8x4 px, ground truth 4 spp, path tracing
at 1 and 2 spp, EEVEE's volumetrics (low, 1 sample), the Compositor at Quality final, outputs in the smoke folder.
"""
import argparse
import csv
import json
import math
import os
import pathlib
import shutil
import statistics
import sys
import tempfile
import time

import numpy as np

import csv_rows

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))   # a script run by path: the repository root (fog_addon, fog_scenes)

import smoke  # noqa: E402
from fog_scenes import render_harness as h  # noqa: E402
from fog_addon import cli, compare  # noqa: E402  (no bpy at import)

OUT = smoke.out(ROOT / "benchmarks" / "out")
CSV = OUT / "speed_error.csv"
SUMMARY_CSV = OUT / "speed_error_summary.csv"
DATA = ROOT / "docs" / "measurements" / "data"   # the committed CSVs (benchmarks/out is not tracked)
READ_CSV = CSV if CSV.is_file() else DATA / CSV.name   # a run of one's own, else the committed rows
PNG = smoke.out(ROOT / "docs" / "figures" / "speed_error.png")

SCENES = smoke.pick([("street_lamps", 0.08), ("spheres", 0.15)], [("street_lamps", 0.08)])   # (scene, 1/m)
PATH_TRACED = "path_traced"
EEVEE_VOLUMETRICS = "eevee_volumetrics"
QUALITIES = ("draft", "final", "exact")   # `render --error`: the add-on's automatic model choice
# Analytic methods, one line per (method of `render --method`, engine, spp to time), each at every Quality.
METHODS = [
    ("nodes", "cycles", (1, 4, 16)),
    ("nodes", "eevee", (1, 4)),
    ("osl", "cycles", (1, 4, 16)),
    ("compositor", "cycles", (1, 4, 16)),
    ("compositor", "eevee", (1, 4)),
]
# EEVEE's volumetrics on the reference's World volume.  "default" is EEVEE 5.0's default volume
# settings (resolution 1:8, 64 steps, 16 shadow samples) at the add-on's 16 render samples (EEVEE's
# own default is 64 TAA samples); "high" 1:2 and 128 steps (1:1 with 256 steps took 421 s per
# render on one core at 160x90 and still had 58 % relative RMSE on the street lamps).
EEVEE_VOLUMETRICS_SETTINGS = [
    ("low", dict(volumetric_tile_size='16', volumetric_samples=32, volumetric_shadow_samples=8,
                 taa_render_samples=4)),
    ("default", dict(volumetric_tile_size='8', volumetric_samples=64, volumetric_shadow_samples=16,
                     taa_render_samples=16)),
    ("high", dict(volumetric_tile_size='2', volumetric_samples=128, volumetric_shadow_samples=32,
                  taa_render_samples=16)),
]
EEVEE_VOLUMETRICS_SETTINGS = smoke.pick(EEVEE_VOLUMETRICS_SETTINGS,
                                        [("low", dict(EEVEE_VOLUMETRICS_SETTINGS[0][1], taa_render_samples=1))])
EEVEE_VOLUME_START = 0.05   # m: the fog nearer the camera is < 0.1 % of any pixel's airlight here
EEVEE_VOLUME_DEPTH = 7.0    # optical depth of the custom range's end (transmittance e^-7)
EEVEE_VOLUMETRICS_COMMON = dict(use_volume_custom_range=True, volumetric_start=EEVEE_VOLUME_START,
                                volumetric_sample_distribution=0.8, use_volumetric_shadows=True,
                                volumetric_light_clamp=0.0, clamp_volume_direct=0.0, light_threshold=1e-4)
SETTINGS = {
    "full": dict(resolution=(160, 90), gt_samples=4096, ladder=(1, 4, 16, 64, 256, 1024, 4096), repeats=3,
                 max_spp_only=False),
    # Quick: each METHODS line only at its highest spp (every Cycles render of the fog
    # re-syncs its shaders: seconds per render even at 48x27).
    "quick": dict(resolution=(48, 27), gt_samples=512, ladder=(1, 16, 64), repeats=1, max_spp_only=True),
    # Smoke mode (``FOG_BENCH_SMOKE=1``, benchmarks/smoke.py), with Quality final and ``SMOKE_FAMILIES``.
    "smoke": dict(resolution=(8, 4), gt_samples=4, ladder=(1, 2), repeats=1, max_spp_only=True),
}
SMOKE_FAMILIES = "path_traced,eevee_volumetrics,compositor/cycles"
PT_SEED = 1   # the ground truth has the reference command's default seed, 0
REPEAT_BUDGET_S = 20.0
FIELDS = ["scene", "beta", "method", "engine", "setting", "spp", "render_s", "render_cpu_s", "setup_s",
          "rel_rmse", "median_rel", "p95_rel", "mean_ratio", "render_median_s", "repeats", "first_render_s",
          "load_s", "process_s", "load_avg", "threads", "cpus", "resolution", "gt_spp", "status", "note"]
SUMMARY_FIELDS = ["scene", "beta", "method", "engine", "setting", "spp", "render_s", "render_cpu_s", "setup_s",
                  "rel_rmse", "median_rel", "time_basis", "time_s", "pt_equal_error_s", "speedup", "speedup_wall",
                  "extrapolated", "gt_noise", "threads"]
TIME_KEYS = {"cpu": "render_cpu_s", "wall": "render_s"}


# ---------------------------------------------------------------- worker (inside bpy)

def _least_busy_cpus(n, interval=0.5):
    """The ``n`` allowed CPUs with the least busy time over ``interval`` seconds (/proc/stat)."""
    allowed = sorted(os.sched_getaffinity(0))
    if n >= len(allowed):
        return allowed

    def busy():
        out = {}
        with open("/proc/stat") as f:
            for line in f:
                name, *v = line.split()
                if name.startswith("cpu") and name != "cpu":
                    v = [int(x) for x in v]
                    out[int(name[3:])] = sum(v) - v[3] - v[4]   # minus idle and iowait
        return out
    try:
        a = busy()
        time.sleep(interval)
        b = busy()
        return sorted(sorted(allowed, key=lambda c: b.get(c, 0) - a.get(c, 0))[:n])
    except OSError:
        return allowed[:n]


def limit_threads(n):
    """One process, ``n`` CPUs: pin this process and ask llvmpipe for ``n`` threads (before bpy loads)."""
    if n <= 0:
        return sorted(os.sched_getaffinity(0))
    os.environ["LP_NUM_THREADS"] = str(n)
    cpus = _least_busy_cpus(n)
    os.sched_setaffinity(0, cpus)
    return cpus


def worker(spec):
    """Run the CLI command ``spec["argv"]`` once, then time warm renders per point; write JSON.

    A point is {"spp": N} (samples of the scene's engine) or, with ``spec["eevee"]``
    (EEVEE's volumetrics on the reference set-up), {"spp": TAA samples, "eevee": {property: value}}.
    No points: only the CLI's render (the ground truth).  Exits with the CLI's code when
    it fails (e.g. a method that is not available).
    """
    threads = spec["threads"]
    cpus = limit_threads(threads)
    import bpy
    from fog_addon import measure

    if threads > 0:   # every set_cycles_cpu of the CLI (reference and render) with a fixed count
        set_cycles_cpu = measure.set_cycles_cpu
        measure.set_cycles_cpu = lambda scene, threads=0: set_cycles_cpu(scene, threads or spec["threads"])

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
    if threads > 0:
        scene.render.threads_mode = 'FIXED'
        scene.render.threads = threads
    result = {"load_s": marks["load_post"] - t0, "setup_s": marks["render_pre"] - marks["load_post"],
              "first_render_s": marks["render_post"] - marks["render_pre"], "cpus": cpus,
              "threads": scene.render.threads if scene.render.threads_mode == 'FIXED' else 0}
    if spec.get("eevee"):
        scene.render.engine = 'BLENDER_EEVEE'
        for k, v in spec["eevee"].items():
            setattr(scene.eevee, k, v)
        for k, v in spec["points"][0]["eevee"].items():
            setattr(scene.eevee, k, v)
        scene.eevee.taa_render_samples = 1
        t = time.perf_counter()
        bpy.ops.render.render(write_still=False, scene=scene.name)   # cold: EEVEE compiles its shaders
        result["first_render_s"] = time.perf_counter() - t
    points = []
    for i, point in enumerate(spec["points"]):
        if point.get("eevee"):
            for k, v in point["eevee"].items():
                setattr(scene.eevee, k, v)
        else:
            measure.set_samples(scene, point["spp"])
        times = []
        while len(times) < spec["repeats"] and (not times or sum(w for w, _ in times) < REPEAT_BUDGET_S):
            t, c = time.perf_counter(), time.process_time()
            bpy.ops.render.render(write_still=False, scene=scene.name)
            times.append((time.perf_counter() - t, time.process_time() - c))
        image = os.path.join(spec["out_dir"], f"{i}_{point['spp']}.exr")
        bpy.data.images["Render Result"].save_render(image, scene=scene)   # EXR settings from the CLI
        points.append(dict(point, times=times, image=image))
    result["points"] = points
    pathlib.Path(spec["result"]).write_text(json.dumps(result))


# ---------------------------------------------------------------- driver

def common_flags(beta, resolution, samples, out):
    """CLI flags shared by ``render`` and ``reference`` (the test harness's measurement set-up)."""
    return ["--density", repr(float(beta)), "--resolution", f"{resolution[0]}x{resolution[1]}",
            "--samples", str(samples), "--no-cast-shadows", "--no-interreflection", "--out", str(out)]


def run_worker(spec):
    """Run one worker process (this script with ``--worker``): (CompletedProcess, wall seconds)."""
    t = time.perf_counter()
    proc = h.run([__file__, "--worker", json.dumps(spec)], timeout=None, check=False)
    return proc, time.perf_counter() - t


def ground_truth(scene, beta, blend, cfg, regen, scratch):
    """Path of the cached ground-truth EXR, path-traced in a worker (same threads) if missing or ``regen``."""
    (w, hgt), spp = cfg["resolution"], cfg["gt_samples"]
    path = OUT / f"gt_{scene}_{h.density_tag(beta)}_{w}x{hgt}_{spp}spp.exr"
    if regen or not path.is_file():
        work = pathlib.Path(tempfile.mkdtemp(prefix=f"{scene}_gt_", dir=scratch))
        argv = ["reference", str(blend), "--seed", "0"] + common_flags(beta, (w, hgt), spp, work / "gt.exr")
        spec = {"argv": argv, "points": [], "repeats": 0, "threads": cfg["threads"],
                "out_dir": str(work), "result": str(work / "result.json")}
        proc, wall = run_worker(spec)
        if proc.returncode != 0:
            raise RuntimeError(f"ground truth failed:\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}")
        res = json.loads((work / "result.json").read_text())
        path.parent.mkdir(parents=True, exist_ok=True)
        shutil.move(str(work / "gt.exr"), str(path))
        print(f"{scene}: ground truth {spp} spp rendered in {res['first_render_s']:.1f} s "
              f"(process {wall:.1f} s, threads {res['threads']}, cpus {res['cpus']}) -> {path.name}")
    return path


def measure_case(case, scene, beta, blend, gt, cfg, scratch):
    """Rows of one worker process: path tracing, EEVEE volumetrics or an analytic method at a Quality.

    ``case`` = (method, engine, setting, points) with points [{"spp": N[, "setting": s, "eevee": {...}]}].
    """
    method, engine, setting, points = case
    tag = method.replace("/", "_")
    work = pathlib.Path(tempfile.mkdtemp(prefix=f"{scene}_{tag}_{engine}_", dir=scratch))
    first = 1 if method == EEVEE_VOLUMETRICS else points[0]["spp"]
    flags = common_flags(beta, cfg["resolution"], first, work / "first.exr")
    spec = {"points": points, "repeats": cfg["repeats"], "threads": cfg["threads"],
            "out_dir": str(work), "result": str(work / "result.json")}
    if method in (PATH_TRACED, EEVEE_VOLUMETRICS):
        spec["argv"] = ["reference", str(blend), "--seed", str(PT_SEED)] + flags
        if method == EEVEE_VOLUMETRICS:
            spec["eevee"] = dict(EEVEE_VOLUMETRICS_COMMON, volumetric_end=EEVEE_VOLUME_DEPTH / beta)
    else:
        spec["argv"] = (["render", str(blend), "--engine", engine, "--method", method.split("/")[0],
                         "--error", setting, "--pixel-centre"] + flags)
    proc, wall = run_worker(spec)
    smoke.echo(proc.stdout, proc.stderr)
    smoke.check(proc.returncode == 0, f"{scene} {method}/{engine}: exit {proc.returncode}")
    base = {"scene": scene, "beta": beta, "method": method, "engine": engine, "setting": setting,
            "process_s": wall, "load_avg": os.getloadavg()[0],
            "resolution": "{}x{}".format(*cfg["resolution"]), "gt_spp": cfg["gt_samples"]}
    label = f"{scene} {method}/{engine}"
    if proc.returncode != 0:
        lines = [ln for ln in (proc.stderr.strip() or proc.stdout).splitlines() if ln.strip()]
        note = lines[-1] if lines else f"exit {proc.returncode}"
        print(f"{label}: SKIPPED ({note}), process {wall:.1f} s")
        return [dict(base, status="skipped", note=note, threads=cfg["threads"])]
    res = json.loads((work / "result.json").read_text())
    models = next((ln.strip() for ln in proc.stdout.splitlines() if ln.startswith("models:")), "")
    print(f"{label}: process {wall:.1f} s (load {res['load_s']:.1f} s, setup {res['setup_s']:.2f} s, "
          f"first render {res['first_render_s']:.2f} s, threads {res['threads']}, cpus {res['cpus']}) {models}")
    rows = []
    for p in res["points"]:
        m = compare.compare_files(p["image"], gt)
        wall_s, cpu_s = min(p["times"])
        rows.append(dict(base, setting=p.get("setting", setting), spp=p["spp"], render_s=wall_s,
                         render_cpu_s=cpu_s, render_median_s=statistics.median(w for w, _ in p["times"]),
                         repeats=len(p["times"]), setup_s=res["setup_s"], first_render_s=res["first_render_s"],
                         load_s=res["load_s"], rel_rmse=m["rel_rmse"], median_rel=m["median_rel"],
                         p95_rel=m["p95_rel"], mean_ratio=m["mean_ratio"], threads=res["threads"],
                         cpus=" ".join(str(c) for c in res["cpus"]), status="ok",
                         note=(models if method not in (PATH_TRACED, EEVEE_VOLUMETRICS) else
                               json.dumps(dict(spec.get("eevee", {}), **p.get("eevee", {})))
                               if method == EEVEE_VOLUMETRICS else "")))
    return rows


def family(method, engine):
    """The ``--methods`` name of a case: path_traced, eevee_volumetrics or <method of METHODS>/<engine>."""
    return method if method in (PATH_TRACED, EEVEE_VOLUMETRICS) else f"{method.split('/')[0]}/{engine}"


FAMILIES = [PATH_TRACED, EEVEE_VOLUMETRICS] + [f"{m}/{e}" for m, e, _ in METHODS]


def cases(cfg, beta):
    """The worker cases of one scene: path tracing, EEVEE volumetrics, every METHODS line x Quality (those of
    ``cfg["families"]``)."""
    out = [(PATH_TRACED, "cycles", "", [{"spp": s} for s in cfg["ladder"]]),
           (EEVEE_VOLUMETRICS, "eevee", "", [{"spp": props["taa_render_samples"], "setting": name,
                                              "eevee": props} for name, props in EEVEE_VOLUMETRICS_SETTINGS])]
    for method, engine, samples in METHODS:
        if cfg["max_spp_only"]:
            samples = samples[-1:]
        for quality in cfg["qualities"]:
            out.append((f"{method}/{quality}", engine, quality, [{"spp": s} for s in samples]))
    return [c for c in out if family(c[0], c[1]) in cfg["families"]]


def time_at_error(pt_rows, err, key="render_cpu_s"):
    """(path-tracing render time ``key`` at relative RMSE ``err``, extrapolated?), log-log interpolation."""
    pts = sorted((math.log(r["rel_rmse"]), math.log(r[key])) for r in pt_rows)
    x, y = np.array(pts).T
    lx = math.log(err)
    if x[0] <= lx <= x[-1]:
        return math.exp(np.interp(lx, x, y)), False
    i = 0 if lx < x[0] else len(x) - 2
    slope = (y[i + 1] - y[i]) / (x[i + 1] - x[i])
    return math.exp(y[i] + slope * (lx - x[i])), True


def equal_error(rows, gt_spp, key="render_cpu_s"):
    """Summary rows: each analytic and EEVEE-volumetrics point with the path-tracing time at equal error,
    in render time ``key`` (``speedup``; ``speedup_wall`` from the wall times, ``render_s``)."""
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
            t_pt, extrapolated = time_at_error(pt, r["rel_rmse"], key)
            t_wall, _ = time_at_error(pt, r["rel_rmse"], "render_s")
            summary.append({k: r[k] for k in ("scene", "beta", "method", "engine", "setting", "spp", "render_s",
                                              "render_cpu_s", "setup_s", "rel_rmse", "median_rel", "threads")}
                           | {"time_basis": key, "time_s": r[key], "pt_equal_error_s": t_pt,
                              "speedup": t_pt / r[key], "speedup_wall": t_wall / r["render_s"],
                              "extrapolated": extrapolated, "gt_noise": gt_noise})
    return summary


QUALITY_MARKERS = {"draft": "v", "final": "o", "exact": "D"}
ANALYTIC_COLOURS = {("nodes", "cycles"): "C0", ("osl", "cycles"): "C1", ("nodes", "eevee"): "C2",
                    ("compositor", "cycles"): "C3", ("compositor", "eevee"): "C4"}


def chart(rows, summary, cfg, key="render_cpu_s"):
    """One panel per scene, relative RMSE (log) vs render time (log): the path-tracing ladder as a
    black line (labels: spp), EEVEE's volumetrics as a purple dashed line (labels: setting),
    the analytic fog with a colour per method/engine and a marker per Quality (labels: spp),
    dotted lines from each EEVEE point and each analytic line's fewest-spp point to the
    path-tracing time at equal error, and the ground truth's estimated noise (errors near it
    are limited by the ground truth)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    scenes = [s for s in SCENES if any(r["scene"] == s[0] and r["status"] == "ok" for r in rows)]
    fig, axes = plt.subplots(1, len(scenes), figsize=(7.5 * len(scenes), 6.5), squeeze=False)
    for ax, (scene, beta) in zip(axes[0], scenes):
        ok = [r for r in rows if r["scene"] == scene and r["status"] == "ok"]
        pt = sorted((r for r in ok if r["method"] == PATH_TRACED), key=lambda r: r["spp"])
        ax.plot([r[key] for r in pt], [r["rel_rmse"] for r in pt], "-o", color="black", ms=4,
                label="Cycles path traced (spp)")
        for r in pt:
            ax.annotate(f"{r['spp']}", (r[key], r["rel_rmse"]), xytext=(4, 2),
                        textcoords="offset points", fontsize=7)
        ev = [r for r in ok if r["method"] == EEVEE_VOLUMETRICS]
        if ev:
            ax.plot([r[key] for r in ev], [r["rel_rmse"] for r in ev], "--s", color="purple", ms=6,
                    label="EEVEE volumetrics (setting)")
            for r in ev:
                ax.annotate(r["setting"], (r[key], r["rel_rmse"]), xytext=(5, 3),
                            textcoords="offset points", fontsize=7, color="purple")
        lowest, families, qualities = set(), {}, {}
        for (method, engine), colour in ANALYTIC_COLOURS.items():
            for quality, mk in QUALITY_MARKERS.items():
                pts = sorted((r for r in ok if r["method"] == f"{method}/{quality}" and r["engine"] == engine),
                             key=lambda r: r["spp"])
                if not pts:
                    continue
                lowest.add((pts[0]["method"], pts[0]["engine"], pts[0]["spp"]))
                ax.plot([r[key] for r in pts], [r["rel_rmse"] for r in pts], mk, color=colour,
                        mec="black", mew=0.5, ms=7, ls="none", alpha=0.85)
                families.setdefault(f"analytic {method}, {engine} (spp)", colour)
                qualities.setdefault(f"Quality {quality}", mk)
                if quality == cfg["qualities"][-1]:
                    for r in pts:
                        ax.annotate(f"{r['spp']}", (r[key], r["rel_rmse"]), xytext=(4, -10),
                                    textcoords="offset points", fontsize=7, color=colour)
        for s in summary:
            if s["scene"] == scene and (s["method"] == EEVEE_VOLUMETRICS
                                        or (s["method"], s["engine"], s["spp"]) in lowest):
                ax.plot([s["time_s"], s["pt_equal_error_s"]], [s["rel_rmse"]] * 2, ":",
                        color="purple" if s["method"] == EEVEE_VOLUMETRICS else "grey", lw=0.8)
        noise = [s["gt_noise"] for s in summary if s["scene"] == scene]
        if noise:
            ax.axhline(noise[0], color="grey", ls="-.", lw=0.6, label="ground-truth noise (estimated)")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("render {}time per frame (s): fastest of warm bpy.ops.render.render calls"
                      .format("CPU " if key == "render_cpu_s" else "wall "))
        ax.set_ylabel("relative RMSE vs path-traced ground truth")
        ax.set_title(f"{scene}, \u03b2 = {beta:g} /m", fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
        handles, labels = ax.get_legend_handles_labels()
        for name, colour in families.items():
            handles.append(Line2D([], [], color=colour, marker="s", ls="none", mec="black", mew=0.5))
            labels.append(name)
        for name, mk in qualities.items():
            handles.append(Line2D([], [], color="lightgrey", marker=mk, ls="none", mec="black", mew=0.5))
            labels.append(name)
        ax.legend(handles, labels, fontsize=7, loc="best")
    threads = f"{cfg['threads']} thread{'s' if cfg['threads'] != 1 else ''}" if cfg["threads"] else "all cores"
    fig.suptitle("Analytic fog per Quality vs Cycles path tracing and EEVEE volumetrics at {}x{}, {} "
                 "(ground truth {} spp; dotted: path-tracing time at equal error)"
                 .format(*cfg["resolution"], threads, cfg["gt_samples"]), fontsize=10)
    PNG.parent.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    fig.savefig(PNG, dpi=120)
    plt.close(fig)


def print_summary(summary):
    print(f"\n{'scene':13} {'method':18} {'engine':6} {'setting':8} {'spp':>4} {'render s':>9} {'cpu s':>7} "
          f"{'rel RMSE':>9} {'median':>7} {'PT s @ equal err':>17} {'speed-up':>9} {'(wall)':>8}")
    for s in summary:
        flag = " (extrapolated)" if s["extrapolated"] else ""
        print(f"{s['scene']:13} {s['method']:18} {s['engine']:6} {s['setting']:8} {s['spp']:4d} "
              f"{s['render_s']:9.3f} {s['render_cpu_s']:7.3f} {s['rel_rmse']:9.4f} {s['median_rel']:7.4f} "
              f"{s['pt_equal_error_s']:17.3g} {s['speedup']:9.3g} {s['speedup_wall']:8.3g}{flag}")
    for scene, noise in dict((s["scene"], s["gt_noise"]) for s in summary).items():
        print(f"{scene}: estimated ground-truth noise (rel RMSE) {noise:.4f}")


def _int_list(s):
    try:
        v = tuple(int(x) for x in s.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated integers, got {s!r}")
    if not v or min(v) < 1:
        raise argparse.ArgumentTypeError(f"expected positive integers, got {s!r}")
    return v


def read_rows(path):
    """Rows of ``speed_error.csv`` with their numbers parsed."""
    ints, texts = {"spp", "repeats", "gt_spp", "threads"}, {"scene", "method", "engine", "setting", "status",
                                                             "note", "resolution", "cpus"}
    rows = []
    with open(path, newline="") as f:
        for r in csv.DictReader(f):
            rows.append({k: (v if k in texts or v == "" else int(v) if k in ints else float(v))
                         for k, v in r.items()})
    return rows


def replot(key):
    """The summary CSV, the chart and the printed summary again from ``CSV`` (no renders)."""
    rows = read_rows(READ_CSV)
    ok = [r for r in rows if r["status"] == "ok"]
    cfg = {"resolution": tuple(int(x) for x in ok[0]["resolution"].split("x")), "gt_samples": ok[0]["gt_spp"],
           "threads": ok[0]["threads"], "qualities": tuple(q for q in QUALITIES
                                                            if any(r["setting"] == q for r in ok))}
    summary = equal_error(rows, cfg["gt_samples"], key)
    csv_rows.write(SUMMARY_CSV, summary, SUMMARY_FIELDS, digits=6)
    chart(rows, summary, cfg, key)
    print_summary(summary)
    print(f"\nwrote {SUMMARY_CSV}, {PNG} from {READ_CSV}")
    return 0


def main(argv=None):
    global SCENES
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--resolution", type=cli._resolution, metavar="WxH", help="default 160x90 (quick 48x27)")
    ap.add_argument("--quick", action="store_true",
                    help="tiny settings: 48x27, gt 512 spp, ladder 1,16,64, analytic at max spp, 1 repeat")
    ap.add_argument("--regen", action="store_true", help="re-render the cached ground truth")
    ap.add_argument("--repeats", type=cli._positive_int("repeats"),
                    help="warm renders per point (default 3, quick 1)")
    ap.add_argument("--threads", type=int, default=1, metavar="N",
                    help="render threads, each worker pinned to N CPUs (default 1; 0 = Blender's automatic "
                         "count, no pinning)")
    ap.add_argument("--scenes", help="comma-separated subset of " + ",".join(s for s, _ in SCENES))
    ap.add_argument("--ladder", type=_int_list, metavar="SPP,...", help="path-tracing spp (default "
                    + ",".join(map(str, SETTINGS["full"]["ladder"])) + ")")
    ap.add_argument("--qualities", default=smoke.pick(",".join(QUALITIES), "final"), help="comma-separated subset of "
                    + ",".join(QUALITIES) + " (default all)")
    ap.add_argument("--time", choices=sorted(TIME_KEYS), default="cpu",
                    help="render time of the speed-ups and the chart: the process CPU time (default; with "
                         "--threads 1 the time on an idle core, robust to other load) or the wall time")
    ap.add_argument("--methods", default=smoke.pick(",".join(FAMILIES), SMOKE_FAMILIES),
                    help="comma-separated subset of " + ",".join(FAMILIES) + " (default all)")
    ap.add_argument("--update", action="store_true",
                    help="keep the CSV's rows of the methods not run now (same resolution and ground truth)")
    ap.add_argument("--replot", action="store_true",
                    help="no renders: the summary CSV and the chart from the existing " + CSV.name)
    ap.add_argument("--worker", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.worker:
        return worker(json.loads(args.worker))
    key = TIME_KEYS[args.time]
    if args.replot:
        return replot(key)
    cfg = dict(SETTINGS["quick" if args.quick else smoke.pick("full", "smoke")])
    cfg["resolution"] = args.resolution or cfg["resolution"]
    cfg["repeats"] = args.repeats or cfg["repeats"]
    cfg["ladder"] = args.ladder or cfg["ladder"]
    cfg["threads"] = max(0, args.threads)
    cfg["qualities"] = tuple(q.strip() for q in args.qualities.split(","))
    if not set(cfg["qualities"]) <= set(QUALITIES):
        ap.error(f"--qualities: each of {', '.join(QUALITIES)}")
    cfg["families"] = [f.strip() for f in args.methods.split(",")]
    if not set(cfg["families"]) <= set(FAMILIES):
        ap.error(f"--methods: each of {', '.join(FAMILIES)}")
    if args.scenes:
        names = args.scenes.split(",")
        if not set(names) <= {s for s, _ in SCENES}:
            ap.error(f"--scenes: each of {', '.join(s for s, _ in SCENES)}")
        SCENES = [s for s in SCENES if s[0] in names]
    rows = []
    t_start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="speed_error_") as scratch:
        for scene, beta in SCENES:
            blend = h.scene_blend(scene, scratch)
            gt = ground_truth(scene, beta, blend, cfg, args.regen, scratch)
            for case in cases(cfg, beta):
                rows += measure_case(case, scene, beta, blend, gt, cfg, scratch)
    if args.update and READ_CSV.is_file():   # the rows of the cases not run now stay
        run = {(r["scene"], family(r["method"], r["engine"])) for r in rows}
        rows = [r for r in read_rows(READ_CSV) if (r["scene"], family(r["method"], r["engine"])) not in run] + rows
    csv_rows.write(CSV, rows, FIELDS, digits=6)
    summary = equal_error(rows, cfg["gt_samples"], key)
    csv_rows.write(SUMMARY_CSV, summary, SUMMARY_FIELDS, digits=6)
    chart(rows, summary, cfg, key)
    print_summary(summary)
    print(f"\nwrote {CSV}, {SUMMARY_CSV}, {PNG} in {time.perf_counter() - t_start:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
