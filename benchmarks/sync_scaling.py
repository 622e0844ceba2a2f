"""Why many lights cost so much in Cycles: its shader set-up grows with the square of a material's nodes.

    .venv/bin/python benchmarks/sync_scaling.py [--lights 1,4,9,16,25,36,64] [--materials 4,16,64]
                                                [--budget S] [--out CSV] [--chart PNG]
    .venv/bin/python benchmarks/sync_scaling.py --chart-only [--out CSV] [--chart PNG]

Every fogged material inlines one copy of a light's node group per fog light
(``nodes/light_groups.py``: about 450 nodes a light).  Before Cycles compiles a
material to SVM it simplifies the inlined graph, and its node deduplication
(``ShaderGraph::deduplicate_nodes``, intern/cycles/scene/shader_graph.cpp)
compares every node with every earlier node of the same type: a profile of
the first render of 25 lights (``perf``) spent 40 % of the process's CPU
time in that loop (``std::_Rb_tree_increment`` under ``deduplicate_nodes``,
``ShaderNode::equals``), and SVM compilation itself was 0.01 s a material.
So the set-up per material grows as (lights x nodes)^2, and with the
number of materials linearly.

Scene: fog_scenes/many_lights.py (ground, three spheres: 4 materials) with
N point lights lighting the surfaces, fog beta = 0.1 /m at Quality "exact"
(every light gets every term: the same group per light, a clean scaling
law); ``--materials`` adds small cubes with materials of their own at 16
lights.  Cycles CPU, one thread, 16x9 pixels, 1 spp: the render is all
set-up.  Each case runs in its own bpy process (``--worker``) with Cycles'
debug log on (fog_scenes/cycles_debug_log.py) and records:

* ``sync_s``: Cycles' "Total time spent synchronizing data" (wall) of the
  first render with fog (``nofog_sync_s`` without);
* ``render_cpu_s`` / ``nofog_render_cpu_s``: CPU time of the whole render
  call (``time.process_time``; Blender's own preparation included);
* ``svm_nodes``: SVM nodes of all shaders together (Cycles' compilation
  summaries), ``material_nodes``: shader nodes one fogged material inlines
  (its own, the Surface group's and one light group per light).

Outputs benchmarks/out/sync_scaling.csv and docs/figures/sync_scaling.png
(sync time against lights and against materials, log-log, with the fitted
exponent of sync time against lights over N >= 9).

Smoke mode (``FOG_BENCH_SMOKE=1``, benchmarks/smoke.py): 1 and 4 lights, 5 materials at 1 light, 4x2 px; a case not
"ok" fails the run.
"""
import argparse
import csv
import json
import os
import pathlib
import subprocess
import sys
import time

import csv_rows
import smoke

ROOT = pathlib.Path(__file__).resolve().parents[1]
OUT = smoke.out(ROOT / "benchmarks" / "out")
CSV = OUT / "sync_scaling.csv"
DATA = ROOT / "docs" / "measurements" / "data"   # the committed CSVs (benchmarks/out is not tracked)
PNG = smoke.out(ROOT / "docs" / "figures" / "sync_scaling.png")
BETA = 0.1
RESOLUTION = smoke.pick((16, 9), (4, 2))
MATERIAL_LIGHTS = smoke.pick(16, 1)   # the lights of the materials sweep
FIELDS = ["lights", "materials", "status", "sync_s", "nofog_sync_s", "render_cpu_s", "nofog_render_cpu_s",
          "apply_cpu_s", "svm_nodes", "material_nodes", "note"]
FIT_FROM = 9   # lights: the fit of sync time against lights uses N >= this


def worker(n_lights, n_materials, result):
    sys.path.insert(0, str(ROOT))   # a script run by path: the repository root
    import re

    import bpy
    from fog_scenes import cycles_debug_log, many_lights
    from fog_addon import measure
    from fog_addon.ops import apply

    scene, _ = many_lights.build_scene(n_lights, direct_light=True)
    for k in range(max(0, n_materials - len(many_lights.MATERIALS))):
        mat = bpy.data.materials.new(f"extra {k}")
        bsdf = mat.node_tree.nodes["Principled BSDF"]
        bsdf.inputs["Base Color"].default_value = (0.2 + 0.6 * (k % 7) / 6, 0.5, 0.3, 1.0)
        bsdf.inputs["Roughness"].default_value = 0.1 + 0.8 * (k % 5) / 4
        mesh = bpy.data.meshes.new(f"extra {k}")
        mesh.from_pydata([(0, 0, 0), (0.3, 0, 0), (0.3, 0.3, 0), (0, 0.3, 0)], [], [(0, 1, 2, 3)])
        mesh.materials.append(mat)
        ob = bpy.data.objects.new(f"extra {k}", mesh)
        ob.location = (-6.0 + 0.4 * (k % 30), 4.0 + 0.4 * (k // 30), 0.01)
        scene.collection.objects.link(ob)
    scene.render.engine = "CYCLES"
    measure.set_cycles_cpu(scene)
    scene.render.resolution_x, scene.render.resolution_y = RESOLUTION
    scene.render.resolution_percentage = 100
    scene.cycles.samples = 1
    scene.render.threads_mode = "FIXED"
    scene.render.threads = 1
    if not cycles_debug_log.enable():
        raise SystemExit("Cycles' debug log could not be turned on (needs nm and an unstripped bpy module)")
    log = pathlib.Path(result).with_suffix(".log")

    def render():
        # Cycles logs to the process's stdout/stderr: send both to a file for the span of the render
        sys.stdout.flush()
        with open(log, "w") as f:
            saved = [os.dup(1), os.dup(2)]
            os.dup2(f.fileno(), 1)
            os.dup2(f.fileno(), 2)
            try:
                t = time.process_time()
                bpy.ops.render.render(write_still=False)
                cpu = time.process_time() - t
            finally:
                for fd, old in zip((1, 2), saved):
                    os.dup2(old, fd)
                    os.close(old)
        text = log.read_text()
        sync = re.findall(r"Total time spent synchronizing data: ([0-9.eE+-]+)", text)
        svm = [int(x) for x in re.findall(r"Number of SVM nodes: (\d+)", text)]
        return cpu, float(sync[-1]) if sync else float("nan"), sum(svm)

    nofog_cpu, nofog_sync, _ = render()
    t = time.process_time()
    apply.apply_fog(scene, BETA, error="exact")
    apply_cpu = time.process_time() - t
    groups = bpy.data.node_groups
    light_nodes = sum(len(ng.nodes) for ng in groups if ng.name.startswith("AnalyticFog Light ["))
    material_nodes = len(bpy.data.materials["ground"].node_tree.nodes) + len(groups["AnalyticFog Surface"].nodes) \
        + n_lights * light_nodes
    cpu, sync, svm = render()
    pathlib.Path(result).write_text(json.dumps(dict(
        sync_s=sync, nofog_sync_s=nofog_sync, render_cpu_s=cpu, nofog_render_cpu_s=nofog_cpu,
        apply_cpu_s=apply_cpu, svm_nodes=svm, material_nodes=material_nodes)))


def run_case(n_lights, n_materials, budget, tmp):
    result = pathlib.Path(tmp) / f"case_{n_lights}_{n_materials}.json"
    row = dict(lights=n_lights, materials=n_materials)
    cmd = [sys.executable, __file__, "--worker", str(n_lights), str(n_materials), str(result)]
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=budget,
                              env=dict(os.environ, TMPDIR=str(tmp)))
    except subprocess.TimeoutExpired:
        return dict(row, status="timeout", note=f"over the {budget:.0f} s budget")
    smoke.echo(proc.stdout, proc.stderr)
    if proc.returncode or not result.exists():
        return dict(row, status="error", note=(proc.stderr or proc.stdout).strip().splitlines()[-1][:200])
    return dict(row, status="ok", **json.loads(result.read_text()))


def fit_exponent(rows):
    """Least-squares slope of log(sync) against log(lights) over the lights sweep's rows with N >= FIT_FROM."""
    import numpy as np
    pts = [(r["lights"], r["sync_s"]) for r in rows
           if r["status"] == "ok" and r["lights"] >= FIT_FROM and r["materials"] == 4]
    if len(pts) < 2:
        return None
    x, y = np.log([p[0] for p in pts]), np.log([p[1] for p in pts])
    return float(np.polyfit(x, y, 1)[0])


def chart(rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    ok = [r for r in rows if r["status"] == "ok"]
    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 4))
    sweep = sorted((r for r in ok if r["materials"] == 4), key=lambda r: r["lights"])
    a.loglog([r["lights"] for r in sweep], [r["sync_s"] for r in sweep], "o-", label="with fog")
    a.loglog([r["lights"] for r in sweep], [r["nofog_sync_s"] for r in sweep], "s--", label="without fog")
    k = fit_exponent(rows)
    a.set_title(f"4 materials: Cycles sync time ~ lights^{k:.2f}" if k else "4 materials")
    a.set_xlabel("point lights")
    a.set_ylabel("Cycles sync time per render, s")
    a.legend()
    a.grid(True, which="both", alpha=0.3)
    mats = sorted((r for r in ok if r["lights"] == MATERIAL_LIGHTS), key=lambda r: r["materials"])
    b.loglog([r["materials"] for r in mats], [r["sync_s"] for r in mats], "o-",
             label=f"with fog, {MATERIAL_LIGHTS} lights")
    b.loglog([r["materials"] for r in mats], [r["nofog_sync_s"] for r in mats], "s--", label="without fog")
    for ax in (a, b):
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    b.set_xlabel("materials")
    b.set_ylabel("Cycles sync time per render, s")
    b.set_title(f"{MATERIAL_LIGHTS} lights")
    b.legend()
    b.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--lights", default=smoke.pick("1,4,9,16,25,36,64", "1,4"))
    p.add_argument("--materials", default=smoke.pick("4,16,64", "5"),
                   help=f"material counts at {MATERIAL_LIGHTS} lights")
    p.add_argument("--budget", type=float, default=600.0, help="seconds per case")
    p.add_argument("--out", type=pathlib.Path, default=CSV)
    p.add_argument("--chart", type=pathlib.Path, default=PNG)
    p.add_argument("--chart-only", action="store_true", help="redraw the chart from the CSV")
    a = p.parse_args(argv)
    if a.chart_only:
        src = a.out if a.out.exists() or a.out != CSV else DATA / CSV.name   # else the committed CSV
        with open(src, newline="") as f:
            rows = [{k: (v if k in ("status", "note") else float(v) if v else float("nan")) for k, v in r.items()}
                    for r in csv.DictReader(f)]
        chart(rows, a.chart)
        return 0
    import tempfile
    cases = [(int(n), 4) for n in a.lights.split(",")]
    cases += [(MATERIAL_LIGHTS, int(m)) for m in a.materials.split(",") if (MATERIAL_LIGHTS, int(m)) not in cases]
    rows = []
    with tempfile.TemporaryDirectory(prefix="sync_scaling_") as tmp:
        for n, m in cases:
            row = run_case(n, m, a.budget, tmp)
            print(json.dumps(row), flush=True)
            smoke.check(row["status"] == "ok", f"{n} lights, {m} materials: {row['status']}: {row.get('note')}")
            rows.append(row)
    csv_rows.write(a.out, rows, FIELDS, digits=4)
    k = fit_exponent(rows)
    print(f"sync time ~ lights^{k:.2f} (N >= {FIT_FROM}, 4 materials)" if k else "too few cases to fit")
    chart(rows, a.chart)
    return 0


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "--worker":
        worker(int(sys.argv[2]), int(sys.argv[3]), sys.argv[4])
    else:
        sys.exit(main())
