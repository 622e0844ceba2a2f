"""Scale: adding the fog to 1 000 materials (target: <= 10 s), removing it, adding it again.

    .venv/bin/python benchmarks/materials_1000.py [--materials N] [--no-profile] [--top K]

Builds a scene of N (1 000) small cube objects, each with its own Principled
BSDF material (distinct colours / roughness), plus 3 point lights, a camera
and a World, then times in one bpy process:

* ``apply_fog`` (first: the tables are baked), ``remove_fog``, ``apply_fog``
  again (tables baked again: remove deletes them), ``apply_fog`` a third time
  with the fog already on (idempotent: groups rebuilt, materials skipped);
* what-if (not the add-on's code path): rebuilding the Surface group in
  place while the 1 000 materials use it, against building it as a new
  group and moving the users over with one ``user_remap``;
* after ``fog_addon.register()``: ``bpy.ops.fog.remove``, ``bpy.ops.fog.add``,
  ``bpy.ops.fog.add`` again, ``bpy.ops.fog.remove``.

Each step is checked (every material fogged / none, one copy of each shared
data-block).  Then one more remove + ``apply_fog`` runs under cProfile and
the top functions (own time and cumulative) are printed, plus the time in
the main phases of ``apply_fog`` (tables, node groups, materials, lights).
Timings are wall-clock (``seconds``) and this process's CPU time
(``cpu_seconds``: closer to the wall time of an otherwise idle machine, the
work being single-threaded) on a shared machine: approximate.

Output: benchmarks/out/materials_1000.csv (step, seconds, cpu_seconds,
materials, fogged, ok, load_avg), the profile in benchmarks/out/materials_1000_profile.txt.
"""
import argparse
import cProfile
import csv
import io
import os
import pathlib
import pstats
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import bpy  # noqa: E402
import bmesh  # noqa: E402

import fog_addon  # noqa: E402
from demo_scenes import add_camera, add_point_light, render_settings, set_world  # noqa: E402
from fog_addon.nodes import compositor, groups, images, owned  # noqa: E402
from fog_addon.ops import apply  # noqa: E402
from fog_addon.precompute import rungs  # noqa: E402

OUT = ROOT / "benchmarks" / "out"
DENSITY = 0.05
TARGET_S = 10.0


def build(scene, n):
    """n cubes of 0.2 m on a grid, each with its own mesh and Principled material; 3 point lights."""
    render_settings(scene)
    set_world(scene)
    bm = bmesh.new()
    bmesh.ops.create_cube(bm, size=0.2)
    base = bpy.data.meshes.new("Cube")
    bm.to_mesh(base)
    bm.free()
    side = int(n ** 0.5 + 0.999)
    for i in range(n):
        mat = bpy.data.materials.new(f"Material {i:04d}")
        if mat.node_tree is None:
            mat.use_nodes = True
        bsdf = next(nd for nd in mat.node_tree.nodes if nd.bl_idname == "ShaderNodeBsdfPrincipled")
        bsdf.inputs["Base Color"].default_value = ((i % 7) / 7, (i % 11) / 11, (i % 13) / 13, 1.0)
        bsdf.inputs["Roughness"].default_value = (i % 10) / 10
        bsdf.inputs["Metallic"].default_value = (i % 3) / 2
        mesh = base.copy()
        mesh.materials.append(mat)
        ob = bpy.data.objects.new(f"Cube {i:04d}", mesh)
        ob.location = ((i % side) * 0.5, (i // side) * 0.5, 0.0)
        scene.collection.objects.link(ob)
    bpy.data.meshes.remove(base)
    for k, loc in enumerate(((2, 2, 3), (8, 5, 3), (5, 12, 3))):
        add_point_light(scene, f"Lamp {k}", loc, 500.0)
    add_camera(scene, (side * 0.25, -10, 8), (side * 0.25, side * 0.25, 0))


def fogged_count():
    return sum(1 for m in bpy.data.materials if m.node_tree is not None and owned.is_fogged(m))


def shared_ok(on):
    """Exactly one copy of each shared data-block when the fog is on, none when off."""
    names = [g.name for g in bpy.data.node_groups] + [i.name for i in bpy.data.images] + [t.name for t in bpy.data.texts]
    ours = sorted(n for n in names if n.startswith("AnalyticFog"))
    models = rungs.choose("nodes")
    want = sorted([groups.PARAMS, groups.SURFACE, groups.WORLD, groups.light_group_name(models),
                   groups.background_group_name(models)] + images.table_names()) if on else []
    if on and compositor.is_set_up(bpy.context.scene):   # the scene's own denoising set-up (Cycles, denoiser on)
        want = sorted(want + [compositor.GROUP])
    return ours == want


def side_built(name, build, *args):
    """What-if for a fix in groups.py: build the shared group ``name`` as a new, unused group, then move
    every user onto it with one ``user_remap`` (its interface identifiers are the same, so every
    instance keeps its links and values) and delete the old one."""
    old = bpy.data.node_groups.get(name)
    if old is not None:
        old.name = name + " (old)"
    new = build(*args)
    if old is not None:
        for key in old.keys():   # markers such as the lights signature
            if key not in new:
                new[key] = old[key]
        old.user_remap(new)
        bpy.data.node_groups.remove(old)
    return new


def load_avg():
    try:
        return round(os.getloadavg()[0], 2)
    except OSError:
        return ""


def timed(rows, label, fn, n, fog_on):
    c0, t0 = time.process_time(), time.perf_counter()
    fn()
    dt, cpu = time.perf_counter() - t0, time.process_time() - c0
    got = fogged_count()
    ok = got == (n if fog_on else 0) and shared_ok(fog_on)
    rows.append({"step": label, "seconds": round(dt, 3), "cpu_seconds": round(cpu, 3), "materials": n,
                 "fogged": got, "ok": ok, "load_avg": load_avg()})
    print(f"{label:34s} {dt:7.2f} s wall {cpu:7.2f} s cpu  fogged {got:5d}  {'ok' if ok else 'WRONG'}"
          f"  (load {load_avg()})", flush=True)
    return dt


PHASES = (  # (label, module file, function): the phases of apply_fog, cumulative time from the profile
    ("tables (all_table_images)", "images.py", "all_table_images"),
    ("Light group (build_light)", "groups.py", "build_light"),
    ("Background Light group", "groups.py", "build_background_light"),
    ("Surface group (build_surface)", "groups.py", "build_surface"),
    ("World group (build_world)", "groups.py", "build_world"),
    ("scene_materials", "apply.py", "scene_materials"),
    ("wrap_material (all)", "material.py", "wrap_material"),
    ("wrap_world", "world.py", "wrap_world"),
    ("wrap_light", "light.py", "wrap_light"),
)


def profile(scene, top, fresh):
    """cProfile one apply_fog: ``fresh`` after remove_fog, else with the fog already on."""
    if fresh:
        apply.remove_fog(scene)
    prof = cProfile.Profile()
    c0, t0 = time.process_time(), time.perf_counter()
    prof.runcall(apply.apply_fog, scene, DENSITY)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    st = pstats.Stats(prof)
    phases = []
    for label, fname, func in PHASES:
        cum = sum(v[3] for k, v in st.stats.items() if k[0].endswith(fname) and k[2] == func)
        calls = sum(v[1] for k, v in st.stats.items() if k[0].endswith(fname) and k[2] == func)
        phases.append((label, calls, cum))
    buf = io.StringIO()
    ps = pstats.Stats(prof, stream=buf)
    ps.sort_stats("tottime").print_stats(top)
    ps.sort_stats("cumulative").print_stats(top)
    title = f"apply_fog {'after remove_fog' if fresh else 'with the fog already on'}"
    head = (f"{title}: {wall:.2f} s wall, {cpu:.2f} s cpu under cProfile (load {load_avg()})\n"
            + "".join(f"  {label:32s} {calls:6d} calls {cum:7.2f} s\n" for label, calls, cum in phases))
    return head, buf.getvalue()


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--materials", type=int, default=1000)
    ap.add_argument("--no-profile", action="store_true")
    ap.add_argument("--top", type=int, default=25)
    args = ap.parse_args(argv)
    n = args.materials

    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    t0 = time.perf_counter()
    build(scene, n)
    print(f"built {n} objects/materials in {time.perf_counter() - t0:.2f} s (load avg {load_avg()})", flush=True)

    rows = []
    timed(rows, "apply_fog (first, bakes tables)", lambda: apply.apply_fog(scene, DENSITY), n, True)
    timed(rows, "remove_fog", lambda: apply.remove_fog(scene), n, False)
    timed(rows, "apply_fog (again, bakes tables)", lambda: apply.apply_fog(scene, DENSITY), n, True)
    timed(rows, "apply_fog (fog already on)", lambda: apply.apply_fog(scene, DENSITY), n, True)
    lights, _ = apply.fog_lights(scene)
    surface_args = (lights, apply.light_models(lights, "nodes"), images.all_table_images())
    timed(rows, "what-if: build_surface in place", lambda: groups.build_surface(*surface_args), n, True)
    timed(rows, "what-if: build_surface side-built",
          lambda: side_built(groups.SURFACE, groups.build_surface, *surface_args), n, True)
    fog_addon.register()
    try:
        timed(rows, "bpy.ops.fog.remove", lambda: bpy.ops.fog.remove(), n, False)
        timed(rows, "bpy.ops.fog.add", lambda: bpy.ops.fog.add(density=DENSITY), n, True)
        timed(rows, "bpy.ops.fog.add (fog already on)", lambda: bpy.ops.fog.add(density=DENSITY), n, True)
        timed(rows, "bpy.ops.fog.remove (again)", lambda: bpy.ops.fog.remove(), n, False)
    finally:
        fog_addon.unregister()

    OUT.mkdir(parents=True, exist_ok=True)
    with open(OUT / "materials_1000.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    print(f"wrote {OUT / 'materials_1000.csv'}")
    adds = [r for r in rows if "apply_fog" in r["step"] or r["step"].startswith("bpy.ops.fog.add")]
    for key in ("seconds", "cpu_seconds"):
        worst = max(r[key] for r in adds)
        print(f"slowest add ({key}): {worst:.2f} s (target <= {TARGET_S:g} s): {'met' if worst <= TARGET_S else 'NOT met'}")

    if not args.no_profile:
        report = [f"{n} materials, load average {load_avg()} at start\n"]
        for fresh in (True, False):
            head, text = profile(scene, args.top, fresh)
            print("\n" + head + text, flush=True)
            report += [head, "\n", text, "\n"]
        (OUT / "materials_1000_profile.txt").write_text("".join(report))
        print(f"wrote {OUT / 'materials_1000_profile.txt'}")
    return 0 if all(r["ok"] for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
