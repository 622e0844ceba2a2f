"""What-if for adding the fog to many materials with many lights: wrap the materials before or after the big groups.

    .venv/bin/python benchmarks/apply_order.py [--materials 1000] [--lights 64]

benchmarks/materials_1000.py found that wrapping 1 000 materials costs far
more when the Surface group they instance is big (64 lights) than when it is
small (4 lights).  This times the two orders of the same work, each in a fresh
process (the scene of materials_1000.py: N cubes with their own Principled
material, L point lights):

* A: build the scene groups for the L lights (``build.build_scene_groups``), then wrap every material
  (``wrap_material``);
* B: build the groups with no light (small), wrap every material, then build
  the groups for the L lights (built beside the old ones, the 1 000 users
  moved over with one ``user_remap``: ``groups.new_group``/``install``).

Both end with every material fogged against the same groups.  Wall and CPU
time of each step; ``apply.apply`` takes order B (its Surface group is
first built without lights).  Output: benchmarks/out/apply_order.csv.
Smoke mode (``FOG_BENCH_SMOKE=1``, benchmarks/smoke.py): 4 materials, 2 lights.
"""
import argparse
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


def load_avg():
    try:
        return round(os.getloadavg()[0], 2)
    except OSError:
        return ""


def worker(order, n, n_lights):
    sys.path.insert(0, str(ROOT))   # a script run by path: the repository root (materials_1000 is beside it)
    import bpy
    import materials_1000 as mb
    from fog_addon.nodes import groups, owned
    from fog_addon.nodes.material import wrap_material
    from fog_addon import methods
    from fog_addon.ops import build, plan
    from fog_addon.precompute.core.spec import FogSpec
    from fog_addon.props import store_spec

    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    mb.build(scene, n, n_lights)
    spec = FogSpec(density=mb.DENSITY, method="nodes").validated()
    store_spec(scene, spec)
    lights, _ = plan.fog_lights(scene)
    groups.set_params(spec.beta_per_unit, spec.albedo, spec.anisotropy)
    mats = plan.scene_materials(scene)
    nodes = methods.get("nodes")

    def scene_groups(lights):
        return build.build_scene_groups(scene, spec, lights, nodes)

    steps = ([("groups, all lights (no users)", lambda: scene_groups(lights)),
              ("wrap materials (Surface group for all lights)", lambda: [wrap_material(m) for m in mats])]
             if order == "A" else
             [("groups, no light (no users)", lambda: scene_groups([])),
              ("wrap materials (Surface group for no light)", lambda: [wrap_material(m) for m in mats]),
              ("groups, all lights (built beside, users remapped)", lambda: scene_groups(lights))])
    for label, fn in steps:
        c, t = time.process_time(), time.perf_counter()
        fn()
        print("APPLY_ORDER " + json.dumps({"order": order, "step": label, "seconds": time.perf_counter() - t,
                                           "cpu_seconds": time.process_time() - c, "load_avg": load_avg()}),
              flush=True)
    fogged = sum(1 for m in mats if owned.is_fogged(m))
    print("APPLY_ORDER " + json.dumps({"order": order, "step": "fogged", "fogged": fogged}), flush=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--materials", type=int, default=smoke.pick(1000, 4))
    ap.add_argument("--lights", type=int, default=smoke.pick(64, 2))
    ap.add_argument("--worker", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.worker:
        worker(args.worker, args.materials, args.lights)
        return 0
    python = os.environ.get("FOG_PYTHON") or str(ROOT / ".venv" / "bin" / "python")
    rows = []
    for order in ("A", "B"):
        proc = subprocess.run([python, __file__, "--worker", order, "--materials", str(args.materials),
                               "--lights", str(args.lights)], capture_output=True, text=True)
        smoke.echo(proc.stdout, proc.stderr)
        if proc.returncode:
            raise RuntimeError(f"order {order} failed (exit {proc.returncode}):\n{proc.stderr[-3000:]}")
        got = [json.loads(ln.split(" ", 1)[1]) for ln in proc.stdout.splitlines() if ln.startswith("APPLY_ORDER ")]
        fogged = next(g["fogged"] for g in got if g["step"] == "fogged")
        smoke.check(fogged == args.materials, f"order {order}: {fogged} of {args.materials} materials fogged")
        for g in got:
            if g["step"] == "fogged":
                continue
            row = {"order": order, "step": g["step"], "seconds": round(g["seconds"], 3),
                   "cpu_seconds": round(g["cpu_seconds"], 3), "materials": args.materials, "lights": args.lights,
                   "fogged": fogged, "load_avg": g["load_avg"]}
            rows.append(row)
            print(f"{order}  {g['step']:52s} {g['seconds']:7.2f} s wall {g['cpu_seconds']:7.2f} s cpu  "
                  f"(load {g['load_avg']})", flush=True)
        total = sum(r["cpu_seconds"] for r in rows if r["order"] == order)
        rows.append({"order": order, "step": "total", "seconds": round(sum(r["seconds"] for r in rows
                                                                          if r["order"] == order), 3),
                     "cpu_seconds": round(total, 3), "materials": args.materials, "lights": args.lights,
                     "fogged": fogged, "load_avg": load_avg()})
        print(f"{order}  {'total':52s} {'':16s} {total:7.2f} s cpu, {fogged} materials fogged", flush=True)
    csv_rows.write(OUT / "apply_order.csv", rows)
    print(f"wrote {OUT / 'apply_order.csv'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
