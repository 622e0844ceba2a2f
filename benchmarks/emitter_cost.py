"""What glowing objects' glows cost (issue 28, item 3): the render with the fog (Compositor: the Emission pass blurred
by each rung of the ladder, and the flat emitters' dipole) over the same render without fog, and the same with the
dipole left out, same scene, same process, warm renders.

    .venv/bin/python benchmarks/emitter_cost.py [--signs 4,32] [--repeats 2]

The scene is shafts_cost.py's hall of columns with 4 point lamps and N glowing signs (1 x 0.4 m emissive planes,
strength 20, turned 30-70 degrees from the camera), Cycles CPU, 640x360, 32 spp, fog of density 0.15/m, g 0.85,
albedo 0.9, shafts off.  Writes benchmarks/out/emitter_cost.csv and .png.  Figures:
docs/measurements/2026-11-28-emitter-table.md.
Smoke mode (``FOG_BENCH_SMOKE=1``, benchmarks/smoke.py): 1 lamp, 2 signs, 8x4 px, 1 spp, one warm render.
"""
import argparse
import json
import math
import pathlib
import sys

import csv_rows
import smoke
import worker_result

ROOT = pathlib.Path(__file__).resolve().parents[1]
OUT = smoke.out(ROOT / "benchmarks" / "out")
SIZE = smoke.pick((640, 360, 32), (8, 4, 1))   # width, height, samples
LAMPS = smoke.pick(4, 1)
DENSITY, G, ALBEDO = 0.15, 0.85, 0.9


def add_signs(scene, count):
    """``count`` emissive 1 x 0.4 m planes over the hall, in a row across the view, turned about the vertical."""
    import bpy
    mat = bpy.data.materials.new("Neon")
    mat.use_nodes = True
    nodes = mat.node_tree.nodes
    nodes.clear()
    emission, out = nodes.new("ShaderNodeEmission"), nodes.new("ShaderNodeOutputMaterial")
    emission.inputs["Color"].default_value = (1.0, 0.3, 0.6, 1.0)
    emission.inputs["Strength"].default_value = 20.0
    mat.node_tree.links.new(emission.outputs[0], out.inputs["Surface"])
    for k in range(count):
        bpy.ops.mesh.primitive_plane_add(size=1.0, location=(-12.0 + 24.0 * (k + 0.5) / count, 2.0 + 6.0 * (k % 4),
                                                             3.0 + (k % 3)))
        sign = bpy.context.object
        sign.name = f"Sign {k:02d}"
        sign.scale = (1.0, 0.4, 1.0)
        sign.rotation_euler = (math.radians(90.0), 0.0, math.radians(30.0 + 40.0 * ((k * 7) % 5) / 4.0))
        sign.data.materials.append(mat)


def worker(spec):
    sys.path[:0] = [str(ROOT), str(ROOT / "benchmarks"), str(ROOT / "tests")]
    import bpy
    from cycles_timing import cycles_cpu, timed_apply, warm
    from shafts_cost import hall
    from fog_addon.ops import apply
    from fog_addon.precompute.physics.emitter import emitter_glow
    from fog_addon.precompute.core.spec import FogSpec
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = hall(bpy.context.scene, LAMPS)
    add_signs(scene, spec["signs"])
    cycles_cpu(scene, *SIZE)

    res = {"signs": spec["signs"]}
    res["nofog_s"], res["nofog_cpu_s"] = warm(spec["repeats"])
    fog = FogSpec(density=DENSITY, anisotropy=G, albedo=(ALBEDO,) * 3, method="compositor", shafts=False)
    for key, min_size in (("fog", emitter_glow.DIPOLE_MIN_SIZE), ("fog_no_dipole", 10 ** 6)):
        emitter_glow.DIPOLE_MIN_SIZE = min_size   # (read when the compositor's tree is built: built anew)
        if key != "fog":
            apply.remove_fog(scene)
        res[f"apply_{key}_s"] = timed_apply(scene, fog)
        res[f"{key}_s"], res[f"{key}_cpu_s"] = warm(spec["repeats"])
    res["ratio_cpu"] = res["fog_cpu_s"] / res["nofog_cpu_s"]
    res["ratio_no_dipole_cpu"] = res["fog_no_dipole_cpu_s"] / res["nofog_cpu_s"]
    worker_result.emit(res)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--signs", default=smoke.pick("4,32", "2"))
    ap.add_argument("--repeats", type=int, default=smoke.pick(2, 1))
    ap.add_argument("--worker")
    args = ap.parse_args()
    if args.worker:
        worker(json.loads(args.worker))
        return
    OUT.mkdir(parents=True, exist_ok=True)
    rows = []
    for n in (int(x) for x in args.signs.split(",")):
        row = worker_result.run(__file__, {"signs": n, "repeats": args.repeats})
        if row is not None:
            print(row, flush=True)
            rows.append(row)
    csv_rows.write(OUT / "emitter_cost.csv", rows)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 4))
    for key, label in (("ratio_cpu", "with the dipole"), ("ratio_no_dipole_cpu", "without")):
        ax.plot([r["signs"] for r in rows], [r[key] for r in rows], "o-", label=label)
    ax.set_xscale("log")
    ax.set_xlabel("glowing signs")
    ax.set_ylabel("render with fog / without (CPU)")
    ax.legend()
    fig.tight_layout()
    fig.savefig(OUT / "emitter_cost.png", dpi=90)


if __name__ == "__main__":
    main()
