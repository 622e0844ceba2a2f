"""What area lights' fog costs (issue 28, item 3): the render with the fog over the same render without it, one
process, for the hall of shafts_cost.py with its N lamps as point lights and as 1 m square area lights facing
down (same positions and power), warm renders.

    .venv/bin/python benchmarks/area_cost.py [--lights 4,16] [--methods compositor,nodes] [--repeats 2]

Cycles CPU, 640x360, 32 spp, fog of density 0.15/m, g 0.85, albedo 0.9, shafts off.  Writes
benchmarks/out/area_cost.csv and .png.  Figures: docs/measurements/2026-11-27-area-lights.md.
Smoke mode (``FOG_BENCH_SMOKE=1``, benchmarks/smoke.py): 1 lamp, 8x4 px, 1 spp, one warm render.
"""
import argparse
import json
import pathlib
import sys
import time

import csv_rows
import smoke
import worker_result

ROOT = pathlib.Path(__file__).resolve().parents[1]
OUT = smoke.out(ROOT / "benchmarks" / "out")
SIZE = smoke.pick((640, 360, 32), (8, 4, 1))   # width, height, samples
DENSITY, G, ALBEDO = 0.15, 0.85, 0.9
AREA_SIZE_M = 1.0


def worker(spec):
    sys.path[:0] = [str(ROOT), str(ROOT / "benchmarks"), str(ROOT / "tests")]
    import bpy
    from shafts_cost import hall
    from cycles_timing import cycles_cpu
    from fog_addon.ops import apply
    from fog_addon.precompute.core.spec import FogSpec
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = hall(bpy.context.scene, spec["lights"])
    if spec["kind"] == "area":
        for obj in scene.objects:
            if obj.type == "LIGHT":
                obj.data.type = "AREA"
                obj.data.shape = "SQUARE"
                obj.data.size = AREA_SIZE_M
    cycles_cpu(scene, *SIZE)

    def warm_render():
        bpy.ops.render.render()   # first: shader compilation, compositor set-up
        best = None
        for _ in range(spec["repeats"]):
            c = time.process_time()
            bpy.ops.render.render()
            best = min(best or 1e300, time.process_time() - c)
        return best

    res = {"kind": spec["kind"], "lights": spec["lights"], "method": spec["method"], "clear_cpu_s": warm_render()}
    t = time.perf_counter()
    apply.apply(scene, FogSpec(density=DENSITY, anisotropy=G, albedo=(ALBEDO,) * 3, method=spec["method"],
                               shafts=False))
    res["apply_s"] = time.perf_counter() - t
    res["fog_cpu_s"] = warm_render()
    res["ratio_cpu"] = res["fog_cpu_s"] / res["clear_cpu_s"]
    worker_result.emit(res)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--lights", default=smoke.pick("4,16", "1"))
    ap.add_argument("--methods", default=smoke.pick("compositor,nodes", "compositor"))
    ap.add_argument("--repeats", type=int, default=smoke.pick(2, 1))
    ap.add_argument("--worker")
    args = ap.parse_args()
    if args.worker:
        worker(json.loads(args.worker))
        return
    rows = []
    for method in args.methods.split(","):
        for n in (int(x) for x in args.lights.split(",")):
            for kind in ("point", "area"):
                row = worker_result.run(__file__, {"lights": n, "method": method, "kind": kind,
                                                   "repeats": args.repeats})
                if row is not None:
                    rows.append(row)
                    print(row, flush=True)
    csv_rows.write(OUT / "area_cost.csv", rows, digits=4)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 4))
    for method in args.methods.split(","):
        for kind, style in (("point", "o--"), ("area", "s-")):
            pts = [(r["lights"], r["ratio_cpu"]) for r in rows if r["method"] == method and r["kind"] == kind]
            if pts:
                ax.plot(*zip(*pts), style, label=f"{method}, {kind} lights")
    ax.set_xscale("log")
    ax.set_xlabel("lights")
    ax.set_ylabel("render with fog / without (CPU)")
    ax.legend()
    fig.tight_layout()
    fig.savefig(OUT / "area_cost.png", dpi=90)


if __name__ == "__main__":
    main()
