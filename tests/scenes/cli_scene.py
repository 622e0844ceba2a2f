"""The command line renders a saved file's fog as the artist left it (tests/test_cli_scene.py).

    python cli_scene.py build OUTDIR      # the panel's flow: fog with non-default settings, render
                                          # panel.exr, save scene.blend; then density changed: override.exr
    python cli_scene.py settings BLEND    # fog_addon.render.fog_settings on BLEND, method cases

The last line of stdout is one JSON object.
"""
import argparse
import json
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import bpy  # noqa: E402

import fog_addon  # noqa: E402
from demo_scenes import add_camera, add_plane, add_point_light, material, set_world  # noqa: E402
from fog_addon import measure, render  # noqa: E402

RESOLUTION = (32, 18)
SAMPLES = 4
DENSITY = 0.06          # 1/m; with SCENE_SCALE 2 that is 0.12 per unit: optical depth about 1 to the wall
COLOR = (0.9, 0.7, 0.5)
SCENE_SCALE = 2.0
OVERRIDE_DENSITY = 0.15
LAMP_ON, LAMP_OFF = "Lamp On", "Lamp Off"   # the second one has its Fog Glow toggled off
GROUND, WALL = "Ground", "Wall"             # Selected Only with only the ground selected: the wall stays unfogged


def build(scene):
    set_world(scene)
    ground = add_plane(scene, GROUND, -6, 6, -2, 10, 0.0, material("GroundMat", (0.6, 0.6, 0.6)))
    wall = add_plane(scene, WALL, -6, 6, 8, 8, 0.0, material("WallMat", (0.3, 0.5, 0.7)))
    wall.data.vertices.foreach_set("co", [-6, 8, 0, 6, 8, 0, 6, 8, 5, -6, 8, 5])   # vertical, facing the camera
    wall.data.update()
    add_point_light(scene, LAMP_ON, (-1.5, 3.0, 1.5), 300.0)
    add_point_light(scene, LAMP_OFF, (2.0, 5.0, 1.2), 300.0)
    add_camera(scene, (0.0, -4.0, 1.6), (0.0, 6.0, 1.2))
    scene.render.engine = "CYCLES"
    measure.set_resolution(scene, *RESOLUTION)
    for ob in scene.objects:
        ob.select_set(ob.name == GROUND)
    return ground, wall


def render_like_the_command(scene, out):
    """What ``python -m fog_addon render --engine cycles --samples SAMPLES --pixel-centre`` sets."""
    scene.render.engine = "CYCLES"
    measure.set_samples(scene, SAMPLES)
    measure.set_cycles_cpu(scene)
    measure.set_pixel_centre_filter(scene)
    measure.render_to_file(scene, out)


def main_build(outdir):
    outdir = pathlib.Path(outdir)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    fog_addon.register()
    scene = bpy.context.scene
    build(scene)
    s = scene.analytic_fog
    s.color = COLOR
    s.scene_scale = SCENE_SCALE
    s.selected_only = True
    bpy.data.objects[LAMP_OFF].data.analytic_fog.use = False
    res = {"add": sorted(bpy.ops.fog.add(density=DENSITY))}
    res["fogged"] = {name: any(n.get("analytic_fog") is not None for n in bpy.data.objects[name]
                               .material_slots[0].material.node_tree.nodes) for name in (GROUND, WALL)}
    render_like_the_command(scene, outdir / "panel.exr")
    bpy.ops.wm.save_as_mainfile(filepath=str(outdir / "scene.blend"))
    s.density = OVERRIDE_DENSITY       # the panel's density field: the fog updates at once
    render_like_the_command(scene, outdir / "override.exr")
    res["settings"] = {"density": DENSITY, "color": COLOR, "scene_scale": SCENE_SCALE, "samples": SAMPLES,
                       "override_density": OVERRIDE_DENSITY}
    return res


def main_settings(blend):
    """render.fog_settings for the method cases, on ``blend`` with its Method set to OSL."""
    render.ensure_properties()
    scene = measure.open_scene(blend)
    s = scene.analytic_fog
    res = {"file": {"density": s.density, "color": list(s.color), "scene_scale": s.scene_scale,
                    "selected_only": s.selected_only, "method": s.method,
                    "lamp_use": {n: bpy.data.objects[n].data.analytic_fog.use for n in (LAMP_ON, LAMP_OFF)}}}
    s.enabled = False            # change the setting only: no fog rebuild from the update callback
    s.method = "OSL"

    def case(engine, method=None):
        args = argparse.Namespace(engine_id=engine, method=method)
        try:
            spec, _, shown, notes = render.fog_settings(scene, args)
        except SystemExit as e:
            return {"exit": str(e)}
        return {"method": spec.method, "source": shown["method"][1], "notes": [n for _, n in notes]}

    res["cycles_file_osl"] = case("CYCLES")
    res["eevee_file_osl"] = case("BLENDER_EEVEE")
    res["cycles_flag_nodes"] = case("CYCLES", "nodes")
    res["eevee_flag_osl"] = case("BLENDER_EEVEE", "osl")
    return res


def main():
    mode, arg = sys.argv[1], sys.argv[2]
    res = main_build(arg) if mode == "build" else main_settings(arg)
    print(json.dumps(res))


if __name__ == "__main__":
    main()
