"""The fog's cost with glass in view (issue 45): the shop window (tests/scenes/shop_window.py: a Principled glass
pane, a shop behind it, two lamps) rendered by Cycles with the default method (Compositor) four ways, in one
Blender process, alternating, each the fastest of REPEATS renders:

* ``glass_nofog`` / ``glass_fog``: the scene as built, without and with fog (the materials' tails past the pane);
* ``opaque_nofog`` / ``opaque_fog``: the same with the pane opaque (Transmission 0: no specular paths, no tails).

Writes benchmarks/out/glass_cost.csv: seconds, the fog's ratio to its fog-free render in each, and the fogged
render's cost with glass over without (the issue's goal: at most 1.3).

    .venv/bin/python benchmarks/glass_cost.py          (about 2 minutes on 2 cores)
"""
import json
import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

import smoke  # noqa: E402

RES = smoke.pick((320, 180), (8, 6))
SAMPLES = smoke.pick(32, 1)
REPEATS = smoke.pick(3, 1)
OUT = smoke.out(ROOT / "benchmarks" / "out" / "glass_cost.csv")

WORKER = r"""
import json, sys, time
sys.path.insert(0, ROOT); sys.path.insert(0, ROOT + "/tests/scenes")
import bpy
import fog_addon
from fog_addon import measure
from fog_addon.ops import apply
import shop_window as sw
fog_addon.register()
(w, h), samples, repeats, out = RES, SAMPLES, REPEATS, OUTDIR
times = {k: [] for k in ("glass_nofog", "glass_fog", "opaque_nofog", "opaque_fog")}
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
for r in range(repeats):
    for tag in times:
        s = setup(tag)
        t = time.perf_counter()
        measure.render_to_file(s, f"{out}/{tag}.exr")
        times[tag].append(time.perf_counter() - t)
print("RESULT " + json.dumps({k: min(v) for k, v in times.items()}))
"""


def main():
    OUT.parent.mkdir(parents=True, exist_ok=True)
    code = WORKER.replace("ROOT", repr(str(ROOT))).replace("RES, SAMPLES, REPEATS, OUTDIR",
                                                             repr((RES, SAMPLES, REPEATS, str(OUT.parent))))
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    smoke.echo(proc.stdout[-3000:] + proc.stderr[-3000:])
    line = next((ln for ln in proc.stdout.splitlines() if ln.startswith("RESULT ")), None)
    smoke.check(proc.returncode == 0 and line is not None, f"exit {proc.returncode}")
    if line is None:
        return
    r = json.loads(line.split(" ", 1)[1])
    with open(OUT, "w") as f:
        f.write("glass_nofog_s,glass_fog_s,opaque_nofog_s,opaque_fog_s,glass_ratio,opaque_ratio,fog_glass_over_opaque\n")
        f.write(f"{r['glass_nofog']:.3f},{r['glass_fog']:.3f},{r['opaque_nofog']:.3f},{r['opaque_fog']:.3f},"
                f"{r['glass_fog'] / r['glass_nofog']:.2f},{r['opaque_fog'] / r['opaque_nofog']:.2f},"
                f"{(r['glass_fog'] / r['glass_nofog']) / (r['opaque_fog'] / r['opaque_nofog']):.2f}\n")
    print(open(OUT).read())


if __name__ == "__main__":
    main()
