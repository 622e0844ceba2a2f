"""What the fog costs as lights multiply: render time with fog over render time without, same scene, same process.

    .venv/bin/python benchmarks/overhead.py [--budget S] [--lights 1,4,16,64,256] [--methods ...]
                                            [--no-boulevard] [--no-materials] [--repeats N]

Scenes: tests/scenes/many_lights.py (a ground plane, matte, glossy and metallic
spheres, N point lights on a grid; here with the lights lighting the surfaces
as in any scene, fog beta = 0.1 1/m) for N in 1, 4, 16, 64, 256, and
demo_scenes/boulevard.py (45 lights, its default density).  Cycles CPU at
320x180, 16 spp (Blender's default filter and no denoiser; cast shadows on),
EEVEE 16 samples at the same size.

Each (scene, method) runs in ONE worker process (this script with ``--worker``):
build the scene, render it without fog (a first "cold" render, then warm ones),
add the fog (``apply_fog``, timed), render it with fog (first render, then warm
ones); EEVEE takes its no-fog warm render last, after removing the fog.  A "warm" time is the minimum of ``repeats`` renders (fewer once they
have taken ``REPEAT_BUDGET_S``); Persistent Data stays off, as for a still
render, so every Cycles render syncs (and compiles) its shaders again.

* ``ratio_warm`` = fog warm / no-fog warm: the price per frame;
* ``ratio_first`` = fog first / no-fog first: what an artist waits for the
  first picture (shader compilation included).  EEVEE's shader compilation is
  most of its cost: its first render is the figure to read (one warm render
  each, as EEVEE caches compiled shaders).  Here (llvmpipe) EEVEE's second
  render of a scene took longer than its first, with and without fog alike
  (1 light: 3.5 s then 10.5 s): compare first with first, warm with warm.
* ``status``: ok; ``partial`` (killed by the budget during the warm renders
  with fog: the first-render ratio stands); ``timeout`` (killed before the
  first render with fog finished); ``not run``; ``error``.

Each worker has a time budget (``--budget``, default 90 s): when it runs out
the worker is killed and the case recorded with whatever it measured (if
the first render with fog had not finished, ``fog_first_s`` is a lower bound:
the time it had run).  Once a method times out, its cases with more lights are recorded
``not run`` (they would only take longer).  The worker's log (stdout +
stderr) is scanned (tests/render_harness.py ``log_errors``): shaders too big for
Cycles' SVM stack or EEVEE's uniform block, GPU shader errors -- a fast
render of black materials is no success; such rows get ``picture_ok`` False.

Also: adding the fog to 1 000 materials (1 000 cubes, each its own
Principled material) with 64 lights, timed (``apply_fog``: tables, groups,
materials), with its own budget.

Outputs: benchmarks/out/overhead.csv and docs/figures/overhead.png (ratio vs
number of lights, log-log, one line per method/engine, the issue's goals
drawn: 1 light <= 1.5x, 16 lights <= 2x, 64 lights <= 3x).
"""
import argparse
import csv
import json
import os
import pathlib
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))

OUT = ROOT / "benchmarks" / "out"
CSV = OUT / "overhead.csv"
PNG = ROOT / "docs" / "figures" / "overhead.png"

LIGHTS = (1, 4, 16, 64, 256)
BOULEVARD_LIGHTS = 45
# name: (engine, method preference); the order of the table and the chart
METHODS = {"cycles_nodes": ("CYCLES", "nodes"), "cycles_osl": ("CYCLES", "osl"), "eevee": ("BLENDER_EEVEE", "nodes")}
RESOLUTION = (320, 180)
SAMPLES = 16
DENSITY = 0.1                  # 1/m for the many-lights scenes (the boulevard uses its own default)
BUDGET_S = 90.0                # per worker
MATERIALS_BUDGET_S = 180.0
REPEATS = 3
REPEAT_BUDGET_S = 12.0         # no more warm repeats once they have taken this long
GOALS = ((1, 1.5), (16, 2.0), (64, 3.0))   # the issue's: (lights, max fog / no fog)
FIELDS = ["case", "lights", "method", "engine", "status", "picture_ok", "log_errors", "nofog_first_s",
          "nofog_warm_s", "fog_apply_s", "fog_first_s", "fog_warm_s", "ratio_warm", "ratio_first",
          "repeats", "budget_s", "process_s", "load_avg", "resolution", "samples", "note"]



def load_avg():
    try:
        return round(os.getloadavg()[0], 2)
    except OSError:
        return ""


# ---------------------------------------------------------------- workers (inside bpy)

def _emit(result):
    print("OVERHEAD_JSON " + json.dumps(result), flush=True)


def _render(scene):
    import bpy
    t = time.perf_counter()
    bpy.ops.render.render(write_still=False, scene=scene.name)
    return time.perf_counter() - t


def _warm(scene, repeats):
    times = []
    while len(times) < repeats and (not times or sum(times) < REPEAT_BUDGET_S):
        times.append(_render(scene))
    return min(times), len(times)


def worker(spec):
    """Time one (scene, method): no fog (first, warm), apply, fog (first, warm); print results as they come."""
    import bpy
    from fog_addon import measure
    from fog_addon.ops import apply

    engine, method = METHODS[spec["method"]]
    if spec["case"] == "boulevard":
        from demo_scenes import boulevard
        bpy.ops.wm.read_factory_settings(use_empty=True)
        scene = bpy.context.scene
        boulevard.build(scene)
        density = boulevard.DEFAULT_DENSITY
    else:
        sys.path.insert(0, str(ROOT / "tests" / "scenes"))
        import many_lights
        scene, _ = many_lights.build_scene(spec["lights"], direct_light=True)
        density = DENSITY
    scene.render.engine = engine
    measure.set_resolution(scene, *RESOLUTION)
    measure.set_samples(scene, SAMPLES)
    measure.set_cycles_cpu(scene)
    scene.cycles.use_denoising = False
    if engine == "BLENDER_EEVEE":
        scene.eevee.light_threshold = min(scene.eevee.light_threshold, 1e-4)
    res = {"lights": len([o for o in scene.objects if o.type == "LIGHT"])}
    res["nofog_first_s"] = _render(scene)
    _emit(res)
    cycles = engine == "CYCLES"
    repeats = spec["repeats"] if cycles else 1   # EEVEE renders are slow here (software GL)
    if cycles:
        res["nofog_warm_s"], _ = _warm(scene, repeats)
        _emit(res)
    t = time.perf_counter()
    apply.apply_fog(scene, density, method=method)
    scene.cycles.use_denoising = False
    res["fog_apply_s"] = time.perf_counter() - t
    res["fog_started"] = time.time()
    _emit(res)
    res["fog_first_s"] = _render(scene)
    res.pop("fog_started")
    _emit(res)
    res["fog_warm_s"], res["repeats"] = _warm(scene, repeats)
    _emit(res)
    if not cycles:   # EEVEE: the no-fog warm render last (the first-render ratio comes first within the budget)
        apply.remove_fog(scene)
        res["nofog_warm_s"], _ = _warm(scene, repeats)
        _emit(res)
    return 0


def materials_worker(spec):
    """Add the fog to ``spec["materials"]`` materials (one cube each) lit by 64 lights; time it."""
    import bpy
    import bmesh
    from fog_addon.ops import apply
    sys.path.insert(0, str(ROOT / "tests" / "scenes"))
    import many_lights

    n, n_lights = spec["materials"], spec["lights"]
    scene, _ = many_lights.build_scene(n_lights, direct_light=True)
    bm = bmesh.new()
    bmesh.ops.create_cube(bm, size=0.2)
    base = bpy.data.meshes.new("Cube")
    bm.to_mesh(base)
    bm.free()
    side = int(n ** 0.5 + 0.999)
    for i in range(n):
        mat = bpy.data.materials.new(f"Material {i:04d}")
        bsdf = mat.node_tree.nodes["Principled BSDF"]
        bsdf.inputs["Base Color"].default_value = ((i % 7) / 7, (i % 11) / 11, (i % 13) / 13, 1.0)
        bsdf.inputs["Roughness"].default_value = (i % 10) / 10
        bsdf.inputs["Metallic"].default_value = (i % 3) / 2
        mesh = base.copy()
        mesh.materials.append(mat)
        ob = bpy.data.objects.new(f"Cube {i:04d}", mesh)
        ob.location = (-5 + (i % side) * 0.3, 3 + (i // side) * 0.3, 0.1)
        scene.collection.objects.link(ob)
    res = {"lights": n_lights, "materials": len(bpy.data.materials)}
    _emit(res)
    t = time.perf_counter()
    apply.apply_fog(scene, DENSITY)
    res["fog_apply_s"] = time.perf_counter() - t
    _emit(res)
    t = time.perf_counter()
    apply.apply_fog(scene, DENSITY)
    res["fog_apply_again_s"] = time.perf_counter() - t
    _emit(res)
    return 0


# ---------------------------------------------------------------- driver

def log_errors(text):
    import render_harness as h
    return h.log_errors(text)


def run_worker(spec, budget):
    """Run a worker with a hard time limit; (last result dict, log text, timed out?, wall seconds)."""
    import render_harness as h
    env = h._env()
    env["PYTHONUNBUFFERED"] = "1"
    cmd = [h.PYTHON, str(pathlib.Path(__file__).resolve()), "--worker", json.dumps(spec)]
    t = time.perf_counter()
    try:
        proc = subprocess.run(cmd, cwd=str(ROOT), env=env, capture_output=True, text=True, timeout=budget)
        out, err, timed_out, rc = proc.stdout, proc.stderr, False, proc.returncode
    except subprocess.TimeoutExpired as exc:
        dec = (lambda b: b.decode(errors="replace") if isinstance(b, bytes) else (b or ""))
        out, err, timed_out, rc = dec(exc.stdout), dec(exc.stderr), True, None
    wall = time.perf_counter() - t
    lines = [ln for ln in out.splitlines() if ln.startswith("OVERHEAD_JSON ")]
    res = json.loads(lines[-1].split(" ", 1)[1]) if lines else {}
    if rc not in (0, None):
        res["error"] = f"exit {rc}: " + " | ".join((err.strip() or out.strip()).splitlines()[-3:])
    return res, out + "\n" + err, timed_out, wall


def measure_case(case, n, method, budget, repeats):
    engine, _ = METHODS[method]
    spec = {"case": case, "lights": n, "method": method, "repeats": repeats}
    res, log, timed_out, wall = run_worker(spec, budget)
    errors = log_errors(log)
    row = {"case": case, "lights": res.get("lights", n), "method": method, "engine": engine,
           "budget_s": budget, "process_s": wall, "load_avg": load_avg(),
           "resolution": "{}x{}".format(*RESOLUTION), "samples": SAMPLES, "log_errors": len(errors),
           "picture_ok": False if errors else ("" if timed_out and "fog_first_s" not in res else True)}
    for k in ("nofog_first_s", "nofog_warm_s", "fog_apply_s", "fog_first_s", "fog_warm_s", "repeats"):
        if k in res:
            row[k] = res[k]
    notes = []
    if timed_out and "fog_first_s" in res:
        row["status"] = "partial"   # the first render with fog finished; warm renders cut by the budget
        notes.append("killed during the warm renders with fog")
    elif timed_out:
        row["status"] = "timeout"
        if "fog_started" in res:   # killed during the first render with fog: it took at least this long
            row["fog_first_s"] = max(0.0, time.time() - res["fog_started"])
            notes.append(f"first render with fog still running at the budget: > {row['fog_first_s']:.0f} s")
        else:
            notes.append("killed before the fog was added")
    elif "error" in res:
        row["status"] = "error"
        notes.append(res["error"])
    else:
        row["status"] = "ok"
    if "fog_warm_s" in row and "nofog_warm_s" in row:
        row["ratio_warm"] = row["fog_warm_s"] / row["nofog_warm_s"]
    if "fog_first_s" in row and "nofog_first_s" in row:
        row["ratio_first"] = row["fog_first_s"] / row["nofog_first_s"]
    if errors:
        notes.append(f"{len(errors)} log errors, e.g. {errors[0][:120]!r}: the picture is wrong")
    row["note"] = "; ".join(notes)
    return row


def measure_materials(n, n_lights, budget):
    spec = {"case": "materials", "materials": n, "lights": n_lights}
    res, log, timed_out, wall = run_worker(spec, budget)
    note = f"{n} materials, {n_lights} lights: apply_fog first (tables baked); again (fog on): " + (
        f"{res['fog_apply_again_s']:.2f} s" if "fog_apply_again_s" in res else "-")
    row = {"case": f"materials_{n}", "lights": n_lights, "method": "cycles_nodes", "engine": "-",
           "status": "timeout" if timed_out else ("error" if "error" in res else "ok"),
           "fog_apply_s": res.get("fog_apply_s", ""), "budget_s": budget, "process_s": wall,
           "load_avg": load_avg(), "log_errors": len(log_errors(log)), "note": note + (
               f"; {res['error']}" if "error" in res else "")}
    return row


def write_csv(rows):
    CSV.parent.mkdir(parents=True, exist_ok=True)
    with open(CSV, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=FIELDS)
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.4g}" if isinstance(v, float) else v) for k, v in r.items()})


def read_csv():
    with open(CSV) as f:
        rows = list(csv.DictReader(f))
    for r in rows:
        for k, v in r.items():
            try:
                r[k] = float(v) if k not in ("case", "method", "engine", "status", "note", "resolution",
                                            "picture_ok") else v
            except ValueError:
                pass
        r["picture_ok"] = {"True": True, "False": False}.get(r["picture_ok"])
    return rows


def chart(rows):
    """Ratio (fog / no fog) vs lights, log-log: per method the warm ratio (solid) and the first-render
    ratio (dashed), through the cases measured.  Crosses: the picture is wrong (shaders too big, black
    materials): that time is not the fog's.  Open markers with an arrow: timeouts (the ratio is at
    least this).  The boulevard (45 lights) is a star.  Black squares: the issue's goals."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(9, 6))
    labels = {"cycles_nodes": "Cycles, node groups", "cycles_osl": "Cycles, OSL", "eevee": "EEVEE, node groups"}

    def point(x, y, r, colour, big):
        ms = 12 if big else 7
        if r["status"] == "timeout":
            ax.plot([x], [y], "*" if big else "o", mfc="none", mec=colour, ms=ms, mew=1.2)
            ax.annotate("", (x, y * 1.8), (x, y), arrowprops=dict(arrowstyle="->", color=colour))
        elif r["picture_ok"] is False:
            ax.plot([x], [y], "X" if big else "x", color=colour, ms=ms + 2, mew=2)
        else:
            ax.plot([x], [y], "*" if big else "o", color=colour, ms=ms)

    for i, method in enumerate(METHODS):
        colour = f"C{i}"
        for key, ls, what in (("ratio_warm", "-", "warm render"), ("ratio_first", "--", "first render")):
            mine = [r for r in rows if r["method"] == method and isinstance(r.get(key), float)]
            done = sorted((r for r in mine if r["case"] == "lights" and r["status"] in ("ok", "partial")),
                          key=lambda r: r["lights"])
            if done:
                ax.plot([r["lights"] for r in done], [r[key] for r in done], ls, color=colour, lw=1.2,
                        label=f"{labels[method]}: {what}")
            for r in mine:
                point(r["lights"], r[key], r, colour, r["case"] == "boulevard")
    gx, gy = zip(*GOALS)
    ax.plot(gx, gy, "s-", color="black", ms=7, lw=2, alpha=0.6, label="issue's goals: 1 light 1.5x, 16: 2x, 64: 3x")
    ax.plot([], [], "x", color="grey", ms=9, mew=2, ls="none",
            label="picture wrong (shader too big: black materials)")
    ax.plot([], [], "o", mfc="none", mec="grey", ms=7, ls="none", label="timeout: the ratio is at least this")
    ax.plot([], [], "*", color="grey", ms=12, ls="none", label=f"boulevard ({BOULEVARD_LIGHTS} lights)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xticks(list(LIGHTS) + [BOULEVARD_LIGHTS])
    ax.set_xticklabels([str(n) for n in LIGHTS] + [str(BOULEVARD_LIGHTS)])
    ax.set_xlabel("point lights")
    ax.set_ylabel("render time with fog / without fog")
    ax.set_title(f"Cost of the fog, {RESOLUTION[0]}x{RESOLUTION[1]}, {SAMPLES} spp, Cycles CPU (2 cores) / EEVEE "
                 "(benchmarks/overhead.py)", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="upper left")
    PNG.parent.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    fig.savefig(PNG, dpi=130)
    plt.close(fig)


def fmt(v, unit=""):
    return f"{v:.3g}{unit}" if isinstance(v, float) else (str(v) if v not in (None, "") else "-")


def print_table(rows):
    print(f"\n{'case':10} {'lights':>6} {'method':13} {'status':8} {'pic':4} {'nofog s':>8} {'apply s':>8} "
          f"{'fog 1st s':>9} {'fog warm s':>10} {'ratio warm':>10} {'ratio 1st':>9}")
    for r in rows:
        print(f"{r['case']:10} {int(r['lights']):6d} {r['method']:13} {r['status']:8} "
              f"{ {True: 'ok', False: 'BAD'}.get(r.get('picture_ok'), '?'):4} {fmt(r.get('nofog_warm_s', r.get('nofog_first_s'))):>8} "
              f"{fmt(r.get('fog_apply_s')):>8} {fmt(r.get('fog_first_s')):>9} {fmt(r.get('fog_warm_s')):>10} "
              f"{fmt(r.get('ratio_warm')):>10} {fmt(r.get('ratio_first')):>9}  {r.get('note', '')[:90]}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--budget", type=float, default=BUDGET_S, help="seconds per (scene, method) worker")
    ap.add_argument("--lights", default=",".join(map(str, LIGHTS)))
    ap.add_argument("--methods", default=",".join(METHODS))
    ap.add_argument("--repeats", type=int, default=REPEATS)
    ap.add_argument("--no-boulevard", action="store_true")
    ap.add_argument("--no-materials", action="store_true")
    ap.add_argument("--materials", type=int, default=1000)
    ap.add_argument("--chart-only", action="store_true", help="redraw the chart from the CSV")
    ap.add_argument("--worker", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.worker:
        spec = json.loads(args.worker)
        return materials_worker(spec) if spec["case"] == "materials" else worker(spec)
    if args.chart_only:
        rows = read_csv()
        chart(rows)
        print_table(rows)
        return 0
    os.environ.setdefault("TMPDIR", tempfile.mkdtemp(prefix="overhead_"))
    t0 = time.perf_counter()
    lights = sorted(int(x) for x in args.lights.split(","))
    cases = [("lights", n) for n in lights]
    if not args.no_boulevard:
        cases.append(("boulevard", BOULEVARD_LIGHTS))
        cases.sort(key=lambda c: c[1])
    rows = []
    for method in args.methods.split(","):
        stopped_at = None
        for case, n in cases:
            if stopped_at is not None:
                rows.append({"case": case, "lights": n, "method": method, "engine": METHODS[method][0],
                             "status": "not run", "budget_s": args.budget,
                             "note": f"timed out with {stopped_at} lights already"})
                print(f"{case:10} {n:4d} {method:13} not run (timed out at {stopped_at} lights)", flush=True)
                continue
            row = measure_case(case, n, method, args.budget, args.repeats)
            rows.append(row)
            print(f"{case:10} {n:4d} {method:13} {row['status']:8} {row['process_s']:6.1f} s  "
                  f"warm {fmt(row.get('ratio_warm'), 'x')}  first {fmt(row.get('ratio_first'), 'x')}  "
                  f"{row['note'][:100]}  (load {load_avg()})", flush=True)
            if row["status"] == "timeout":
                stopped_at = n
        write_csv(rows)
    if not args.no_materials:
        row = measure_materials(args.materials, 64, MATERIALS_BUDGET_S)
        rows.append(row)
        print(f"{row['case']}: {row['status']} apply_fog {fmt(row['fog_apply_s'], ' s')}  {row['note']}", flush=True)
    write_csv(rows)
    chart(rows)
    print_table(rows)
    print(f"\nwrote {CSV.relative_to(ROOT)}, {PNG.relative_to(ROOT)} in {time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
