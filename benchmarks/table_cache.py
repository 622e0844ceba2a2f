"""Time of the table bakes with the on-disk table cache (``precompute/core/bakers.py``) cold, warm and off.

    .venv/bin/python benchmarks/table_cache.py [REPEATS]

Each figure is one fresh process:

* ``tables g``: every table for anisotropy g (``bakers.numpy_tables``) and both pixel filter tables
  (``pixel.FILTERS``), timed inside the process: cold (an empty cache folder), warm (the same folder
  again) and off (``ANALYTIC_FOG_CACHE=off``).
* ``apply``: a typical test process: Blender (bpy) adds the fog with the node groups to a small scene
  (a sphere, a plane, a point light; ``apply.apply_fog``) and with the Compositor method, no render;
  the whole process's wall time, warm against off.

Smoke mode (``FOG_BENCH_SMOKE=1``, benchmarks/smoke.py): g 0 only, one repetition, the node groups only.
"""
import json
import os
import pathlib
import subprocess
import sys
import tempfile
import time

import smoke

ROOT = pathlib.Path(__file__).resolve().parents[1]
ANISOTROPIES = smoke.pick((0.0, 0.85), (0.0,))
APPLY_CASES = smoke.pick(((0.0, "nodes"), (0.85, "nodes"), (0.0, "compositor")), ((0.0, "nodes"),))   # (g, method)

_TABLES = r"""
import json, sys, time
sys.path.insert(0, sys.argv[1])
t = time.perf_counter()
from fog_addon.precompute.core import table_cache
from fog_addon.precompute.model import bakers
from fog_addon.precompute.model import pixel
g = float(sys.argv[2])
t0 = time.perf_counter()
bakers.numpy_tables(g)
for spec, bake in pixel.FILTERS.values():
    table_cache.cached_bake(spec, bake)
print(json.dumps({"bake_s": time.perf_counter() - t0}))
"""

_APPLY = r"""
import json, sys, time
sys.path.insert(0, sys.argv[1])
import bpy
from fog_addon.ops import apply
from demo_scenes import add_camera, add_point_light, add_sphere, material
bpy.ops.wm.read_factory_settings(use_empty=True)
s = bpy.context.scene
add_camera(s, (0, -8, 2), (0, 0, 0))
add_point_light(s, "L", (0, 0, 3), 100.0)
add_sphere(s, "S", (0, 0, 0), 1.0, material("M", (0.5, 0.5, 0.5)))
t = time.perf_counter()
apply.apply_fog(s, 0.05, anisotropy=float(sys.argv[2]), method=sys.argv[3])
print(json.dumps({"apply_s": time.perf_counter() - t}))
"""


def run(script, env, *args):
    t = time.perf_counter()
    r = subprocess.run([sys.executable, "-c", script, str(ROOT), *map(str, args)], capture_output=True, text=True,
                       env=env, timeout=900)
    wall = time.perf_counter() - t
    smoke.echo(r.stdout, r.stderr)
    assert r.returncode == 0, r.stderr[-3000:]
    return dict(json.loads(r.stdout.strip().splitlines()[-1]), wall_s=wall)


def main(repeats=smoke.pick(3, 1)):
    rows = []
    for g in ANISOTROPIES:
        for k in range(repeats):
            with tempfile.TemporaryDirectory() as d:
                env = dict(os.environ, ANALYTIC_FOG_CACHE=d)
                rows.append(("tables", g, "cold", run(_TABLES, env, g)))
                rows.append(("tables", g, "warm", run(_TABLES, env, g)))
            rows.append(("tables", g, "off", run(_TABLES, dict(os.environ, ANALYTIC_FOG_CACHE="off"), g)))
    with tempfile.TemporaryDirectory() as d:
        for g, method in APPLY_CASES:
            env = dict(os.environ, ANALYTIC_FOG_CACHE=d)
            run(_APPLY, env, g, method)   # fills the cache
            for k in range(repeats):
                rows.append((f"apply {method}", g, "warm", run(_APPLY, env, g, method)))
                rows.append((f"apply {method}", g, "off", run(_APPLY, dict(os.environ, ANALYTIC_FOG_CACHE="off"),
                                                               g, method)))
    print("what,g,cache,inner_s,process_wall_s")
    for what, g, mode, r in rows:
        print(f"{what},{g},{mode},{r.get('bake_s', r.get('apply_s')):.3f},{r['wall_s']:.3f}")


if __name__ == "__main__":
    main(*map(int, sys.argv[1:]))
