"""What one light costs the Compositor method, term by term: compositor time a frame per light.

    .venv/bin/python benchmarks/compositor_cost.py [--lights 16] [--repeats 3] [--out CSV]

The many-lights scene (fog_scenes/many_lights.py, its lights lighting the surfaces) with N point lights
or N spots (60 degrees, blend 0.3, aimed down, as ``overhead.py --spots``), Cycles CPU at 320x180 and
1 spp, so the render is a small part and the compositor most of the frame: render CPU time with the fog
(Compositor method, Quality Final) minus without, divided by N.  Each row also cuts some outputs of the
lights' compositor groups (the compositor evaluates only what reaches its output): Scattered (the fog
light on surfaces), Airlight and Background (the two glows), so the difference between rows is what a
term costs.  Each (kind, cut) runs in its own process (``--worker``); times are the best of ``repeats``
warm renders (``time.process_time``, all threads).  Smoke mode (``FOG_BENCH_SMOKE=1``,
benchmarks/smoke.py): 1 light, 8x4 px, the cut of all three outputs only, one warm render.
"""
import argparse
import json
import os
import pathlib
import subprocess
import sys
import tempfile
import time

import csv_rows
import overhead
import smoke

ROOT = pathlib.Path(__file__).resolve().parents[1]
OUT = smoke.out(ROOT / "benchmarks" / "out" / "compositor_cost.csv")
CUTS = smoke.pick(("", "Scattered", "Airlight,Background", "Scattered,Airlight,Background"),
                  ("Scattered,Airlight,Background",))
RESOLUTION = smoke.pick((320, 180), (8, 4))
FIELDS = ["kind", "lights", "cut", "nofog_cpu_s", "fog_cpu_s", "ms_per_light", "resolution", "samples", "source"]


def worker(spec):
    sys.path.insert(0, str(ROOT))   # a script run by path: the repository root
    import bpy
    from fog_scenes import many_lights
    from fog_addon import measure
    from fog_addon.nodes import comp_lights
    from fog_addon.ops import apply

    scene, _ = many_lights.build_scene(spec["lights"], direct_light=True)
    if spec["kind"] == "spot":
        overhead.as_spots(scene)
    scene.render.engine = "CYCLES"
    measure.set_resolution(scene, *RESOLUTION)
    measure.set_samples(scene, 1)
    measure.set_cycles_cpu(scene)
    scene.cycles.use_denoising = False

    def best():
        times = []
        for _ in range(spec["repeats"]):
            t = time.process_time()
            bpy.ops.render.render()
            times.append(time.process_time() - t)
        return min(times)

    bpy.ops.render.render()
    nofog = best()
    apply.apply_fog(scene, density=0.1, method="compositor")
    cut = [c for c in spec["cut"].split(",") if c]
    found = set()
    for ng in bpy.data.node_groups:
        if ng.name.startswith(comp_lights.LIGHT_GROUP):
            out = next(n for n in ng.nodes if n.bl_idname == "NodeGroupOutput")
            for name in (c for c in cut if c in out.inputs):   # a light's glow group or its scatter group
                found.add(name)
                for link in list(out.inputs[name].links):
                    ng.links.remove(link)
    if set(cut) - found:   # an output renamed: the row would time the whole fog under the cut's name
        raise RuntimeError(f"no compositor light group has the outputs {sorted(set(cut) - found)}")
    bpy.ops.render.render()
    fog = best()
    print("COST_JSON " + json.dumps({"nofog_cpu_s": nofog, "fog_cpu_s": fog}), flush=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--lights", type=int, default=smoke.pick(16, 1))
    ap.add_argument("--repeats", type=int, default=smoke.pick(3, 1))
    ap.add_argument("--out", default=str(OUT))
    ap.add_argument("--worker", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.worker:
        return worker(json.loads(args.worker))
    env = dict(os.environ, TMPDIR=os.environ.get("TMPDIR") or tempfile.mkdtemp(prefix="compositor_cost_"))
    rows = []
    for kind in ("point", "spot"):
        for cut in CUTS:
            spec = {"kind": kind, "lights": args.lights, "cut": cut, "repeats": args.repeats}
            proc = subprocess.run([sys.executable, __file__, "--worker", json.dumps(spec)], cwd=str(ROOT), env=env,
                                  capture_output=True, text=True)
            smoke.echo(proc.stdout, proc.stderr)
            line = next((ln for ln in proc.stdout.splitlines() if ln.startswith("COST_JSON ")), None)
            if line is None:
                raise RuntimeError(f"{kind} {cut!r} failed:\n{proc.stdout[-2000:]}\n{proc.stderr[-2000:]}")
            r = json.loads(line.split(" ", 1)[1])
            rows.append({"kind": kind, "lights": args.lights, "cut": cut or "none", **r,
                         "ms_per_light": 1000.0 * (r["fog_cpu_s"] - r["nofog_cpu_s"]) / args.lights,
                         "resolution": "{}x{}".format(*RESOLUTION), "samples": 1, "source": overhead.source_id()})
            print(f"{kind:5} cut {cut or 'none':30} {rows[-1]['ms_per_light']:7.1f} ms a light", flush=True)
    csv_rows.write(args.out, rows, FIELDS, digits=4)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
