"""What light shafts cost (issue 27, "Cost"): render time with fog over render time without, same scene, same
process, with N shadowed point lamps in a hall of columns, shafts on and off.

    .venv/bin/python benchmarks/shafts_cost.py [--lights 4,16,64] [--variants shafts,noshafts]
                                               [--engines cycles,eevee] [--samples 32] [--resolution 640x360]
                                               [--eevee-resolution 160x90] [--repeats N] [--budget S]
                                               [--profile-from N] [--out CSV] [--chart PNG]
    .venv/bin/python benchmarks/shafts_cost.py --chart-only [--out CSV] [--chart PNG]

Figures and their reading: docs/measurements/2026-11-26-shafts-cost.md.

The scene (built here with bmesh, ``hall``): a 40 m ground and a hall of 16 x 16 square columns (0.3 m wide,
3 m high, 1.5 m apart, centres at +-0.75, +-2.25, ... +-11.25 m); N point lamps (radius 0, 500 W each, cast
shadows) 2 m above the ground on an n x n grid over the hall (n = sqrt N: 4 lamps 12 m apart, 64 lamps 3 m
apart), each in the middle of four columns 1.06 m away, so every lamp's glow is cut by columns on every
side; the camera 20 m off a corner and 14 m up, looking at the hall's middle (24 mm lens).  Fog: beta
``DENSITY`` = 0.04/m, about 1 optical thickness across the hall (24 m) and 1.3 from the camera to the
hall's middle, so the glows overlap.  The geometry is the same for every N.

Each (engine, N, variant) runs in ONE worker process (this script with ``--worker``), one at a time:

* build the scene; render without fog: a first render, then the minimum of ``repeats`` warm ones;
* add the fog with ``fog_addon.ops.apply.apply(scene, spec)``, ``spec`` = FogSpec(density, method "auto",
  default Quality, shafts on or off) (``fog_apply_*``: the whole call, i.e. the shadow work: choosing the
  method, baking the maps, building the groups); inside it, timed by wrapping the add-on's functions:
  ``bvh_*`` (``shadow_maps.scene_bvh``: the casters' BVH), ``bake_*`` (``shadow_maps.bake``: the maps' ray
  casts), ``shaft_groups_*`` (``comp_shafts.build_shaft_group``), ``shadowing_*`` (``caveats.shadowing_lights``,
  called by Auto, the method and the notes);
* render with fog: a first render, then the minimum of ``repeats`` warm ones.

Variants: ``shafts`` (Light Shafts on, the default; Auto must choose the compositor for the shafts:
``choice``), ``shafts_draft`` (the same at Quality Draft: fewer quadrature nodes, ``shafts.SAMPLES``), ``noshafts`` (Light Shafts off, Method Auto: what Auto then chooses), ``noshafts_comp`` (Light
Shafts off, Method Compositor: the same method as ``shafts`` without the shafts).  ``shadow_maps``: the
number of shadow-map images in the file after apply.

Ratios (wall ``ratio_*`` and process CPU time ``ratio_*_cpu``, ``time.process_time``: all threads; the
machine is shared, the CPU ratios are the ones to read):

* ``ratio_warm`` = fog warm / no-fog warm;
* ``ratio_first`` = (apply + fog first) / no-fog first: what an artist waits for the first picture, the
  shadow work included; ``ratio_first_render`` = fog first / no-fog first without it.

The log (stdout and stderr of the worker) is checked for "out of SVM stack space", "too big", shader and
compositor errors (``log_errors``); the pictures for black materials (benchmarks/overhead.py
``picture_stats``, off the clock).  ``--profile-from N``: with N lamps or more, ``apply`` runs under cProfile
and the worker prints its top 10 functions by cumulative and by own time (``profile_*.txt`` beside the CSV).

Outputs: benchmarks/out/shafts_cost.csv and shafts_cost.png (ratio against lamps, CPU time: first with the
shadow work, first render alone and warm, shafts on and off; the issue's goals: 4 lamps <= 2x, 16 <= 3x), the
workers' logs in benchmarks/out/logs/; copy the CSV and the chart to docs/measurements/data/ under dated
names to keep them.  Smoke mode (``FOG_BENCH_SMOKE=1``, benchmarks/smoke.py): 1 lamp, shafts on, 8x4 px,
1 spp, one warm render, apply() profiled; a worker not ok or with log errors fails the run.
"""
import cProfile
import io
import json
import math
import os
import pathlib
import pstats
import re
import resource
import subprocess
import sys
import tempfile
import time

import cost_cli
import csv_rows
import smoke
import overhead as ov   # the timed renders (_render, _warm, BEAT), _emit, picture checks, load_avg, source_id

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

OUT = smoke.out(ROOT / "benchmarks" / "out")
CSV = OUT / "shafts_cost.csv"
KEPT = ROOT / "docs" / "measurements" / "data" / "shafts_cost_2026-11-26.csv"   # the committed run
PNG = OUT / "shafts_cost.png"

LIGHTS = smoke.pick((4, 16, 64), (1,))
DENSITY = 0.04                 # 1/m: ~1 optical thickness across the 24 m hall
LAMP_POWER = 500.0             # W per lamp
LAMP_HEIGHT = 2.0              # m
COLUMN_HALF, COLUMN_HEIGHT, COLUMN_SPACING, COLUMNS = 0.15, 3.0, 1.5, 16
HALL_HALF = 0.5 * COLUMNS * COLUMN_SPACING   # 12 m
CAMERA = ((-20.0, -20.0, 14.0), (0.0, 0.0, 0.0), 24.0)   # position m, target m, lens mm
RESOLUTION, EEVEE_RESOLUTION, SAMPLES = smoke.pick(((640, 360), (160, 90), 32), ((8, 4), (8, 4), 1))
BUDGET_S = 1800.0
REPEATS = smoke.pick(2, 1)
# variant: (method, Light Shafts, Quality; None: the default, Final)
VARIANTS = {"shafts": ("auto", True, None), "shafts_draft": ("auto", True, "draft"), "noshafts": ("auto", False, None),
            "noshafts_comp": ("compositor", False, None)}
GOALS = ((4, 2.0), (16, 3.0))
EXTRA_ERRORS = [re.compile(p) for p in (r"(?i)compositor.*\berror\b|\berror\b.*compositor", r"Traceback",
                                        r"(?i)\bexception\b")]
FIELDS = ["engine", "lights", "variant", "method", "shafts", "status", "choice", "shadow_maps", "shafted_groups",
          "log_errors", "picture_check", "surface_ratio", "dark_frac", "mean_nofog", "mean_fog",
          "ratio_warm_cpu", "ratio_first_cpu", "ratio_first_render_cpu", "ratio_warm", "ratio_first",
          "ratio_first_render",
          "nofog_first_s", "nofog_first_cpu_s", "nofog_warm_s", "nofog_warm_cpu_s",
          "fog_apply_s", "fog_apply_cpu_s", "bvh_s", "bvh_cpu_s", "bake_s", "bake_cpu_s", "bake_calls",
          "shaft_groups_s", "shaft_groups_cpu_s", "shaft_group_calls", "shadowing_s", "shadowing_cpu_s",
          "fog_first_s", "fog_first_cpu_s", "fog_first_setup_s", "fog_warm_s", "fog_warm_cpu_s", "repeats",
          "process_s", "process_cpu_s", "load_avg_start", "load_avg_end", "resolution", "samples", "density",
          "source", "note"]
TEXT_FIELDS = ("engine", "variant", "method", "status", "choice", "picture_check", "resolution", "source", "note")


# ---------------------------------------------------------------- the scene (inside bpy)

def lamp_positions(n_lights):
    """(x, y, z) m of ``n_lights`` (a square number) lamps on a regular grid over the hall."""
    n = int(round(math.sqrt(n_lights)))
    if n * n != n_lights:
        raise ValueError(f"{n_lights} lamps: a square number is needed (4, 16, 64)")
    xs = [-HALL_HALF + (i + 0.5) * 2.0 * HALL_HALF / n for i in range(n)]
    return [(x, y, LAMP_HEIGHT) for y in xs for x in xs]


def hall(scene, n_lights):
    """The benchmark's scene on ``scene``: ground, 16 x 16 columns, ``n_lights`` lamps, camera, world."""
    from demo_scenes import add_box, add_camera, add_point_light, add_plane, material, render_settings, set_world
    render_settings(scene)
    set_world(scene)
    stone = material("Stone", (0.55, 0.52, 0.48), roughness=0.8)
    ground = material("Ground", (0.3, 0.3, 0.3), roughness=0.6)
    add_plane(scene, "Ground", -20.0, 20.0, -20.0, 20.0, 0.0, ground)
    for i in range(COLUMNS):
        for j in range(COLUMNS):
            x, y = (-HALL_HALF + (k + 0.5) * COLUMN_SPACING for k in (i, j))
            add_box(scene, f"Column {i:02d} {j:02d}", (x, y, 0.5 * COLUMN_HEIGHT),
                    (COLUMN_HALF, COLUMN_HALF, 0.5 * COLUMN_HEIGHT), stone)
    for k, pos in enumerate(lamp_positions(n_lights)):
        add_point_light(scene, f"Lamp {k:02d}", pos, LAMP_POWER)
    add_camera(scene, CAMERA[0], CAMERA[1], lens=CAMERA[2])
    return scene


# ---------------------------------------------------------------- worker (inside bpy)

class _Timers:
    """Wall and CPU time spent in wrapped functions (``wrap``), and their calls."""

    def __init__(self):
        self.wall, self.cpu, self.calls = {}, {}, {}

    def wrap(self, module, name, key):
        inner = getattr(module, name)

        def timed(*args, **kwargs):
            c, t = time.process_time(), time.perf_counter()
            try:
                return inner(*args, **kwargs)
            finally:
                self.wall[key] = self.wall.get(key, 0.0) + time.perf_counter() - t
                self.cpu[key] = self.cpu.get(key, 0.0) + time.process_time() - c
                self.calls[key] = self.calls.get(key, 0) + 1

        setattr(module, name, timed)


def _profile_top(prof, key, n=10):
    s = io.StringIO()
    pstats.Stats(prof, stream=s).sort_stats(key).print_stats(n)
    return s.getvalue()


def worker(spec):
    """Time one (engine, lights, variant): no fog (first, warm), apply, fog (first, warm); print as it goes."""
    import bpy
    from fog_addon import caveats, shadow_maps
    from fog_addon.nodes import comp_shafts
    from fog_addon.ops import apply
    from fog_addon.precompute.core.spec import FogSpec

    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = hall(bpy.context.scene, spec["lights"])
    cycles = spec["engine"] == "cycles"
    ov.cost_settings(scene, cycles, spec["resolution"], spec["samples"])
    bpy.app.handlers.render_stats.append(ov.BEAT)
    tmp = pathlib.Path(os.environ.get("TMPDIR") or tempfile.gettempdir())
    tag = f"shafts_{spec['engine']}_{spec['lights']}_{spec['variant']}_{os.getpid()}"
    res = {"lights": len([o for o in scene.objects if o.type == "LIGHT"])}
    res["nofog_first_s"], res["nofog_first_cpu_s"] = ov._render(scene, "nofog_first")
    ov._emit(res)
    res["nofog_warm_s"], res["nofog_warm_cpu_s"], _ = ov._warm(scene, spec["repeats"], "nofog_warm")
    ov._emit(res)
    nofog = ov._save_render(scene, tmp / f"{tag}_nofog.exr")

    timers = _Timers()
    timers.wrap(shadow_maps, "scene_bvh", "bvh")
    timers.wrap(shadow_maps, "bake", "bake")
    timers.wrap(comp_shafts, "build_shaft_group", "shaft_groups")
    timers.wrap(caveats, "shadowing_lights", "shadowing")
    method, shafts_on, quality = VARIANTS[spec["variant"]]
    fog = FogSpec(density=DENSITY, method=method, shafts=shafts_on,
                  **({"quality": quality} if quality is not None else {}))
    prof = cProfile.Profile() if spec.get("profile") else None
    c, t = time.process_time(), time.perf_counter()
    if prof is not None:
        prof.enable()
    notes = apply.apply(scene, fog)
    if prof is not None:
        prof.disable()
    res["fog_apply_s"], res["fog_apply_cpu_s"] = time.perf_counter() - t, time.process_time() - c
    for key in ("bvh", "bake", "shaft_groups", "shadowing"):
        res[f"{key}_s"], res[f"{key}_cpu_s"] = timers.wall.get(key, 0.0), timers.cpu.get(key, 0.0)
    res["bake_calls"], res["shaft_group_calls"] = timers.calls.get("bake", 0), timers.calls.get("shaft_groups", 0)
    # a wrapped function the add-on no longer calls through its module would time 0 s unseen
    smoke.check(not shafts_on or len(timers.calls) == 4, f"wrapped functions not called: "
                f"{sorted({'bvh', 'bake', 'shaft_groups', 'shadowing'} - set(timers.calls))}")
    res["choice"] = apply.method_line(apply.stored_choice() or {}) or ""
    res["method"] = (apply.stored_choice() or {}).get("method", "")
    res["shadow_maps"] = sum(1 for img in bpy.data.images if img.name.startswith(shadow_maps.IMAGE_PREFIX))
    res["shafted_groups"] = sum(1 for ng in bpy.data.node_groups if ng.name.startswith(comp_shafts.SHAFT_GROUP + " "))
    res["notes"] = [f"{a}: {b}" for a, b in notes]
    if prof is not None:
        for key in ("cumulative", "tottime"):
            print(f"PROFILE_{key.upper()}\n" + _profile_top(prof, key) + "PROFILE_END", flush=True)
    scene.cycles.use_denoising = False
    ov._emit(res)
    res["fog_first_s"], res["fog_first_cpu_s"] = ov._render(scene, "fog_first")
    if ov.BEAT.first_sample is not None:
        res["fog_first_setup_s"] = ov.BEAT.first_sample
    ov._emit(res)
    res.update(ov.picture_stats(nofog, ov._save_render(scene, tmp / f"{tag}_fog.exr")))
    ov._emit(res)
    res["fog_warm_s"], res["fog_warm_cpu_s"], res["repeats"] = ov._warm(scene, spec["repeats"], "fog_warm")
    ov._emit(res)
    return 0


# ---------------------------------------------------------------- driver

def log_errors(text):
    """The log lines that mean a render is wrong: render_harness's patterns, and compositor errors."""
    from fog_scenes import render_harness as h
    extra = [ln.strip() for ln in text.splitlines() if any(p.search(ln) for p in EXTRA_ERRORS)]
    return list(dict.fromkeys(h.log_errors(text) + extra))


def run_worker(spec, budget, script=__file__):
    """(last result, log text, status, wall s, CPU s of the worker process ``script`` --worker ``spec``)."""
    from fog_scenes import render_harness as h
    env = dict(h._env(), PYTHONUNBUFFERED="1")
    cmd = [h.PYTHON, str(pathlib.Path(script).resolve()), "--worker", json.dumps(spec)]
    t, ru0 = time.perf_counter(), resource.getrusage(resource.RUSAGE_CHILDREN)
    try:
        proc = subprocess.run(cmd, cwd=str(ROOT), env=env, capture_output=True, text=True, timeout=budget)
        out, err = proc.stdout, proc.stderr
        status = "ok" if proc.returncode == 0 else f"exit {proc.returncode}"
    except subprocess.TimeoutExpired as exc:
        dec = (lambda b: b.decode(errors="replace") if isinstance(b, bytes) else (b or ""))
        out, err, status = dec(exc.stdout), dec(exc.stderr), f"timeout after {budget:.0f} s"
    wall = time.perf_counter() - t
    ru1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (ru1.ru_utime - ru0.ru_utime) + (ru1.ru_stime - ru0.ru_stime)
    lines = [ln for ln in out.splitlines() if ln.startswith("OVERHEAD_JSON ")]
    res = json.loads(lines[-1].split(" ", 1)[1]) if lines else {}
    return res, out + "\n" + err, status, wall, cpu


def ratios(row):
    for suffix in ("", "_cpu"):
        s = "_cpu_s" if suffix else "_s"
        get = lambda k: row.get(k + s)
        if get("fog_warm") and get("nofog_warm"):
            row["ratio_warm" + suffix] = get("fog_warm") / get("nofog_warm")
        if get("fog_first") and get("nofog_first"):
            row["ratio_first_render" + suffix] = get("fog_first") / get("nofog_first")
            row["ratio_first" + suffix] = (get("fog_apply") + get("fog_first")) / get("nofog_first")
    return row


def measure(engine, n, variant, args):
    resolution = args.resolution if engine == "cycles" else args.eevee_resolution
    spec = {"engine": engine, "lights": n, "variant": variant, "repeats": args.repeats, "samples": args.samples,
            "resolution": resolution, "profile": n >= args.profile_from}
    load0 = ov.load_avg()
    res, log, status, wall, cpu = run_worker(spec, args.budget)
    errors = log_errors(log)
    smoke.echo(log)
    smoke.check(status == "ok" and not errors, f"{engine} {n} {variant}: {status}, log errors {errors[:3]}")
    row = {k: v for k, v in res.items() if k in FIELDS}
    row.update(engine=engine, lights=n, variant=variant, shafts=VARIANTS[variant][1], status=status,
               log_errors=len(errors), process_s=wall, process_cpu_s=cpu, load_avg_start=load0,
               load_avg_end=ov.load_avg(), resolution="{}x{}".format(*resolution), samples=args.samples,
               density=DENSITY, source=args.source)
    notes = [n_ for n_ in res.get("notes", []) if "shaft" in n_.lower() or "shadow" in n_.lower()]
    row["note"] = " | ".join(errors[:3] + notes[:2])[:600]
    ratios(row)
    tag = f"{engine}_{n}_{variant}"
    (OUT / "logs").mkdir(parents=True, exist_ok=True)
    (OUT / "logs" / f"shafts_cost_{tag}.log").write_text(log)
    prof = re.findall(r"PROFILE_(\w+)\n(.*?)PROFILE_END", log, re.S)
    if prof:
        (OUT / f"shafts_cost_profile_{tag}.txt").write_text("\n".join(f"== {k}\n{v}" for k, v in prof))
    for e in errors[:10]:
        print("   LOG:", e)
    return row


def read_csv(path):
    return csv_rows.read(path, TEXT_FIELDS)


def chart(rows, path):
    """Fog / no fog (process CPU time) against lamps, log x: per (engine, variant) the first render with
    the shadow work (dashed) and the warm render (solid); wall ratios as small dots; the issue's goals."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(10, 5.5))
    labels = {"shafts": "shafts on (Auto)", "shafts_draft": "shafts on, Quality Draft (Auto)", "noshafts": "shafts off (Auto)",
              "noshafts_comp": "shafts off (Compositor)"}
    i = 0
    for engine in ("cycles", "eevee"):
        for variant in VARIANTS:
            mine = sorted((r for r in rows if r["engine"] == engine and r["variant"] == variant),
                          key=lambda r: r["lights"])
            if not mine:
                continue
            colour = f"C{i}"
            i += 1
            res = mine[0].get("resolution", "")
            for key, ls, what in (("ratio_warm_cpu", "-", "warm"), ("ratio_first_cpu", "--", "first + apply"),
                                  ("ratio_first_render_cpu", ":", "first, render alone")):
                pts = [(r["lights"], r[key]) for r in mine if isinstance(r.get(key), float)]
                if pts:
                    ax.plot(*zip(*pts), ls, marker="o", color=colour, lw=1.3,
                            label=f"{engine.capitalize()} {res}, {labels[variant]}: {what}")
                wall = [(r["lights"] * {"-": 0.95, "--": 1.05, ":": 1.0}[ls], r[key[:-4]]) for r in mine
                        if isinstance(r.get(key[:-4]), float)]
                if wall:
                    ax.plot(*zip(*wall), ".", color=colour, mec="grey", ms=5, alpha=0.8)
    gx, gy = zip(*GOALS)
    ax.plot(gx, gy, "s", color="black", ms=8, alpha=0.7, label="issue 27's goals (Cycles): 4 lamps 2x, 16 lamps 3x")
    ax.plot([], [], ".", color="grey", ms=5, ls="none", label="wall-clock ratio (shared machine)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xticks(list(LIGHTS))
    ax.set_xticklabels([str(n) for n in LIGHTS])
    ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    ax.set_xlim(3, 85)
    ax.set_xlabel("shadowed point lamps")
    ax.set_ylabel("CPU time with fog / without fog")
    src = ", ".join(dict.fromkeys(str(r.get("source", "")) for r in rows))
    spp = rows[0].get("samples", "") if rows else ""
    ax.set_title(f"Cost of light shafts: hall of columns, beta {DENSITY}/m, {spp:g} spp, default Quality, "
                 f"code {src}\n(benchmarks/shafts_cost.py)" if isinstance(spp, float) else "Cost of light shafts",
                 fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7.5, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    fig.savefig(path, dpi=120, bbox_inches="tight")
    plt.close(fig)


def fmt(v):
    return f"{v:.3g}" if isinstance(v, float) else ("-" if v in (None, "") else str(v))


def print_table(rows):
    print(f"\n{'engine':6} {'N':>3} {'variant':13} {'status':8} {'maps':>4} {'apply':>6} {'bake':>6} {'groups':>6} "
          f"{'nofog1':>7} {'fog1':>7} {'nofogw':>7} {'fogw':>7} | {'1st cpu':>7} {'1r cpu':>7} {'warm cpu':>8} | "
          f"{'1st':>6} {'warm':>6} log pic")
    for r in rows:
        print(f"{r['engine']:6} {int(r['lights']):3d} {r['variant']:13} {str(r['status'])[:8]:8} "
              f"{fmt(r.get('shadow_maps')):>4} {fmt(r.get('fog_apply_cpu_s')):>6} {fmt(r.get('bake_cpu_s')):>6} "
              f"{fmt(r.get('shaft_groups_cpu_s')):>6} {fmt(r.get('nofog_first_cpu_s')):>7} "
              f"{fmt(r.get('fog_first_cpu_s')):>7} {fmt(r.get('nofog_warm_cpu_s')):>7} {fmt(r.get('fog_warm_cpu_s')):>7}"
              f" | {fmt(r.get('ratio_first_cpu')):>7} {fmt(r.get('ratio_first_render_cpu')):>7} "
              f"{fmt(r.get('ratio_warm_cpu')):>8} | {fmt(r.get('ratio_first')):>6} {fmt(r.get('ratio_warm')):>6} "
              f"{fmt(r.get('log_errors'))} {r.get('picture_check', '-')}  {r.get('choice', '')[:90]}")


def main(argv=None):
    ap = cost_cli.parser(__doc__, SAMPLES, RESOLUTION, EEVEE_RESOLUTION, REPEATS, CSV, PNG)
    ap.add_argument("--lights", default=",".join(map(str, LIGHTS)))
    ap.add_argument("--variants", default=smoke.pick("shafts,noshafts", "shafts"))
    ap.add_argument("--engines", default="cycles")
    ap.add_argument("--budget", type=float, default=BUDGET_S, help="seconds per worker")
    ap.add_argument("--profile-from", type=int, default=smoke.pick(64, 1), help="profile apply() from this many lamps")
    args = ap.parse_args(argv)
    code = cost_cli.dispatch(args, worker, read_csv, chart, print_table, KEPT)
    if code is not None:
        return code
    args.source = ov.source_id()
    os.environ.setdefault("TMPDIR", tempfile.mkdtemp(prefix="shafts_cost_"))
    print(f"code {args.source}, {args.samples} spp, load {ov.load_avg()}, {os.cpu_count()} CPUs", flush=True)
    kept = read_csv(args.out) if args.update and args.out.exists() else []
    rows = []
    for engine in args.engines.split(","):
        for n in sorted(int(x) for x in args.lights.split(",")):
            for variant in args.variants.split(","):
                row = measure(engine, n, variant, args)
                rows.append(row)
                print(f"{engine} {n:3d} {variant:13} {row['status']}: first {fmt(row.get('ratio_first_cpu'))}x CPU "
                      f"({fmt(row.get('ratio_first'))}x wall), render only {fmt(row.get('ratio_first_render_cpu'))}x,"
                      f" warm {fmt(row.get('ratio_warm_cpu'))}x CPU ({fmt(row.get('ratio_warm'))}x wall); apply "
                      f"{fmt(row.get('fog_apply_s'))} s (bake {fmt(row.get('bake_s'))}, groups "
                      f"{fmt(row.get('shaft_groups_s'))}); maps {row.get('shadow_maps')}; "
                      f"load {row['load_avg_start']} -> {row['load_avg_end']}; {row.get('choice', '')[:120]}",
                      flush=True)
                done = {(r["engine"], int(r["lights"]), r["variant"]) for r in rows}
                out = [r for r in kept if (r["engine"], int(r["lights"]), r["variant"]) not in done] + rows
                out.sort(key=lambda r: (r["engine"], int(r["lights"]), list(VARIANTS).index(r["variant"])))
                csv_rows.write(args.out, out, FIELDS, digits=4)
    rows = read_csv(args.out)
    chart(rows, args.chart)
    print_table(rows)
    print(f"\nwrote {args.out}, {args.chart}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
