"""Measure what one fogged material (and the World) can hold per light kind and ladder step, per engine.

Each probe is a fresh Blender process (``probe``): a small scene (a rough ground, a glossy sphere, with
``point_glass`` a Glass BSDF pane too), N lights of one kind on a grid above it, fog added by the operator
(``bpy.ops.fog.add()``) with every light forced to one ladder step (``plan.choose_models`` replaced in the
probe's process, so no budget steps them down), then one tiny render:

* ``svm``: Cycles SVM, 16 x 12 px, 1 sample; Cycles' debug log gives each shader's peak SVM stack use
  (``fog_scenes.cycles_debug_log``); clean = no "out of SVM stack space" and no fogged object black;
* ``osl``: the same with the OSL method; clean = exit 0, no error in the log, nothing black; the fogged
  material's inlined node count (what becomes OSL layers) is reported;
* ``eevee``: EEVEE, 8 x 8 px, 1 sample, on the file saved and reopened without the add-on (as a farm renders
  it: the inline marks are not saved); clean = no "Uniform block ... too big (X/65536)" line; the X of the
  overflow lines gives the bytes (each under the shader that failed to link: MA<material>, WO<World>).

``--count`` (OSL): the scene built, no render; the verdict is the inlined node count against 32 767.

    TMPDIR=/tmp/h3 .venv/bin/python benchmarks/shader_budgets.py probe KIND STEP ENGINE N [--g G] [--count]
    TMPDIR=/tmp/h3 .venv/bin/python benchmarks/shader_budgets.py run [--kinds ...] [--steps ...]
        [--engines ...] [--max-n 64] [--start N1 N2] [--count] [--out benchmarks/shader_budgets]
    FOG_BENCH_SMOKE=1 .venv/bin/python benchmarks/shader_budgets.py   # smoke: one tiny probe (SMOKE_ARGS)

``run`` (plain Python, no bpy) probes each kind x step x engine: the per-light cost from two or three small
N (stack floats, bytes, inlined nodes), the limit it predicts, then a bisection over N checked by renders
(``--no-bisect``: the prediction checked at N and N + 1 only; ``--start``: EEVEE's first N given instead of
searched).  It writes ``results.csv`` (one row per probe),
``budgets.json`` (per-light cost and limit by kind, step, engine; the engines' limits) in ``--out``.
"""
import argparse
import csv
import json
import math
import os
import pathlib
import re
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

import smoke  # noqa: E402

# kind: (Blender light type, Dense Fog, a Glass BSDF in the scene)
KINDS = {
    "point": ("POINT", False, False),
    "spot": ("SPOT", False, False),
    "area": ("AREA", False, False),
    "point_dense": ("POINT", True, False),
    "spot_dense": ("SPOT", True, False),
    "area_dense": ("AREA", True, False),
    "point_glass": ("POINT", False, True),
}
STEPS = {"full": 0, "glow": 1, "off": 2}
ENGINES = ("svm", "osl", "eevee")
EEVEE_START = {"POINT": 12, "SPOT": 4, "AREA": 4}   # the first N the EEVEE search probes (then x2 / x1.5)
SVM_STACK = 255
OSL_LAYERS = 32767
EEVEE_BYTES = 65536
DENSITY = 0.1
ANISOTROPY = 0.85
SIZE = {"svm": (16, 12), "osl": (16, 12), "eevee": (8, 8)}
FOGGED = ("Ground", "Glossy", "Glass")   # the fogged objects (and their materials' names)

UNIFORM = re.compile(r"[Uu]niform block.*?too big \((\d+)/(\d+)\)")
LINKING = re.compile(r"ERROR\s+(\S+)\s+Linking")
SVM_OUT = re.compile(r"out of SVM stack space, shader \"?([^\"]*?)\"? too big")


# ----------------------------------------------------------------------------------------------------------
# the probe (inside Blender)

def _material(bpy, name, base, rough):
    mat = bpy.data.materials.new(name)
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*base, 1.0)
    bsdf.inputs["Roughness"].default_value = rough
    # a faint glow of its own: a material that compiles is never black, whatever the lights reach
    bsdf.inputs["Emission Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    bsdf.inputs["Emission Strength"].default_value = 0.02
    return mat


def _glass(bpy):
    from fog_scenes import probe_common
    return probe_common.glass_material("Glass")


def build_scene(kind, n, engine):
    """A fresh file: ground, glossy sphere (and a glass pane), ``n`` lights of ``kind``, camera, black World."""
    import bmesh
    import bpy
    from fog_scenes import probe_common
    from fog_scenes.probe_common import look_at
    bpy.ops.wm.read_factory_settings(use_empty=True)
    s = bpy.context.scene
    look_at(s, (0.0, -9.0, 2.5), (0.0, 0.0, 1.2), 30.0)
    ltype, _, glass = KINDS[kind]

    def mesh_object(*args, **kw):
        return probe_common.mesh_object(s, *args, **kw)

    mesh_object("Ground", lambda bm: bmesh.ops.create_grid(bm, x_segments=1, y_segments=1, size=30.0),
                _material(bpy, "Ground", (0.4, 0.4, 0.4), 0.8))
    mesh_object("Glossy", lambda bm: bmesh.ops.create_uvsphere(bm, u_segments=24, v_segments=12, radius=1.0),
                _material(bpy, "Glossy", (0.2, 0.4, 0.8), 0.2), (0.0, 0.0, 1.0))
    if glass:
        mesh_object("Glass", lambda bm: bmesh.ops.create_grid(bm, x_segments=1, y_segments=1, size=0.6),
                    _glass(bpy), (1.4, -4.0, 1.4), (math.pi / 2, 0.0, 0.0))
    k = max(1, math.ceil(math.sqrt(n)))
    for i in range(n):
        x = -6.0 + 12.0 * ((i % k) + 0.5) / k
        y = -2.0 + 10.0 * ((i // k) + 0.5) / k
        data = bpy.data.lights.new(f"L{i:03d}", ltype)
        data.energy = 200.0
        if ltype == "SPOT":
            data.spot_size, data.spot_blend = math.radians(60.0), 0.2
        if ltype == "AREA":
            data.size = 0.5
        ob = bpy.data.objects.new(f"L{i:03d}", data)
        ob.location = (x, y, 3.0)
        s.collection.objects.link(ob)
    s.world = bpy.data.worlds.new("World")
    s.world.node_tree.nodes["Background"].inputs["Color"].default_value = (0, 0, 0, 1)
    return s


def force_step(step):
    """Every light at ``step`` (rungs.STEPS): the planner's choice replaced in this process only (in the module
    that plans: ``ops.plan`` since the restructuring, ``ops.apply`` before)."""
    import importlib
    mods = [importlib.import_module("fog_addon.ops.apply")]
    try:
        mods.insert(0, importlib.import_module("fog_addon.ops.plan"))
    except ImportError:
        pass
    home = next(m for m in mods if hasattr(m, "_models"))

    def forced(scene, spec, method, lights, budget=None, previous=None, **_judged):
        choice = {"target": spec.target_error, "error": 0.0, "rims": {}, "engine": scene.render.engine,
                  "limited": None, "lights": {o.name: [step, 0.0] for o in lights}, "thin": {},
                  "dense": {"left_out": {}, "missing": 0.0, "why": method.name}}
        return home._models(spec, method, lights, [step] * len(lights), {}, frozenset()), choice
    for m in mods:
        if hasattr(m, "choose_models"):
            m.choose_models = forced


def inlined_nodes(tree, seen_depth=0):
    """Nodes of ``tree`` with its groups inlined (group nodes, their inputs/outputs, reroutes and frames not
    counted): what Cycles' OSL makes layers of, before its own simplification."""
    count = 0
    for nd in tree.nodes:
        if nd.bl_idname == "ShaderNodeGroup":
            if nd.node_tree is not None:
                count += inlined_nodes(nd.node_tree, seen_depth + 1)
        elif nd.bl_idname not in ("NodeGroupInput", "NodeGroupOutput", "NodeReroute", "NodeFrame"):
            count += 1
    return count


def pixel_objects(scene, width, height):
    """The name of the object each pixel centre's camera ray hits first ('' for the sky), (height, width)."""
    import numpy as np
    from fog_scenes.probe_common import camera_rays
    import bpy
    cam = scene.camera
    origin, d = camera_rays(cam, width, height)
    dg = bpy.context.evaluated_depsgraph_get()
    names = np.empty((height, width), dtype=object)
    for j in range(height):
        for i in range(width):
            hit, _, _, _, ob, _ = scene.ray_cast(dg, tuple(origin), tuple(d[j, i]))
            names[j, i] = ob.name if hit else ""
    return names


def probe(kind, step_name, engine, n, g=ANISOTROPY, workdir=None, passes=False, top=False, render=True):
    import bpy
    import numpy as np
    import fog_addon
    from fog_addon import measure
    from fog_scenes import cycles_debug_log
    from fog_scenes.probe_common import tiny_render
    t0 = time.perf_counter()
    workdir = pathlib.Path(workdir or os.environ.get("TMPDIR", "/tmp")) / "shader_budgets"
    workdir.mkdir(parents=True, exist_ok=True)
    step = STEPS[step_name]
    _, dense, _ = KINDS[kind]
    fog_addon.register()
    force_step(step)
    s = build_scene(kind, n, engine)
    w, h = SIZE[engine]
    tiny_render(s, "BLENDER_EEVEE" if engine == "eevee" else "CYCLES", w, h)
    measure.set_cycles_cpu(s)
    st = s.analytic_fog
    st.density, st.anisotropy = DENSITY, g
    st.method = "OSL" if engine == "osl" else "NODES"
    st.quality = "EXACT"
    st.use_shafts = False
    st.use_multiple_scattering = dense
    st.use_passes = passes
    if top:   # a fog layer (daylight: sunsky.py) over the lights
        st.use_fog_top, st.fog_top = True, 5.0
    res = {"kind": kind, "step": step_name, "engine": engine, "n": n, "g": g, "passes": passes, "top": top}
    ok = bpy.ops.fog.add()
    res["added"] = "FINISHED" in ok
    from fog_addon.ops import apply
    choice = apply.stored_choice() or {}
    res["steps"] = sorted({v[0] for v in choice.get("lights", {}).values()})
    res["method"] = choice.get("method")
    res["nodes"] = {m.name: inlined_nodes(m.node_tree) for m in bpy.data.materials if m.node_tree is not None
                    and m.name in FOGGED}
    res["nodes"]["World"] = inlined_nodes(s.world.node_tree)
    res["t_add"] = time.perf_counter() - t0
    if not render:   # the node counts only (OSL's layers: what an OSL render would make of them)
        res["t_total"] = res["t_add"]
        print("PROBE_JSON " + json.dumps(res), flush=True)
        return
    measure.set_pixel_centre_filter(s)
    if engine == "eevee":
        path = workdir / f"{kind}_{step_name}_{n}.blend"
        bpy.ops.wm.save_as_mainfile(filepath=str(path))
        fog_addon.unregister()
        s = measure.open_scene(path)
    elif engine == "svm":
        res["debug_log"] = cycles_debug_log.enable()
    names = pixel_objects(s, w, h)
    out = workdir / f"{kind}_{step_name}_{engine}_{n}.exr"
    t1 = time.perf_counter()
    print("PROBE_RENDER_START", flush=True)
    measure.render_to_file(s, out)
    print("PROBE_RENDER_END", flush=True)
    res["t_render"] = time.perf_counter() - t1
    img = bpy.data.images.load(str(out), check_existing=False)
    px = np.array(img.pixels[:], dtype=np.float32).reshape(h, w, 4)[::-1, :, :3]   # row 0 = top
    res["objects"] = {}
    for name in sorted(set(names.ravel())):
        sel = px[names == name].sum(-1)
        res["objects"][name or "sky"] = {"pixels": int(sel.size), "max": float(sel.max()),
                                         "median": float(np.median(sel)), "finite": bool(np.isfinite(sel).all())}
    res["t_total"] = time.perf_counter() - t0
    print("PROBE_JSON " + json.dumps(res), flush=True)


# ----------------------------------------------------------------------------------------------------------
# the driver (plain Python)

def run_probe(kind, step, engine, n, g=ANISOTROPY, timeout=3600, passes=False, top=False, render=True):
    """Run one probe in a fresh process; a dict: the probe's JSON plus the log's verdicts.  ``render=False``
    (OSL): the scene built but not rendered, the verdict is the fogged materials' and the World's inlined node
    counts against OSL's 32 767 layers (``OSL_LAYERS``), the measure the OSL budget is built on (Cycles'
    simplification removes some nodes, so a render may still pass beyond it)."""
    from fog_scenes import render_harness as h
    from fog_scenes.cycles_debug_log import peaks
    t0 = time.perf_counter()
    try:
        flags = (["--passes"] if passes else []) + (["--top"] if top else []) + ([] if render else ["--count"])
        proc = h.run([__file__, "probe", kind, step, engine, n, "--g", g, *flags], timeout=timeout, check=False)
        text, rc = proc.stdout + proc.stderr, proc.returncode
    except Exception as e:   # noqa: BLE001 - a timeout is a verdict too
        text, rc = f"probe failed: {e}", -999
    smoke.echo(text)
    row = {"kind": kind, "step": step, "engine": engine, "n": n, "g": g, "passes": passes, "top": top, "rc": rc,
           "rendered": render,
           "seconds": round(time.perf_counter() - t0, 1)}
    line = next((ln for ln in text.splitlines() if ln.startswith("PROBE_JSON ")), None)
    res = json.loads(line.split(" ", 1)[1]) if line else {}
    # no scene reached: the add-on failed to load or build (not a verdict on the shaders' size)
    row["broken"] = not line and "PROBE_RENDER_START" not in text
    row.update(added=res.get("added"), steps=res.get("steps"), nodes=res.get("nodes"))
    render_log = text.split("PROBE_RENDER_START", 1)[-1]
    row["uniform_bytes"] = sorted({int(a) for a, _ in UNIFORM.findall(text)})
    # each overflow line under the shader that failed to link before it (MA<material>, WO<world>)
    linking = [(m.start(), m.group(1)) for m in LINKING.finditer(text)]
    row["uniform_by_shader"] = {}
    for m in UNIFORM.finditer(text):
        name = next((nm for at, nm in reversed(linking) if at < m.start()), "?")
        row["uniform_by_shader"][name] = max(row["uniform_by_shader"].get(name, 0), int(m.group(1)))
    row["svm_overflow"] = sorted(set(SVM_OUT.findall(text)))
    row["svm_peaks"] = peaks(render_log)
    row["errors"] = h.log_errors(text)[:6]
    objects = res.get("objects", {})
    lit_sky = step != "off"
    row["black"] = sorted(name for name, o in objects.items()
                          if (name != "sky" or lit_sky) and (o["max"] <= 0.0 or not o["finite"]))
    row["objects"] = {k: round(v["median"], 5) for k, v in objects.items()}
    if not render:
        clean = rc == 0 and bool(row["nodes"]) and max(row["nodes"].values()) <= OSL_LAYERS
    elif engine == "eevee":
        clean = rc == 0 and not row["uniform_bytes"] and not row["errors"]
    else:
        clean = rc == 0 and bool(objects) and not row["errors"] and not row["black"]
    row["clean"] = bool(clean and res.get("added"))
    if rc != 0:
        row["tail"] = text[-1500:]
    return row


def _fit(points):
    """(slope, intercept) of a least-squares line through [(n, value)]."""
    xs, ys = zip(*points)
    mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
    sxx = sum((x - mx) ** 2 for x in xs)
    slope = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sxx if sxx else 0.0
    return slope, my - slope * mx


def predicted(engine, rows):
    """Per-light cost, base and predicted limit from small-N probes ``rows`` of one kind x step x engine."""
    out = {}
    if engine == "svm":
        per_shader = {}
        for r in rows:
            for name, p in r["svm_peaks"].items():
                per_shader.setdefault(name, []).append((r["n"], p))
        out["svm_peaks"] = {name: dict(v) for name, v in per_shader.items()}
        fits = {name: _fit(v) for name, v in per_shader.items() if len(v) >= 2}
        out["floats_per_light"] = {name: round(a, 2) for name, (a, b) in fits.items()}
        limits = [math.floor((SVM_STACK - b) / a) for a, b in fits.values() if a > 0.05]
        out["predicted"] = min(limits) if limits else None
    elif engine == "osl":
        per = [(r["n"], max(v for k, v in r["nodes"].items() if k != "World")) for r in rows if r["nodes"]]
        world = [(r["n"], r["nodes"]["World"]) for r in rows if r["nodes"]]
        if len(per) >= 2:
            a, b = _fit(per)
            wa, wb = _fit(world)
            out.update(nodes_per_light=round(a, 1), base_nodes=round(b), world_nodes_per_light=round(wa, 1),
                       world_base=round(wb))
            lim = [math.floor((OSL_LAYERS - b) / a)] if a > 0 else []
            if wa > 0:
                lim.append(math.floor((OSL_LAYERS - wb) / wa))
            out["predicted"] = min(lim) if lim else None
    else:
        pts = [(r["n"], max(r["uniform_bytes"])) for r in rows if r["uniform_bytes"]]
        if len(pts) >= 2:
            a, b = _fit(pts)
            out.update(bytes_per_light=round(a, 1), base_bytes=round(b), predicted=math.floor((EEVEE_BYTES - b) / a))
    return out


def measure_case(kind, step, engine, writer, max_n, bisect=True, g=ANISOTROPY, small=(1, 2, 4), passes=False,
                 top=False, start=None, render=True):
    """Probe one kind x step x engine: small N for the cost, then the limit; the case's summary.  ``start``
    (EEVEE): the N probed first (two that overflow give the cost), instead of the doubling search."""
    rows = []

    def probe_n(n):
        r = run_probe(kind, step, engine, n, g, passes=passes, top=top, render=render)
        if r["broken"]:   # e.g. the add-on mid-edit: once more, then stop (a verdict it is not)
            time.sleep(30)
            r = run_probe(kind, step, engine, n, g, passes=passes, top=top, render=render)
            if r["broken"]:
                raise SystemExit(f"the probe {kind} {step} {engine} N={n} did not build its scene:\n{r.get('tail')}")
        smoke.check(r["clean"], f"the probe {kind} {step} {engine} N={n} did not render clean: {r}")
        rows.append(r)
        writer(r)
        print(f"  {kind:12s} {step:5s} {engine:5s} p{int(passes)}t{int(top)} N={n:4d} clean={r['clean']} "
              f"{r['seconds']:6.1f}s peaks={r['svm_peaks']} bytes={r['uniform_by_shader'] or r['uniform_bytes']} "
              f"nodes={r['nodes']} black={r['black']} err={r['errors'][:1]}", flush=True)
        return r

    if engine == "eevee" and start:
        summary = predicted(engine, [r for r in (probe_n(n) for n in start) if r["uniform_bytes"]])
    elif engine == "eevee":
        # the block overflows only well above a few lights: find two overflowing N by doubling
        n, over = EEVEE_START.get(KINDS[kind][0], 8), []
        while n <= max_n and len(over) < 2:
            r = probe_n(n)
            if r["uniform_bytes"]:
                over.append(r)
                n = int(n * 1.5) + 1
            else:
                n *= 2
        summary = predicted(engine, over)
    else:
        summary = predicted(engine, [probe_n(n) for n in small])
    summary.update(kind=kind, step=step, engine=engine, g=g, passes=passes, top=top, rendered=render)
    clean_n = sorted(r["n"] for r in rows if r["clean"])
    dirty_n = sorted(r["n"] for r in rows if not r["clean"])
    guess = summary.get("predicted")
    if guess is not None and guess < 1:
        guess = 0
    lo = max([0] + [n for n in clean_n if not dirty_n or n < min(dirty_n)])
    hi = min(dirty_n) if dirty_n else None
    if guess is not None and guess <= max_n:
        for n in (guess, guess + 1):
            if n >= 1 and n != lo and n != hi and (hi is None or n < hi) and n > lo:
                r = probe_n(n)
                if r["clean"]:
                    lo = max(lo, n)
                else:
                    hi = n if hi is None else min(hi, n)
    if bisect and hi is None and (guess is None or guess > max_n):
        pass   # no overflow within max_n: the limit is above it (not probed: set-up time grows with N^2)
    while bisect and hi is not None and hi - lo > 1:
        mid = (lo + hi) // 2
        r = probe_n(mid)
        lo, hi = (mid, hi) if r["clean"] else (lo, mid)
    if engine == "eevee":   # the cost per light over every overflowing N (the bisection's too)
        fit = predicted(engine, [r for r in rows if r["uniform_bytes"]])
        summary.update({k: fit[k] for k in ("bytes_per_light", "base_bytes") if k in fit})
    summary["limit"] = lo if hi is not None else None
    summary["first_bad"] = hi
    summary["above"] = max(r["n"] for r in rows) if hi is None and rows else None
    summary["seconds"] = round(sum(r["seconds"] for r in rows), 1)
    return summary


def main_run(args):
    out = smoke.out(args.out)
    out.mkdir(parents=True, exist_ok=True)
    csv_path = out / "results.csv"
    new = not csv_path.exists()
    fields = ["kind", "step", "engine", "n", "g", "passes", "top", "clean", "rc", "seconds", "added", "steps", "svm_peaks",
              "svm_overflow", "uniform_bytes", "nodes", "black", "objects", "errors", "uniform_by_shader", "rendered"]
    f = open(csv_path, "a", newline="")
    w = csv.DictWriter(f, fieldnames=fields, extrasaction="ignore")
    if new:
        w.writeheader()

    def writer(row):
        w.writerow({k: json.dumps(v) if isinstance(v, (dict, list)) else v for k, v in row.items()})
        f.flush()

    summaries_path = out / "summaries.jsonl"
    for engine in args.engines:
        for kind in args.kinds:
            for step in args.steps:
                s = measure_case(kind, step, engine, writer, args.max_n, not args.no_bisect, args.g,
                                 tuple(args.small), args.passes, args.top, args.start, not args.count)
                smoke.check(s["limit"] is not None or s["above"] is not None, f"no verdict: {s}")
                print("SUMMARY " + json.dumps(s), flush=True)
                with open(summaries_path, "a") as fs:
                    fs.write(json.dumps(s) + "\n")
    f.close()
    summarize(out)


def summarize(out):
    """budgets.json from ``out``/summaries.jsonl (the last summary of each case wins)."""
    import subprocess
    out = pathlib.Path(out)
    cases = {}
    for line in (out / "summaries.jsonl").read_text().splitlines():
        c = json.loads(line)
        key = f"{c['kind']}/{c['step']}/{c['engine']}" + ("+passes" if c.get("passes") else "") + (
            "+top" if c.get("top") else "") + (f"+g{c['g']:g}" if c.get("g", ANISOTROPY) != ANISOTROPY else "") + (
            "+count" if c.get("rendered") is False else "")
        keep = {k: c.get(k) for k in ("limit", "first_bad", "above", "predicted", "floats_per_light",
                                      "nodes_per_light", "base_nodes", "world_nodes_per_light", "world_base",
                                      "bytes_per_light", "base_bytes", "g", "seconds", "rendered")
                if c.get(k) is not None}
        if "svm_peaks" in c:
            keep["svm_peaks"] = {k: v for k, v in c["svm_peaks"].items() if k in FOGGED or k == "default_background"}
        cases[key] = keep
    commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True).stdout.strip()
    data = {"blender": "5.0.1 (bpy module)", "commit": commit + " (+ uncommitted restructuring of fog_addon/)",
            "date": time.strftime("%Y-%m-%d"), "anisotropy": ANISOTROPY, "density": DENSITY,
            "engine_limits": {"svm_stack_floats": SVM_STACK, "osl_layers": OSL_LAYERS,
                              "eevee_uniform_bytes": EEVEE_BYTES},
            "notes": "limit: largest N rendering clean (bisection); first_bad: smallest N that did not; above: no "
                     "overflow up to that N (not probed further); +count: OSL verdicts from the inlined node count "
                     "against 32 767, no render. svm_peaks: peak SVM stack floats by N (Cycles "
                     "debug log; default_background is the World). Costs are per light from a line fit.",
            "cases": cases}
    (out / "budgets.json").write_text(json.dumps(data, indent=1, sort_keys=True))
    return data


# smoke mode (benchmarks/smoke.py), with no arguments: one probe end to end (a point light with its glow off, Cycles
# SVM, 16 x 12 px, in a fresh process), its rows and summary in the smoke folder
SMOKE_ARGS = ["run", "--kinds", "point", "--steps", "off", "--engines", "svm", "--small", "1", "--no-bisect"]


def main():
    if smoke.ON and len(sys.argv) == 1:
        sys.argv += SMOKE_ARGS
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    p = sub.add_parser("probe")
    p.add_argument("kind", choices=KINDS)
    p.add_argument("step", choices=STEPS)
    p.add_argument("engine", choices=ENGINES)
    p.add_argument("n", type=int)
    p.add_argument("--g", type=float, default=ANISOTROPY)
    p.add_argument("--passes", action="store_true", help="Fog Passes on")
    p.add_argument("--top", action="store_true", help="a Fog Top (a fog layer 5 m deep) over the lights")
    p.add_argument("--count", action="store_true", help="no render: the inlined node counts only")
    r = sub.add_parser("run")
    r.add_argument("--passes", action="store_true")
    r.add_argument("--top", action="store_true")
    r.add_argument("--small", type=int, nargs="+", default=[1, 2, 4], help="the N that give the per-light cost")
    r.add_argument("--kinds", nargs="+", default=list(KINDS), choices=KINDS)
    r.add_argument("--steps", nargs="+", default=list(STEPS), choices=STEPS)
    r.add_argument("--engines", nargs="+", default=list(ENGINES), choices=ENGINES)
    r.add_argument("--max-n", type=int, default=64)
    r.add_argument("--g", type=float, default=ANISOTROPY)
    r.add_argument("--no-bisect", action="store_true")
    r.add_argument("--count", action="store_true", help="OSL: no renders, the verdict from the inlined node "
                   "counts against OSL's 32 767 layers")
    r.add_argument("--start", type=int, nargs="+", help="EEVEE: the N probed first (two that overflow give "
                   "the cost per light), instead of the doubling search")
    r.add_argument("--out", default=str(ROOT / "benchmarks" / "shader_budgets"))
    j = sub.add_parser("summarize")
    j.add_argument("--out", default=str(ROOT / "benchmarks" / "shader_budgets"))
    args = ap.parse_args()
    if args.cmd == "summarize":
        summarize(args.out)
        return
    if args.cmd == "probe":
        probe(args.kind, args.step, args.engine, args.n, args.g, passes=args.passes, top=args.top,
              render=not args.count)
    else:
        main_run(args)


if __name__ == "__main__":
    main()
