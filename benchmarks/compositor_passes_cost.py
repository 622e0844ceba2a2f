"""The Compositor method's fog passes' cost (issue 45: at most 1.1x the same fog without them): Cycles' render of
the many-lights scene (ground, three spheres, N point lamps lighting the surfaces; fog_scenes/many_lights.build_scene)
with the Compositor method, three ways, in one Blender process, alternating, each the fastest of REPEATS renders
(the render written, the compositor run: its File Output node writes the passes):

* ``nofog``: the scene without fog;
* ``fog``: with the Compositor's fog, Fog Passes off;
* ``passes``: the same with Fog Passes on (the materials' Fog Transmittance AOV, the fog group's two outputs, the
  File Output node's multilayer EXR).

Writes benchmarks/out/compositor_passes_cost.csv (lights, seconds of each, the ratios).

    .venv/bin/python benchmarks/compositor_passes_cost.py          (about 3 minutes on 2 cores)
"""
import json
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

import smoke  # noqa: E402
import worker_result  # noqa: E402

LIGHTS = smoke.pick((1, 25), (1,))   # (square numbers: the scene's grid)
RES = smoke.pick((160, 90), (8, 6))
SAMPLES = smoke.pick(16, 1)
REPEATS = smoke.pick(3, 1)
OUT = smoke.out(ROOT / "benchmarks" / "out" / "compositor_passes_cost.csv")

def worker(spec):
    """One lamp count's three renders, alternating (the module docstring); emits the fastest of each."""
    import bpy  # noqa: F401 - (Blender first)
    import fog_addon
    from fog_addon import measure
    from fog_addon.nodes import compositor
    from fog_addon.ops import apply
    from fog_addon.precompute.core.spec import FogSpec
    from fog_scenes import many_lights as ml
    fog_addon.register()
    n, (w, h), out = spec["lights"], RES, str(OUT.parent)

    def setup(tag):
        s, _ = ml.build_scene(n, direct_light=True)
        s.render.engine = "CYCLES"
        measure.set_cycles_cpu(s)
        s.render.resolution_x, s.render.resolution_y = w, h
        s.cycles.samples, s.cycles.use_denoising = SAMPLES, False
        if tag != "nofog":
            apply.apply(s, FogSpec(density=0.05, method="compositor", passes=tag == "passes"))
            for node in compositor.passes_outputs(s):
                node.directory = out + "/"
        return s

    worker_result.emit({"lights": n, **worker_result.fastest_renders(
        setup, ("nofog", "fog", "passes"), REPEATS, lambda tag: f"{out}/passes_cost_{tag}_{n}.exr")})


def main():
    if "--worker" in sys.argv:
        return worker(json.loads(sys.argv[sys.argv.index("--worker") + 1]))
    OUT.parent.mkdir(parents=True, exist_ok=True)
    rows = [r for r in (worker_result.run(__file__, {"lights": n}) for n in LIGHTS) if r]
    with open(OUT, "w") as f:
        f.write("lights,nofog_s,fog_s,passes_s,fog_ratio,passes_ratio,passes_over_fog\n")
        for r in rows:
            f.write(f"{r['lights']},{r['nofog']:.3f},{r['fog']:.3f},{r['passes']:.3f},{r['fog'] / r['nofog']:.2f},"
                    f"{r['passes'] / r['nofog']:.2f},{r['passes'] / r['fog']:.3f}\n")
    print(open(OUT).read())


if __name__ == "__main__":
    main()
