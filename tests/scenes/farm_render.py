"""Process B of the farm test: render a saved .blend where the add-on is neither installed nor enabled.

    python farm_render.py FILE.blend OUTDIR JOBS_JSON

JOBS_JSON: a list of {"out": NAME.exr, "engine": null | "BLENDER_EEVEE", "frame": null | int}.
engine null renders with the settings saved in the file (as a farm would); otherwise
``farm_common.render_settings`` switches engine.  frame: ``scene.frame_set(frame)`` first.

Run it from a directory without ``fog_addon``, with a clean environment: this script
imports only bpy and farm_common (which imports only bpy).  Scripts auto-run is off.
The last line of stdout is one JSON object: what the process could see of the add-on,
the file's images, texts, script nodes and drivers, the saved render settings, and per
job the driven light/camera positions next to the objects' own.
"""
import importlib.util
import json
import math
import os
import sys
import time

import bpy

from farm_common import driver_report, emit, render_exr, render_settings


def addon_state():
    prefs = bpy.context.preferences
    return {
        "find_spec_fog_addon": importlib.util.find_spec("fog_addon") is not None,
        "enabled_addons": sorted(a.module for a in prefs.addons),
        "fog_modules": sorted(m for m in sys.modules if "fog" in m.lower()),
        "fog_operator": hasattr(bpy.ops, "fog") and "add" in dir(bpy.ops.fog),
        "scene_rna_prop": hasattr(bpy.types.Scene, "analytic_fog"),
        "auto_exec": bool(prefs.filepaths.use_scripts_auto_execute),
    }


def file_report(scene):
    images = {i.name: {"packed": i.packed_file is not None, "source": i.source, "filepath": i.filepath,
                       "has_data": bool(i.has_data) or i.packed_file is not None}
              for i in bpy.data.images if i.type == "IMAGE"}
    texts = {t.name: {"filepath": t.filepath, "in_memory": bool(t.is_in_memory), "chars": len(t.as_string())}
             for t in bpy.data.texts}
    scripts = []
    trees = [("group", g) for g in bpy.data.node_groups] + \
            [("material", m.node_tree) for m in bpy.data.materials if m.node_tree] + \
            [("world", w.node_tree) for w in bpy.data.worlds if w.node_tree]
    for kind, tree in trees:
        for n in tree.nodes:
            if n.bl_idname == "ShaderNodeScript":
                scripts.append({"tree": tree.name, "mode": n.mode, "script": n.script.name if n.script else None,
                                "bytecode_chars": len(n.bytecode), "filepath": n.filepath})
    r, c = scene.render, scene.cycles
    settings = {"engine": r.engine, "res": [r.resolution_x, r.resolution_y, r.resolution_percentage],
                "samples": c.samples, "adaptive": c.use_adaptive_sampling, "filter": c.pixel_filter_type,
                "filter_width": c.filter_width, "denoise": c.use_denoising, "seed": c.seed,
                "animated_seed": c.use_animated_seed, "osl": bool(c.shading_system), "device": c.device}
    return {"images": images, "texts": texts, "scripts": scripts, "settings": settings}


def driven_positions(scene):
    """Each driven 'Light k Location' / 'Camera Location' / 'Light k Intensity' node's values next to
    what they should be at this frame: the target object's world location, or the target light's
    radiant intensity power * colour / (4 pi)."""
    dg = bpy.context.evaluated_depsgraph_get()
    out = []
    for g in bpy.data.node_groups:
        ge = g.evaluated_get(dg)
        for n in ge.nodes:
            kind = n.name.rsplit(" ", 1)[-1]
            if n.bl_idname != "ShaderNodeCombineXYZ" or kind not in ("Location", "Intensity"):
                continue
            fc = next((f for f in (g.animation_data.drivers if g.animation_data else ())
                       if f.data_path.startswith(f'nodes["{n.name}"]')), None)
            target = fc.driver.variables[0].targets[0].id if fc else None
            if target is None:
                want = None
            elif kind == "Location":
                want = list(target.evaluated_get(dg).matrix_world.translation)
            else:
                light = target.evaluated_get(dg)
                want = [light.energy * c / (4.0 * math.pi) for c in light.color]
            out.append({"group": g.name, "node": n.name, "kind": kind, "driven": [s.default_value for s in n.inputs[:3]],
                        "target": target.name if target else None, "expected": want})
    return out


def canary(scene):
    """Prove Python drivers cannot run here: a driver needing auto-run (attribute access) must fail.

    Added after the renders, on a custom property of the scene (it renders nothing).
    Simple expressions, and Python expressions passing Blender's restricted-access test
    (e.g. ``float(p)``), still run without auto-run; ``x.real`` does not.
    """
    scene["farm_canary"] = -1.0
    d = scene.driver_add('["farm_canary"]').driver
    d.type = "SCRIPTED"
    v = d.variables.new()
    v.name = "x"
    v.targets[0].id_type = "OBJECT"
    v.targets[0].id = scene.camera
    v.targets[0].data_path = "location[0]"
    d.expression = "x.real + 1.0"
    scene.frame_set(scene.frame_current)
    value = scene.evaluated_get(bpy.context.evaluated_depsgraph_get())["farm_canary"]
    return {"valid": bool(d.is_valid), "value": value, "autoexec_fail": bool(bpy.app.autoexec_fail)}


def main():
    blend, outdir, jobs = sys.argv[1], sys.argv[2], json.loads(sys.argv[3])
    before = addon_state()
    bpy.context.preferences.filepaths.use_scripts_auto_execute = False
    # use_scripts: the operator takes auto-run from Blender's global flag, not from the preference
    bpy.ops.wm.open_mainfile(filepath=os.path.abspath(blend), load_ui=False, use_scripts=False)
    scene = bpy.context.scene
    after = addon_state()
    report = file_report(scene)
    done = []
    for job in jobs:
        if job.get("engine"):
            render_settings(scene, job["engine"])
        if job.get("frame") is not None:
            scene.frame_set(int(job["frame"]))
        t = time.perf_counter()
        render_exr(scene, os.path.join(outdir, job["out"]))
        done.append({**job, "render_s": round(time.perf_counter() - t, 2), "drivers": driver_report(),
                     "positions": driven_positions(scene), "frame_current": scene.frame_current})
    print("farm_render: renders done, canary follows", file=sys.stderr, flush=True)
    blocked = {"autoexec_fail": bool(bpy.app.autoexec_fail), "message": bpy.app.autoexec_fail_message}
    emit({"before_open": before, "after_open": after, "after_renders": addon_state(), **report, "jobs": done,
          "blocked_scripts": blocked, "canary": canary(scene)})


if __name__ == "__main__":
    main()
