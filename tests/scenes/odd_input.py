"""Odd input, as a new user gives it: what the fog says and does; prints one JSON line (ODD_JSON).

* ``density_zero``: the sky row and a lit sphere of a 32 x 18 Cycles render (4 samples, the spheres demo with a
  grey World) with the fog at density 0, by the Node Groups and the Compositor methods, over the same render
  without the fog.
* ``panel``: values typed into the panel beyond the sliders (density 1e4, visibility 0.01 m, a negative Height
  Falloff, Scene Scale 0): the setting keeps the typed value, the fog keeps what it was built with, and the panel's
  message (``apply.sync_error``) is the operator's for the same value; ``settings_error`` says it before Add Fog.
* ``notes``: the operator's warnings for a lamp at the camera, a scene with no lights, a Ground Level above the
  scene, Scene Scale 1e6, and two view layers with the Compositor method and no compositor of the user's (and
  Auto's choice there).
* ``nan``: any "nan" in the explain lines of those scenes.
"""
import json
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import bpy  # noqa: E402
import numpy as np  # noqa: E402

import fog_addon  # noqa: E402
from demo_scenes import spheres  # noqa: E402
from fog_addon.ops import apply  # noqa: E402
from fog_addon.precompute.core.spec import FogSpec  # noqa: E402

WORLD_GREY = 0.08
_registered = []


def fresh():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    if not _registered:
        fog_addon.register()
        _registered.append(True)
    scene = bpy.context.scene
    spheres.build(scene)
    scene.render.engine = "CYCLES"
    scene.cycles.samples = 4
    scene.cycles.use_denoising = False
    scene.cycles.seed = 1
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 32, 18, 100
    bg = scene.world.node_tree.nodes.get("Background")
    if bg is not None:
        bg.inputs["Color"].default_value = (WORLD_GREY, WORLD_GREY, WORLD_GREY, 1.0)
    return scene


def render(scene):
    path = str(pathlib.Path(bpy.app.tempdir or "/tmp") / "odd_input.exr")
    scene.render.filepath = path
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.view_settings.view_transform = "Standard"
    bpy.ops.render.render(write_still=True)
    img = bpy.data.images.load(path, check_existing=False)
    w, h = img.size
    px = np.array(img.pixels[:], dtype=np.float64).reshape(h, w, 4)[::-1, :, :3]   # row 0 = top
    bpy.data.images.remove(img)
    return px


def warnings(result):
    return [why for _, why in result]


def density_zero():
    out = {}
    for method in ("NODES", "COMPOSITOR"):
        scene = fresh()
        clear = render(scene)
        scene.analytic_fog.density = 0.0
        scene.analytic_fog.method = method
        assert bpy.ops.fog.add() == {"FINISHED"}
        fogged = render(scene)
        out[method.lower()] = {"sky": float(fogged[0].mean() / clear[0].mean()),
                               "picture": float(fogged.mean() / clear.mean()),
                               "sky_clear": float(clear[0].mean()), "built": apply.built_method().name}
    return out


def panel():
    scene = fresh()
    out = {}
    typed = {"density": 1e4, "visibility": 0.01, "height_falloff": -5.0, "scene_scale": 0.0}
    s = scene.analytic_fog
    s.density = 0.1
    out["before_add"] = {}
    for key, value in typed.items():   # before Add Fog: the panel's box says what Add Fog would refuse
        old = getattr(s, key)
        if key == "height_falloff":
            s.use_fog_top = True
        setattr(s, key, value)
        out["before_add"][key] = apply.settings_error(scene)
        setattr(s, key, old) if key != "visibility" else setattr(s, "density", 0.1)
        s.use_fog_top = False
    assert bpy.ops.fog.add() == {"FINISHED"}
    for key, value in typed.items():
        if key == "height_falloff":
            s.use_fog_top = True
        built = apply.stored_choice()
        setattr(s, key, value)
        try:
            FogSpec.from_settings(s)
            operator = None
        except ValueError as e:
            operator = str(e)
        out[key] = {"kept": getattr(s, key), "message": apply.sync_error(scene), "operator": operator,
                    "fog_kept": apply.stored_choice() == built}
        if key == "visibility":
            s.density = 0.1
        else:
            setattr(s, key, {"density": 0.1, "height_falloff": 0.0, "scene_scale": 1.0}[key])
        s.use_fog_top = False
    out["cleared"] = apply.sync_error(scene)
    return out


def notes():
    out, nan = {}, []
    # a lamp at the camera
    scene = fresh()
    lamp = next(o for o in scene.objects if o.type == "LIGHT")
    lamp.location = scene.camera.location
    scene.analytic_fog.density = 0.1
    out["lamp_at_camera"] = run_add(scene, nan)
    # no lights
    scene = fresh()
    for o in [o for o in scene.objects if o.type == "LIGHT"]:
        bpy.data.objects.remove(o)
    out["no_lights"] = run_add(scene, nan)
    # Ground Level above the scene
    scene = fresh()
    s = scene.analytic_fog
    s.use_fog_top, s.fog_top, s.ground_level = True, 20.0, 100.0
    out["ground_above"] = run_add(scene, nan)
    out["panel_notes"] = panel_notes(scene)
    # Scene Scale 1e6
    scene = fresh()
    scene.analytic_fog.scene_scale = 1e6
    out["scale_1e6"] = run_add(scene, nan)
    # density 100 (the largest)
    scene = fresh()
    scene.analytic_fog.density = 100.0
    out["density_100"] = run_add(scene, nan)
    # two view layers, no compositor of the user's
    scene = fresh()
    scene.view_layers.new("Second")
    scene.analytic_fog.method = "COMPOSITOR"
    scene.analytic_fog.use_shafts = False
    out["two_layers_compositor"] = run_add(scene, nan)
    bpy.ops.fog.remove()
    scene.analytic_fog.method = "AUTO"
    out["two_layers_auto"] = run_add(scene, nan)
    return out, nan


def run_add(scene, nan):
    reports = []
    ok = bpy.ops.fog.add()
    lines = apply.explain()
    nan += [ln for ln in lines if "nan" in ln.lower()]
    for name, why in apply.fog_lights(scene)[1]:
        reports.append(f"{name}: {why}")
    reports += apply.stored_caveats()
    reports += apply.scene_notes(scene, apply.spec_of(scene))
    choice = apply.stored_choice() or {}
    return {"ok": sorted(ok), "notes": reports, "explain": lines, "method": choice.get("method"),
            "reason": choice.get("method_reason"), "skipped": _last_skipped(scene)}


def panel_notes(scene):
    """The panel's memo of the scene's notes (``apply.panel_notes``): the same list on a second redraw, computed
    again once the scene changed (the ground moved above Ground Level: the note goes) and said again when it
    comes back."""
    spec = apply.spec_of(scene)
    first = apply.panel_notes(scene, spec)
    again = apply.panel_notes(scene, spec)
    ground = next(o for o in scene.objects if o.type == "MESH")
    z = ground.location.z
    ground.location.z = 150.0
    bpy.context.view_layer.update()
    moved = apply.panel_notes(scene, spec)
    ground.location.z = z
    bpy.context.view_layer.update()
    back = apply.panel_notes(scene, spec)
    return {"memo": again is first, "first": first, "moved": moved, "back": back}


def _last_skipped(scene):
    """What Add Fog warned about (its skipped list), from a second call of ``apply.apply`` (adding twice is
    the same as once)."""
    return [why for _, why in apply.apply(scene, apply.spec_of(scene))]


def main():
    out = {"density_zero": density_zero(), "panel": panel()}
    out["notes"], out["nan"] = notes()
    print("ODD_JSON " + json.dumps(out))


if __name__ == "__main__":
    main()
