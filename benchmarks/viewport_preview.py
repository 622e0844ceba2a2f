"""The viewport preview's cost (issue 45): Cycles' render of the many-lights scene (ground, three spheres, N point
lamps lighting the surfaces; fog_scenes/many_lights.build_scene) with the Compositor method, three ways, in one
Blender process, alternating, each the fastest of REPEATS renders:

* ``nofog``: the scene without fog;
* ``final``: with the Compositor's fog as F12 renders it, the compositing off (the render's own cost: the
  materials with the preview's closures behind a factor of 0);
* ``bare``: the same scene built without a preview (``Compositor.preview_budget`` None): what ``final`` cost
  before the preview existed;
* ``viewport``: what the rendered viewport renders (``preview.forced``: the preview's closures on, no
  compositing), at SAMPLES samples, the same for all.

Writes benchmarks/out/viewport_preview.csv (lights, shown, seconds of each, the ratios to ``nofog``).

    .venv/bin/python benchmarks/viewport_preview.py          (about 9 minutes on 2 cores)
"""
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

import smoke  # noqa: E402
import worker_result  # noqa: E402

LIGHTS = smoke.pick((1, 25, 100), (1,))   # (square numbers: the scene's grid)
RES = smoke.pick((320, 180), (8, 6))
SAMPLES = smoke.pick(64, 1)
REPEATS = smoke.pick(3, 1)
OUT = smoke.out(ROOT / "benchmarks" / "out" / "viewport_preview.csv")

WORKER = r"""
import sys
sys.path.insert(0, ROOT); sys.path.insert(0, ROOT + "/benchmarks")
import bpy
import fog_addon
from fog_addon import measure, methods
from fog_addon.nodes import preview
from fog_addon.ops import apply
from fog_addon.precompute.core.spec import FogSpec
from fog_scenes import many_lights as ml
import worker_result
fog_addon.register()
comp = methods.get("compositor")
budget = comp.preview_budget
n, (w, h), samples, repeats, out = N, RES, SAMPLES, REPEATS, OUTDIR
shown = {}   # the lights the preview holds (the final build's)
def setup(tag):
    s, cam = ml.build_scene(n, direct_light=True)
    s.render.engine = "CYCLES"; measure.set_cycles_cpu(s)
    s.render.resolution_x, s.render.resolution_y = w, h
    s.cycles.samples = samples; s.cycles.use_denoising = False
    if tag != "nofog":
        comp.preview_budget = (lambda *a: None) if tag == "bare" else budget
        apply.apply(s, FogSpec(density=0.05, method="compositor"))
        if tag == "final":
            shown["lights"] = sum(1 for v in (((apply.stored_choice() or {}).get("preview") or {}).get("lights")
                                              or {}).values() if v[0] < 2)
    s.render.use_compositing = False
    return s
def render(tag, s, path):
    if tag == "viewport":
        with preview.forced():
            measure.render_to_file(s, path)
    else:
        measure.render_to_file(s, path)
times = worker_result.fastest_renders(setup, ("nofog", "bare", "final", "viewport"), repeats,
                                      lambda tag: f"{out}/{tag}_{n}.exr", render)
worker_result.emit({"lights": n, "shown": shown.get("lights"), **times})
"""


def run(n):
    code = (WORKER.replace("ROOT", repr(str(ROOT))).replace("N, RES, SAMPLES, REPEATS, OUTDIR",
                                                               repr((n, RES, SAMPLES, REPEATS, str(OUT.parent)))))
    return worker_result.run_code(code, f"{n} lights")


def main():
    OUT.parent.mkdir(parents=True, exist_ok=True)
    rows = [r for r in (run(n) for n in LIGHTS) if r]
    with open(OUT, "w") as f:
        f.write("lights,shown,nofog_s,bare_s,final_s,viewport_s,bare_ratio,final_ratio,viewport_ratio\n")
        for r in rows:
            f.write(f"{r['lights']},{r['shown']},{r['nofog']:.3f},{r['bare']:.3f},{r['final']:.3f},"
                    f"{r['viewport']:.3f},{r['bare'] / r['nofog']:.2f},{r['final'] / r['nofog']:.2f},"
                    f"{r['viewport'] / r['nofog']:.2f}\n")
    print(open(OUT).read())


if __name__ == "__main__":
    main()
