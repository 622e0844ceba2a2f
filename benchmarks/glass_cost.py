"""The fog's cost with glass in view (issue 45): the shop window (tests/scenes/shop_window.py: a Principled glass
pane, a shop behind it, two lamps) rendered by Cycles with the default method (Compositor) four ways, in one
Blender process, alternating, each the fastest of REPEATS renders:

* ``glass_nofog`` / ``glass_fog``: the scene as built, without and with fog (the materials' tails past the pane);
* ``opaque_nofog`` / ``opaque_fog``: the same with the pane opaque (Transmission 0: no specular paths, no tails).

Writes benchmarks/out/glass_cost.csv: seconds, the fog's ratio to its fog-free render in each, and the fogged
render's cost with glass over without (the issue's goal: at most 1.3).

    .venv/bin/python benchmarks/glass_cost.py          (about 2 minutes on 2 cores)
"""
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

import csv_rows  # noqa: E402
import smoke  # noqa: E402
import worker_result  # noqa: E402

RES = smoke.pick((320, 180), (8, 6))
SAMPLES = smoke.pick(32, 1)
REPEATS = smoke.pick(3, 1)
OUT = smoke.out(ROOT / "benchmarks" / "out" / "glass_cost.csv")

WORKER = r"""
import sys
sys.path.insert(0, ROOT); sys.path.insert(0, ROOT + "/tests/scenes"); sys.path.insert(0, ROOT + "/benchmarks")
import bpy
import fog_addon
from fog_addon import measure
from fog_addon.ops import apply
import shop_window as sw
fog_addon.register()
import worker_result
(w, h), samples, repeats, out = RES, SAMPLES, REPEATS, OUTDIR
def setup(tag):
    scene, cam = sw.build()
    scene.render.engine = "CYCLES"; measure.set_cycles_cpu(scene)
    sw.configure(scene, samples)
    scene.render.resolution_x, scene.render.resolution_y = w, h
    scene.cycles.use_denoising = False
    if tag.startswith("opaque"):
        bpy.data.materials["Pane"].node_tree.nodes["Principled BSDF"].inputs["Transmission Weight"].default_value = 0.0
    if tag.endswith("_fog"):
        apply.apply_fog(scene, sw.BETA, method="compositor")
    return scene
worker_result.emit(worker_result.fastest_renders(setup, ("glass_nofog", "glass_fog", "opaque_nofog", "opaque_fog"),
                                                 repeats, lambda tag: f"{out}/{tag}.exr"))
"""


def main():
    OUT.parent.mkdir(parents=True, exist_ok=True)
    code = WORKER.replace("ROOT", repr(str(ROOT))).replace("RES, SAMPLES, REPEATS, OUTDIR",
                                                             repr((RES, SAMPLES, REPEATS, str(OUT.parent))))
    r = worker_result.run_code(code, "the shop window")
    if r is None:
        return
    glass, opaque = r["glass_fog"] / r["glass_nofog"], r["opaque_fog"] / r["opaque_nofog"]
    csv_rows.write(OUT, [{**{f"{k}_s": round(v, 3) for k, v in r.items()}, "glass_ratio": round(glass, 2),
                          "opaque_ratio": round(opaque, 2), "fog_glass_over_opaque": round(glass / opaque, 2)}])


if __name__ == "__main__":
    main()
