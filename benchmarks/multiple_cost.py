"""What multiple scattering costs (issue 28, "Cost"): the render with Dense Fog on over the same render with it
off (single scattering), same scene, same method, same process, warm renders (the table baked and cached).

    .venv/bin/python benchmarks/multiple_cost.py [--lights 4,16] [--methods compositor,nodes] [--repeats 2]
                                                 [--kind point|spot|area]

The scene is shafts_cost.py's hall of columns (N point lamps on a grid), Cycles CPU, 640x360, 32 spp, fog of
density 0.15/m, g 0.85, albedo 0.9, shafts off (they are measured on their own); ``--kind spot``: the lamps are
spot lights pointing down (60 degrees, blend 0.15), ``area``: 0.5 m square area lights facing down (the
compositor gives both their multiply scattered light).  Writes benchmarks/out/multiple_cost.csv and .png
(multiple_cost_<kind>.* for the other kinds).  Figures: docs/measurements/2026-11-27-multiple-scattering.md.
Smoke mode (``FOG_BENCH_SMOKE=1``, benchmarks/smoke.py): 1 lamp, 8x4 px, 1 spp, one warm render.
"""
import argparse
import json
import pathlib
import sys

import csv_rows
import smoke
import worker_result

ROOT = pathlib.Path(__file__).resolve().parents[1]
OUT = smoke.out(ROOT / "benchmarks" / "out")
SIZE = smoke.pick((640, 360, 32), (8, 4, 1))   # width, height, samples
DENSITY, G, ALBEDO = 0.15, 0.85, 0.9


def worker(spec):
    sys.path[:0] = [str(ROOT), str(ROOT / "benchmarks"), str(ROOT / "tests")]
    import bpy
    from cycles_timing import cycles_cpu, timed_apply, warm
    from shafts_cost import hall
    from fog_addon.ops import apply
    from fog_addon.precompute.core.spec import FogSpec
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = hall(bpy.context.scene, spec["lights"])
    kind = spec.get("kind", "point")
    if kind != "point":
        import math
        for o in scene.objects:
            if o.type == "LIGHT":
                o.data.type = kind.upper()
                if kind == "spot":
                    o.data.spot_size, o.data.spot_blend = math.radians(60.0), 0.15
                else:
                    o.data.shape, o.data.size = "SQUARE", 0.5
    cycles_cpu(scene, *SIZE)

    res = {"lights": spec["lights"], "method": spec["method"], "kind": kind}
    for ms in (False, True):
        fog = FogSpec(density=DENSITY, anisotropy=G, albedo=(ALBEDO,) * 3, method=spec["method"], shafts=False,
                      multiple_scattering=ms)
        res[f"apply_{'ms' if ms else 'ss'}_s"] = timed_apply(scene, fog)
        key = "ms" if ms else "ss"
        res[f"{key}_s"], res[f"{key}_cpu_s"] = warm(spec["repeats"])
    apply.remove_fog(scene)
    res["ratio"] = res["ms_s"] / res["ss_s"]
    res["ratio_cpu"] = res["ms_cpu_s"] / res["ss_cpu_s"]
    worker_result.emit(res)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--lights", default=smoke.pick("4,16", "1"))
    ap.add_argument("--methods", default="compositor,nodes")
    ap.add_argument("--repeats", type=int, default=smoke.pick(2, 1))
    ap.add_argument("--kind", default="point", choices=("point", "spot", "area"))
    ap.add_argument("--worker")
    args = ap.parse_args()
    if args.worker:
        worker(json.loads(args.worker))
        return
    OUT.mkdir(parents=True, exist_ok=True)
    rows = []
    for method in args.methods.split(","):
        for n in (int(x) for x in args.lights.split(",")):
            row = worker_result.run(__file__, {"lights": n, "method": method, "repeats": args.repeats,
                                               "kind": args.kind})
            if row is not None:
                print(row, flush=True)
                rows.append(row)
    stem = "multiple_cost" if args.kind == "point" else f"multiple_cost_{args.kind}"
    csv_rows.write(OUT / f"{stem}.csv", rows)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 4))
    for method in args.methods.split(","):
        pts = [(r["lights"], r["ratio_cpu"]) for r in rows if r["method"] == method]
        ax.plot(*zip(*pts), "o-", label=method)
    ax.axhline(1.3, color="grey", ls="--", label="goal 1.3x")
    ax.set_xscale("log")
    ax.set_xlabel(f"{args.kind} lights")
    ax.set_ylabel("render with Dense Fog / without (CPU)")
    ax.legend()
    fig.tight_layout()
    fig.savefig(OUT / f"{stem}.png", dpi=90)


if __name__ == "__main__":
    main()
