"""A city at night (issue 47): what the fog costs with N shafted street lamps, in time and memory, against the same
render without fog, the public operator's defaults (Method Auto, Light Shafts on, Quality Final).

    .venv/bin/python benchmarks/city_night.py [--lights 1,10,100,400,1000] [--resolution 640x360] [--samples 32]
                                              [--repeats N] [--budget S] [--out CSV] [--chart PNG] [--update]
    .venv/bin/python benchmarks/city_night.py --chart-only

The scene is ``demo_scenes/city_night.py`` (twelve blocks on a 120 m square, N lamps along the streets, the camera
on a roof; fog beta 0.02/m).  Each N runs in ONE worker process (this script with ``--worker``), one at a time:
no fog (a first render, then the minimum of ``repeats`` warm ones), ``apply`` (``fog_apply_s``; inside it the
casters' BVH, the maps' ray casts and the shaft groups, timed by wrapping the add-on's functions), fog (first,
warm).  Peak memory is the worker's resident set at its highest (``ru_maxrss``) after each phase: ``rss_nofog_gb``
(the scene and its fog-free renders), ``rss_apply_gb``, ``rss_fog_gb``; ``fog_peak_gb`` = ``rss_fog_gb`` -
``rss_nofog_gb``, what the fog adds.  ``map_points_m``: the shadow maps' grid points (millions) in the file;
``predicted``: Auto's predicted ratio (``methods.auto.predicted_ratio``, the compositor's, read from its choice).
Ratios are process CPU time (``time.process_time``: all threads): warm = fog warm / no-fog warm; first = (apply +
fog first) / no-fog first.  The log is checked for "out of SVM stack space" and compositor errors, the picture
for black surfaces.

Outputs: benchmarks/out/city_night.csv and city_night.png (the ratios and the fog's memory against lamps, the
issue's goals); copy them to docs/measurements/data/ under dated names to keep them.  Smoke mode
(``FOG_BENCH_SMOKE=1``): 4 lamps, 8x4 px, 1 spp.
"""
import os
import pathlib
import re
import resource
import sys
import tempfile
import time

import cost_cli
import csv_rows
import overhead as ov
import shafts_cost as sc   # the timers, the worker's process, the log's checks
import smoke

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

OUT = smoke.out(ROOT / "benchmarks" / "out")
CSV = OUT / "city_night.csv"
KEPT = ROOT / "docs" / "measurements" / "data" / "city_night_2026-12-01.csv"
PNG = OUT / "city_night.png"
LIGHTS = smoke.pick((1, 10, 100, 400, 1000), (4,))
RESOLUTION, SAMPLES = smoke.pick(((640, 360), 32), ((8, 4), 1))
REPEATS = smoke.pick(2, 1)
BUDGET_S = 3600.0
# issue 47's goals (Cycles, 640x360, 32 spp): lamps -> (Add Fog s, fog's peak GB over the fog-free render, warm)
GOALS = {400: (30.0, 4.0, 2.5), 1000: (60.0, 6.0, 3.0)}
FIELDS = ["lights", "resolution", "samples", "status", "choice", "shadow_maps", "map_points_m", "shaft_groups",
          "log_errors", "picture_check", "fog_apply_s", "fog_apply_cpu_s", "bvh_s", "bake_s", "shaft_groups_s",
          "rss_nofog_gb", "rss_apply_gb", "rss_fog_gb", "fog_peak_gb", "nofog_first_cpu_s", "nofog_warm_cpu_s",
          "fog_first_cpu_s", "fog_warm_cpu_s", "ratio_first_cpu", "ratio_warm_cpu", "ratio_first", "ratio_warm",
          "predicted", "process_s", "load_avg_start", "load_avg_end", "source", "note"]
TEXT_FIELDS = ("resolution", "status", "choice", "picture_check", "source", "note")


def _rss_gb():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6   # (kB on Linux)


def worker(spec):
    """Time and weigh one N: no fog, apply, fog; print as it goes (``overhead._emit``)."""
    import bpy
    from demo_scenes import city_night
    from fog_addon import caveats, shadow_maps
    from fog_addon.nodes import comp_shafts
    from fog_addon.ops import apply
    from fog_addon.precompute.core.spec import FogSpec

    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = city_night.build(bpy.context.scene, spec["lights"])
    ov.cost_settings(scene, True, spec["resolution"], spec["samples"])
    bpy.app.handlers.render_stats.append(ov.BEAT)
    tmp = pathlib.Path(os.environ.get("TMPDIR") or tempfile.gettempdir())
    res = {"lights": spec["lights"]}
    res["nofog_first_s"], res["nofog_first_cpu_s"] = ov._render(scene, "nofog_first")
    res["nofog_warm_s"], res["nofog_warm_cpu_s"], _ = ov._warm(scene, spec["repeats"], "nofog_warm")
    nofog = ov._save_render(scene, tmp / f"city_{spec['lights']}_nofog_{os.getpid()}.exr")
    res["rss_nofog_gb"] = _rss_gb()
    ov._emit(res)
    timers = sc._Timers()
    timers.wrap(shadow_maps, "scene_bvh", "bvh")
    timers.wrap(shadow_maps, "bake", "bake")
    timers.wrap(comp_shafts, "build_shaft_group", "shaft_groups")
    timers.wrap(caveats, "shadowing_lights", "shadowing")
    c, t = time.process_time(), time.perf_counter()
    apply.apply(scene, FogSpec(density=city_night.DEFAULT_DENSITY))
    res["fog_apply_s"], res["fog_apply_cpu_s"] = time.perf_counter() - t, time.process_time() - c
    res["rss_apply_gb"] = _rss_gb()
    for key in ("bvh", "bake", "shaft_groups"):
        res[f"{key}_s"] = timers.wall.get(key, 0.0)
    choice = apply.stored_choice() or {}
    res["choice"] = apply.method_line(choice) or ""
    maps = [img for img in bpy.data.images if img.name.startswith(shadow_maps.IMAGE_PREFIX)]
    res["shadow_maps"] = len(maps)
    res["map_points_m"] = sum(img.size[0] * img.size[1] for img in maps) / 1e6
    res["shaft_groups"] = timers.calls.get("shaft_groups", 0)
    found = re.search(r"predicted [0-9.]+x with node groups, ([0-9.]+)x with the compositor", res["choice"])
    res["predicted"] = float(found.group(1)) if found else None   # Auto's own
    ov._emit(res)
    res["fog_first_s"], res["fog_first_cpu_s"] = ov._render(scene, "fog_first")
    res.update(ov.picture_stats(nofog, ov._save_render(scene, tmp / f"city_{spec['lights']}_fog_{os.getpid()}.exr")))
    ov._emit(res)
    res["fog_warm_s"], res["fog_warm_cpu_s"], _ = ov._warm(scene, spec["repeats"], "fog_warm")
    res["rss_fog_gb"] = _rss_gb()
    res["fog_peak_gb"] = res["rss_fog_gb"] - res["rss_nofog_gb"]
    ov._emit(res)
    return 0


def run_worker(spec, budget):
    """shafts_cost's worker run, with this script as the worker."""
    return sc.run_worker(spec, budget, script=__file__)


def measure_one(n, args):
    load0 = ov.load_avg()
    spec = {"lights": n, "repeats": args.repeats, "samples": args.samples, "resolution": args.resolution}
    res, log, status, wall, _ = run_worker(spec, args.budget)
    errors = sc.log_errors(log)
    smoke.echo(log)
    smoke.check(status == "ok" and not errors, f"{n} lamps: {status}, log errors {errors[:3]}")
    row = {k: v for k, v in res.items() if k in FIELDS}
    row.update(lights=n, status=status, log_errors=len(errors), process_s=wall, load_avg_start=load0,
               load_avg_end=ov.load_avg(), resolution="{}x{}".format(*args.resolution), samples=args.samples,
               source=args.source, note=" | ".join(errors[:3])[:300])
    sc.ratios(row)
    (OUT / "logs").mkdir(parents=True, exist_ok=True)
    (OUT / "logs" / f"city_night_{n}_{row['resolution']}.log").write_text(log)
    return row


def chart(rows, path):
    """Left: fog / no fog (CPU) against lamps, first with Add Fog and warm, Auto's prediction; right: Add Fog's
    seconds and the fog's peak memory (GB); the issue's goals as squares."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(12, 4.8))
    for res in dict.fromkeys(r["resolution"] for r in rows):
        mine = sorted((r for r in rows if r["resolution"] == res), key=lambda r: r["lights"])
        for key, ls, what in (("ratio_warm_cpu", "-", "warm"), ("ratio_first_cpu", "--", "first + Add Fog"),
                              ("predicted", ":", "Auto's prediction")):
            pts = [(r["lights"], r[key]) for r in mine if isinstance(r.get(key), float)]
            if pts:
                a1.plot(*zip(*pts), ls, marker="o", label=f"{res}: {what}")
        for key, ls, what in (("fog_apply_s", "-", "Add Fog, s"), ("fog_peak_gb", "--", "fog's peak memory, GB")):
            pts = [(r["lights"], r[key]) for r in mine if isinstance(r.get(key), float)]
            if pts:
                a2.plot(*zip(*pts), ls, marker="o", label=f"{res}: {what}")
    for n, (apply_s, gb, warm) in GOALS.items():
        a1.plot([n], [warm], "ks", alpha=0.6)
        a2.plot([n, n], [apply_s, gb], "ks", alpha=0.6)
    a1.plot([], [], "ks", alpha=0.6, label="issue 47's goals (640x360)")
    for ax, label in ((a1, "CPU time with fog / without"), (a2, "seconds / GB")):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("street lamps (each by walls; the Quality shafts at most 64)")
        ax.set_ylabel(label)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7.5)
    src = ", ".join(dict.fromkeys(str(r.get("source", "")) for r in rows))
    fig.suptitle(f"A city at night: beta 0.02/m, Cycles CPU, defaults, code {src} (benchmarks/city_night.py)",
                 fontsize=9)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)   # (the worker's process renders; this one only draws)


def print_table(rows):
    print(f"\n{'N':>5} {'res':>9} {'status':8} {'maps':>5} {'Mpts':>6} {'apply':>6} {'bake':>5} {'peak':>5} "
          f"{'1st':>6} {'warm':>6} {'pred':>6}")
    for r in rows:
        f = sc.fmt
        print(f"{int(r['lights']):5d} {r['resolution']:>9} {str(r['status'])[:8]:8} {f(r.get('shadow_maps')):>5} "
              f"{f(r.get('map_points_m')):>6} {f(r.get('fog_apply_s')):>6} {f(r.get('bake_s')):>5} "
              f"{f(r.get('fog_peak_gb')):>5} {f(r.get('ratio_first_cpu')):>6} {f(r.get('ratio_warm_cpu')):>6} "
              f"{f(r.get('predicted')):>6}  {r.get('picture_check', '-')}")


def main(argv=None):
    ap = cost_cli.parser(__doc__, SAMPLES, RESOLUTION, RESOLUTION, REPEATS, CSV, PNG)
    ap.add_argument("--lights", default=",".join(map(str, LIGHTS)))
    ap.add_argument("--budget", type=float, default=BUDGET_S, help="seconds per worker")
    args = ap.parse_args(argv)
    code = cost_cli.dispatch(args, worker, lambda p: csv_rows.read(p, TEXT_FIELDS), chart, print_table, KEPT)
    if code is not None:
        return code
    args.source = ov.source_id()
    os.environ.setdefault("TMPDIR", tempfile.mkdtemp(prefix="city_night_"))
    kept = csv_rows.read(args.out, TEXT_FIELDS) if args.update and args.out.exists() else []
    rows = []
    for n in sorted(int(x) for x in args.lights.split(",")):
        rows.append(measure_one(n, args))
        print_table(rows[-1:])
        done = {(int(r["lights"]), r["resolution"]) for r in rows}
        out = [r for r in kept if (int(r["lights"]), r["resolution"]) not in done] + rows
        out.sort(key=lambda r: (r["resolution"], int(r["lights"])))
        csv_rows.write(args.out, out, FIELDS, digits=4)
    return cost_cli.finish(args, csv_rows.read(args.out, TEXT_FIELDS), chart, print_table)


if __name__ == "__main__":
    sys.exit(main())
