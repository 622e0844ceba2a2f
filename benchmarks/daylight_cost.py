"""What the daylight fog costs (issue 29, "Cost: <= 1.3x the fog-free render, in the benchmark's protocol"): the
render with the fog layer over the same render without it, in one process, for the city of fog_scenes/daylight.py
(a sun at 40 degrees, a light-blue sky, ten buildings), first and warm renders.

    .venv/bin/python benchmarks/daylight_cost.py [--cases hard_g0_inside,...] [--runs cycles:compositor,...]
                                                 [--samples 32] [--resolution 640x360] [--eevee-samples 16]
                                                 [--eevee-resolution 160x90] [--repeats 2] [--update]
    .venv/bin/python benchmarks/daylight_cost.py --chart-only

The protocol of shafts_cost.py and area_cost.py: Cycles CPU, 640x360, 32 spp, no denoiser; EEVEE (software GL
here, slow) at 160x90 and 16 samples, reported with no goal.  The scene is the city as
``python -m fog_scenes.daylight OUT.blend --case CASE`` builds it without its fog box (``daylight.build``,
with_fog False): the add-on's test conventions (no cast shadows, no interreflection, one diffuse bounce, volume
bounces 0), as the render tests render it against Cycles; camera ``inside`` (1.6 m up, in the layer).  The fog is
the case's layer (``daylight.layer``): density 0.01/m, albedo 0.9, Henyey-Greenstein g 0 or 0.7, a hard top at
100 m (``hard``) or 60 m with a 50 m falloff above (``falloff``), and in the ``_air`` cases Air 1 (the aerial
perspective's kernels: what they cost per pixel does not depend on the distances), added with
``fog_addon.ops.apply.apply(scene, FogSpec(..., method=METHOD, fog_top=..., height_falloff=...))`` (what
``python -m fog_addon render ... --method METHOD`` calls).

Each (engine, method, case) runs in ONE worker process (this script with ``--worker``, through
``worker_result.run``), one at a time:

* build the city; render without fog: a first render, then the minimum of ``repeats`` warm ones;
* add the fog (``apply_*``: the whole call; inside it, timed by wrapping the add-on's functions: ``bake_*``
  ``daylight_tables.bake_fog_light``, the fog light's irradiance map (0 when the table cache,
  ``precompute/core/table_cache.py``, holds it); ``probe_*`` ``sunsky.probe_sky``, the World's equirectangular probe
  render; ``comp_group_*`` ``comp_fog.build_fog_group``; ``surface_group_*``
  ``surface_group.build_surface``);
* render with fog: a first render, then the minimum of ``repeats`` warm ones;
* with the compositor's fog group muted (``nocomp_warm_*``, warm renders): what the rest of the fog costs
  (the materials' daylight terms and AOVs); the compositor's part is ``fog_warm - nocomp_warm``.
* count the nodes of the fog's groups: ``comp_nodes`` (the compositor fog group's own nodes),
  ``comp_nodes_all`` (every node it evaluates, group nodes expanded into their trees, recursively),
  ``comp_groups`` (distinct sub-groups); ``surface_nodes``/``_all`` and ``world_nodes``/``_all`` likewise
  for the node groups' Surface and World groups.

Times are process CPU time (``time.process_time``, all threads: Cycles', the compositor's, llvmpipe's; ``*_cpu_s``)
and wall time (``*_s``).  The machine is shared: the CPU ratios are the ones to read.  Ratios: ``ratio_warm`` =
fog warm / no-fog warm; ``ratio_first_render`` = fog first / no-fog first; ``ratio_first`` = (apply + fog first)
/ no-fog first.  The pictures are checked off the clock (overhead.py ``picture_stats``: no black materials).

Outputs: benchmarks/out/daylight_cost.csv and daylight_cost.png.  Figures and their reading:
docs/measurements/2026-11-27-daylight-cost.md.  Smoke mode (``FOG_BENCH_SMOKE=1``, benchmarks/smoke.py): the case
falloff_g0.7_inside_air, Cycles and the Compositor, 8x4 px, 1 spp, one warm render.
"""
import os
import pathlib
import sys
import tempfile
import time

import cost_cli
import csv_rows
import smoke
import worker_result

ROOT = pathlib.Path(__file__).resolve().parents[1]
OUT = smoke.out(ROOT / "benchmarks" / "out")
CSV = OUT / "daylight_cost.csv"
PNG = OUT / "daylight_cost.png"
KEPT = ROOT / "docs" / "measurements" / "data" / "daylight_cost_2026-11-27.csv"   # the committed run, if kept

CASES = smoke.pick(("hard_g0_inside", "hard_g0.7_inside", "falloff_g0_inside", "falloff_g0.7_inside",
                    "hard_g0_inside_air", "falloff_g0.7_inside_air"), ("falloff_g0.7_inside_air",))
AIR_SUFFIX = "_air"   # a case with Air 1 (``split_air``)
RUNS = smoke.pick(("cycles:compositor", "cycles:nodes", "eevee:compositor"), ("cycles:compositor",))   # engine:method
RESOLUTION, SAMPLES = smoke.pick(((640, 360), 32), ((8, 4), 1))
EEVEE_RESOLUTION, EEVEE_SAMPLES = smoke.pick(((160, 90), 16), ((8, 4), 1))
REPEATS = smoke.pick(2, 1)
GOAL = 1.3   # the issue's: fog / no fog, Cycles
FIELDS = ["engine", "method", "case", "status", "choice", "picture_check", "surface_ratio", "dark_frac",
          "mean_nofog", "mean_fog",
          "ratio_warm_cpu", "ratio_first_render_cpu", "ratio_first_cpu", "ratio_warm", "ratio_first_render",
          "ratio_first",
          "nofog_first_s", "nofog_first_cpu_s", "nofog_warm_s", "nofog_warm_cpu_s",
          "apply_s", "apply_cpu_s", "bake_s", "bake_cpu_s", "probe_s", "probe_cpu_s", "comp_group_s",
          "comp_group_cpu_s", "surface_group_s", "surface_group_cpu_s",
          "fog_first_s", "fog_first_cpu_s", "fog_first_setup_s", "fog_warm_s", "fog_warm_cpu_s",
          "nocomp_warm_s", "nocomp_warm_cpu_s", "comp_share_cpu", "repeats",
          "comp_nodes", "comp_nodes_all", "comp_groups", "surface_nodes", "surface_nodes_all", "world_nodes",
          "world_nodes_all", "images", "notes",
          "process_s", "load_avg_start", "load_avg_end", "resolution", "samples", "source"]
TEXT_FIELDS = ("engine", "method", "case", "status", "choice", "picture_check", "notes", "resolution", "source")


# ---------------------------------------------------------------- worker (inside bpy)

def node_counts(tree):
    """(own nodes, nodes evaluated with group nodes expanded recursively, distinct sub-groups) of ``tree``."""
    memo, groups = {}, set()

    def expanded(t):
        if t.name not in memo:
            n = 0
            for node in t.nodes:
                sub = getattr(node, "node_tree", None)
                if sub is not None and node.bl_idname.endswith("NodeGroup"):
                    groups.add(sub.name)
                    n += expanded(sub)
                else:
                    n += 1
            memo[t.name] = n
        return memo[t.name]

    return len(tree.nodes), expanded(tree), len(groups)


def _wrap(module, name, key, wall, cpu):
    """Replace ``module.name`` by a wrapper adding its wall and CPU seconds to ``wall[key]``, ``cpu[key]``."""
    inner = getattr(module, name)

    def timed(*args, **kwargs):
        c, t = time.process_time(), time.perf_counter()
        try:
            return inner(*args, **kwargs)
        finally:
            wall[key] = wall.get(key, 0.0) + time.perf_counter() - t
            cpu[key] = cpu.get(key, 0.0) + time.process_time() - c

    setattr(module, name, timed)


def split_air(case):
    """(the city's case, Air): a case name ending in ``_air`` is that case with Air 1 (sea-level clear air)."""
    return (case[:-len(AIR_SUFFIX)], 1.0) if case.endswith(AIR_SUFFIX) else (case, 0.0)


def worker(spec):
    """Time one (engine, method, case): no fog (first, warm), apply, fog (first, warm), the compositor muted."""
    sys.path[:0] = [str(ROOT), str(ROOT / "benchmarks")]
    import bpy
    import overhead as ov
    from fog_addon import sunsky
    from fog_addon.nodes import comp_fog, groups, surface_group
    from fog_addon.ops import apply
    from fog_addon.precompute.physics.daylight import daylight_tables
    from fog_addon.precompute.core.spec import FogSpec
    from fog_scenes import daylight as dl

    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    case, air = split_air(spec["case"])
    dl.build(scene, case, with_fog=False)
    cycles = spec["engine"] == "cycles"
    ov.cost_settings(scene, cycles, spec["resolution"], spec["samples"])
    bpy.app.handlers.render_stats.append(ov.BEAT)   # the first sample's time (fog_first_setup_s)
    tmp = pathlib.Path(os.environ.get("TMPDIR") or tempfile.gettempdir())
    tag = f"daylight_{spec['engine']}_{spec['method']}_{spec['case']}_{os.getpid()}"
    res = {}
    res["nofog_first_s"], res["nofog_first_cpu_s"] = ov._render(scene, "nofog_first")
    res["nofog_warm_s"], res["nofog_warm_cpu_s"], _ = ov._warm(scene, spec["repeats"], "nofog_warm")
    nofog = ov._save_render(scene, tmp / f"{tag}_nofog.exr")

    wall, cpu = {}, {}
    _wrap(daylight_tables, "bake_fog_light", "bake", wall, cpu)
    _wrap(sunsky, "probe_sky", "probe", wall, cpu)
    _wrap(comp_fog, "build_fog_group", "comp_group", wall, cpu)
    _wrap(surface_group, "build_surface", "surface_group", wall, cpu)
    f = dl.layer(case)
    fog = FogSpec(density=f["beta0"], albedo=(f["albedo"],) * 3, anisotropy=f["g"], method=spec["method"],
                  fog_top=f["h0"], height_falloff=f["H"], air=air)
    c, t = time.process_time(), time.perf_counter()
    notes = apply.apply(scene, fog)
    res["apply_s"], res["apply_cpu_s"] = time.perf_counter() - t, time.process_time() - c
    for key in ("bake", "probe", "comp_group", "surface_group"):
        res[f"{key}_s"], res[f"{key}_cpu_s"] = wall.get(key, 0.0), cpu.get(key, 0.0)
    # a wrapped function the add-on no longer calls through its module would time 0 s unseen (the bake is
    # skipped when the table cache holds the map)
    smoke.check(spec["method"] != "compositor" or {"probe", "comp_group", "surface_group"} <= set(wall),
                f"wrapped functions not called: {sorted({'probe', 'comp_group', 'surface_group'} - set(wall))}")
    res["choice"] = apply.method_line(apply.stored_choice() or {}) or ""
    res["notes"] = " | ".join(f"{a}: {b}" for a, b in notes)[:600]
    for key, name in (("comp", comp_fog.FOG_GROUP), ("surface", groups.SURFACE), ("world", groups.WORLD)):
        tree = bpy.data.node_groups.get(name)
        if tree is not None:
            res[f"{key}_nodes"], res[f"{key}_nodes_all"], n_groups = node_counts(tree)
            if key == "comp":
                res["comp_groups"] = n_groups
    res["images"] = len(bpy.data.images)
    scene.cycles.use_denoising = False
    res["fog_first_s"], res["fog_first_cpu_s"] = ov._render(scene, "fog_first")
    res["fog_first_setup_s"] = ov.BEAT.first_sample
    res.update(ov.picture_stats(nofog, ov._save_render(scene, tmp / f"{tag}_fog.exr")))
    res["fog_warm_s"], res["fog_warm_cpu_s"], res["repeats"] = ov._warm(scene, spec["repeats"], "fog_warm")
    tree = scene.compositing_node_group
    muted = [n for n in (tree.nodes if tree is not None else ())
             if getattr(n, "node_tree", None) is not None and n.node_tree.name == comp_fog.FOG_GROUP]
    if muted:
        for n in muted:
            n.mute = True
        res["nocomp_warm_s"], res["nocomp_warm_cpu_s"], _ = ov._warm(scene, spec["repeats"], "nocomp_warm")
        for n in muted:
            n.mute = False
    worker_result.emit(res)
    return 0


# ---------------------------------------------------------------- driver

def load_avg():
    try:
        return round(os.getloadavg()[0], 2)
    except OSError:
        return ""


def source_id():
    sys.path.insert(0, str(ROOT / "benchmarks"))
    import overhead
    return overhead.source_id()


def ratios(row):
    for suffix, s in (("", "_s"), ("_cpu", "_cpu_s")):
        get = row.get
        if get("fog_warm" + s) and get("nofog_warm" + s):
            row["ratio_warm" + suffix] = get("fog_warm" + s) / get("nofog_warm" + s)
        if get("fog_first" + s) and get("nofog_first" + s):
            row["ratio_first_render" + suffix] = get("fog_first" + s) / get("nofog_first" + s)
            row["ratio_first" + suffix] = (get("apply" + s) + get("fog_first" + s)) / get("nofog_first" + s)
    if row.get("nocomp_warm_cpu_s") and row.get("fog_warm_cpu_s"):
        row["comp_share_cpu"] = (row["fog_warm_cpu_s"] - row["nocomp_warm_cpu_s"]) / row["fog_warm_cpu_s"]
    return row


def measure(engine, method, case, args):
    cycles = engine == "cycles"
    resolution = args.resolution if cycles else args.eevee_resolution
    samples = args.samples if cycles else args.eevee_samples
    spec = {"engine": engine, "method": method, "case": case, "resolution": resolution, "samples": samples,
            "repeats": args.repeats}
    load0, t = load_avg(), time.perf_counter()
    res = worker_result.run(__file__, spec)
    row = {"engine": engine, "method": method, "case": case, "status": "ok" if res is not None else "error"}
    row.update({k: v for k, v in (res or {}).items() if k in FIELDS})
    row.update(process_s=time.perf_counter() - t, load_avg_start=load0, load_avg_end=load_avg(),
               resolution="{}x{}".format(*resolution), samples=samples, source=args.source)
    return ratios(row)


def read_csv(path):
    return csv_rows.read(path, TEXT_FIELDS)


def chart(rows, path):
    """Left: fog / no fog (CPU) per case and run, warm (solid) and first render (hatched), the issue's 1.3x.
    Right: the warm fogged render's CPU seconds split: no fog, the rest of the fog, the compositor's group."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    cases = list(dict.fromkeys(r["case"] for r in rows))
    runs = list(dict.fromkeys((r["engine"], r["method"]) for r in rows))
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(13, 5))
    x = np.arange(len(cases))
    width = 0.8 / (2 * len(runs))
    for i, run in enumerate(runs):
        get = {r["case"]: r for r in rows if (r["engine"], r["method"]) == run}
        res = next(iter(get.values())).get("resolution", "")
        for j, (key, hatch, what) in enumerate((("ratio_warm_cpu", None, "warm"),
                                                ("ratio_first_render_cpu", "//", "first"))):
            ys = [get[c].get(key) if isinstance(get.get(c, {}).get(key), float) else np.nan for c in cases]
            ax.bar(x + (2 * i + j - len(runs) + 0.5) * width, ys, width, color=f"C{i}", hatch=hatch,
                   alpha=0.9 if j == 0 else 0.55, edgecolor="black", lw=0.5,
                   label=f"{run[0].capitalize()} {res}, {run[1]}: {what}")
    ax.axhline(1.0, color="grey", lw=0.8)
    ax.axhline(GOAL, color="black", ls="--", lw=1.0, label=f"issue 29's goal (Cycles): {GOAL}x")
    ax.set_xticks(x)
    ax.set_xticklabels(cases, fontsize=8)
    ax.set_ylabel("CPU time with fog / without fog")
    ax.legend(fontsize=7)
    ax.grid(True, axis="y", alpha=0.3)
    labels = []
    for i, run in enumerate(runs):
        for k, c in enumerate(cases):
            r = next((r for r in rows if (r["engine"], r["method"]) == run and r["case"] == c), None)
            if r is None or not isinstance(r.get("fog_warm_cpu_s"), float):
                continue
            pos = len(labels)
            labels.append(f"{run[0][:1].upper()} {run[1][:4]} {c.replace('_inside', '')}")
            nofog = r["nofog_warm_cpu_s"]
            rest = (r["nocomp_warm_cpu_s"] if isinstance(r.get("nocomp_warm_cpu_s"), float)
                    else r["fog_warm_cpu_s"]) - nofog
            comp = r["fog_warm_cpu_s"] - nofog - rest
            bx.bar(pos, nofog, color="0.75", label="no fog" if pos == 0 else None)
            bx.bar(pos, rest, bottom=nofog, color="C2", label="fog: materials, AOVs, set-up" if pos == 0 else None)
            bx.bar(pos, comp, bottom=nofog + rest, color="C3",
                   label="fog: the compositor's group" if pos == 0 else None)
    bx.set_xticks(range(len(labels)))
    bx.set_xticklabels(labels, rotation=60, ha="right", fontsize=7)
    bx.set_ylabel("warm render, CPU s (all threads)")
    bx.legend(fontsize=7)
    bx.grid(True, axis="y", alpha=0.3)
    src = ", ".join(dict.fromkeys(str(r.get("source", "")) for r in rows))
    fig.suptitle(f"Cost of the daylight fog: the city (fog_scenes/daylight.py), camera inside, code {src} "
                 f"(benchmarks/daylight_cost.py)", fontsize=9)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def fmt(v, spec=".3g"):
    return format(v, spec) if isinstance(v, float) else ("-" if v in (None, "") else str(v))


def print_table(rows):
    print(f"\n{'engine':6} {'method':10} {'case':20} {'nofog1':>7} {'nofogw':>7} {'fog1':>7} {'fogw':>7} "
          f"{'1st':>6} {'warm':>6} {'1st+ap':>6} {'apply':>6} {'bake':>6} {'nocomp':>7} {'comp%':>6} "
          f"{'nodes':>6} pic   (CPU s)")
    for r in rows:
        share = r.get("comp_share_cpu")
        print(f"{r['engine']:6} {r['method']:10} {r['case']:20} {fmt(r.get('nofog_first_cpu_s')):>7} "
              f"{fmt(r.get('nofog_warm_cpu_s')):>7} {fmt(r.get('fog_first_cpu_s')):>7} "
              f"{fmt(r.get('fog_warm_cpu_s')):>7} {fmt(r.get('ratio_first_render_cpu')):>6} "
              f"{fmt(r.get('ratio_warm_cpu')):>6} {fmt(r.get('ratio_first_cpu')):>6} "
              f"{fmt(r.get('apply_cpu_s')):>6} {fmt(r.get('bake_cpu_s')):>6} {fmt(r.get('nocomp_warm_cpu_s')):>7} "
              f"{fmt(100 * share if isinstance(share, float) else None):>6} {fmt(r.get('comp_nodes_all')):>6} "
              f"{r.get('picture_check', '-')}")


def main(argv=None):
    ap = cost_cli.parser(__doc__, SAMPLES, RESOLUTION, EEVEE_RESOLUTION, REPEATS, CSV, PNG)
    ap.add_argument("--cases", default=",".join(CASES))
    ap.add_argument("--runs", default=",".join(RUNS), help="engine:method, comma-separated")
    ap.add_argument("--eevee-samples", type=int, default=EEVEE_SAMPLES)
    args = ap.parse_args(argv)
    code = cost_cli.dispatch(args, worker, read_csv, chart, print_table, KEPT)
    if code is not None:
        return code
    args.source = source_id()
    os.environ.setdefault("TMPDIR", tempfile.mkdtemp(prefix="daylight_cost_"))
    print(f"code {args.source}, load {load_avg()}, {os.cpu_count()} CPUs", flush=True)
    kept = read_csv(args.out) if args.update and args.out.exists() else []
    order = lambda r: (list(RUNS).index(f"{r['engine']}:{r['method']}") if f"{r['engine']}:{r['method']}" in RUNS
                       else 99, list(CASES).index(r["case"]) if r["case"] in CASES else 99)
    rows = []
    for run in args.runs.split(","):
        engine, method = run.split(":")
        for case in args.cases.split(","):
            row = measure(engine, method, case, args)
            rows.append(row)
            print(f"{engine} {method} {case} {row['status']}: first {fmt(row.get('ratio_first_render_cpu'))}x CPU, "
                  f"warm {fmt(row.get('ratio_warm_cpu'))}x CPU ({fmt(row.get('ratio_warm'))}x wall), apply "
                  f"{fmt(row.get('apply_s'))} s (bake {fmt(row.get('bake_s'))}); compositor "
                  f"{fmt(row.get('comp_share_cpu'))} of the warm fog; load {row['load_avg_start']} -> "
                  f"{row['load_avg_end']}; {row.get('choice', '')[:100]}", flush=True)
            done = {(r["engine"], r["method"], r["case"]) for r in rows}
            out = [r for r in kept if (r["engine"], r["method"], r["case"]) not in done] + rows
            csv_rows.write(args.out, sorted(out, key=order), FIELDS, digits=4)
    rows = read_csv(args.out)
    chart(rows, args.chart)
    print_table(rows)
    print(f"\nwrote {args.out}, {args.chart}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
