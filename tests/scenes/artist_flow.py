"""What an artist does in the UI, without drawing it: settings, presets, light changes, bad input.

Prints one JSON line of findings; tests/test_artist.py asserts on them.
Run with BLENDER_USER_RESOURCES pointing at a scratch folder (user presets are written there).
"""
import json
import pathlib
import sys
import types

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import bpy  # noqa: E402

import fog_addon  # noqa: E402
from add_remove import snapshot  # noqa: E402
from demo_scenes import spheres  # noqa: E402

R = {}


def beta_in_groups():
    return bpy.data.node_groups["AnalyticFog Params"].nodes["Beta"].outputs[0].default_value


def light_instances():
    bundles = [n.node_tree for n in bpy.data.node_groups["AnalyticFog Surface"].nodes
               if n.bl_idname == "ShaderNodeGroup" and n.node_tree.name.startswith("AnalyticFog Surface Lights")]
    return sorted(n.label.split(": ", 1)[1] for b in bundles for n in b.nodes
                  if n.bl_idname == "ShaderNodeGroup" and n.label.startswith("Light "))


def add(**kw):
    """bpy.ops.fog.add; returns ("FINISHED"|"CANCELLED", [messages]) - errors raise in bpy.ops."""
    try:
        return sorted(bpy.ops.fog.add(**kw))[0], None
    except RuntimeError as e:
        return "CANCELLED", str(e)


def settings_and_presets(scene):
    s = scene.analytic_fog
    assert add(density=0.1)[0] == "FINISHED"
    s.visibility = 1000.0
    R["density_from_visibility_1km"] = s.density
    R["beta_after_visibility"] = beta_in_groups()
    s.scene_scale = 10.0
    R["beta_after_scale_10"] = beta_in_groups()
    s.scene_scale = 1.0
    s.color = (0.5, 0.7, 0.9)
    R["albedo_in_groups"] = list(bpy.data.node_groups["AnalyticFog Params"].nodes["Albedo"].outputs[0].default_value)
    bpy.ops.fog.preset_builtin(name="haze")
    R["haze_density"] = s.density
    R["haze_beta_in_groups"] = beta_in_groups()
    R["haze_anisotropy"] = [s.anisotropy, bpy.data.node_groups["AnalyticFog Params"]["analytic_fog_anisotropy"]]
    s.anisotropy = 0.0
    # a user preset through Blender's preset system: save, change, apply, remove
    s.density, s.color = 0.0123, (0.9, 0.8, 0.7)
    R["preset_add"] = sorted(bpy.ops.fog.preset_add(name="Harbour Fog"))[0]
    path = bpy.utils.preset_find("Harbour_Fog", "analytic_fog")
    R["preset_file"] = bool(path)
    s.density, s.color = 0.5, (1.0, 1.0, 1.0)
    bpy.ops.script.execute_preset(filepath=path, menu_idname="FOG_MT_presets")
    R["preset_restored"] = [s.density, list(s.color)]
    R["preset_beta_in_groups"] = beta_in_groups()
    bpy.types.FOG_MT_presets.bl_label = "Harbour Fog"   # what execute_preset sets: the active preset
    bpy.ops.fog.preset_add(remove_active=True)
    R["preset_removed"] = not bpy.utils.preset_find("Harbour_Fog", "analytic_fog")


def method_switch(scene):
    mats = snapshot()["materials"]
    scene.analytic_fog.method = "OSL"
    from fog_addon.nodes import groups
    from fog_addon.precompute.model import rungs
    osl = rungs.choose("osl")
    R["osl_script_nodes"] = sum(n.bl_idname == "ShaderNodeScript"
                                for g in (groups.light_group_name(osl), groups.background_group_name(osl))
                                for n in bpy.data.node_groups[g].nodes)
    R["node_groups_left_after_switch"] = sorted(g.name for g in bpy.data.node_groups
                                                if g.name.startswith("AnalyticFog Light"))
    R["osl_switch_on"] = scene.cycles.shading_system
    scene.analytic_fog.method = "NODES"
    R["osl_switch_restored"] = scene.cycles.shading_system
    R["materials_kept_by_method_switch"] = snapshot()["materials"] == mats


def anisotropy_switch(scene):
    """The panel's Anisotropy: g's models and tables replace the isotropic ones; a g the method can't serve
    is refused and changes nothing; back to 0 leaves no table or group of g behind."""
    mats = snapshot()["materials"]
    s = scene.analytic_fog

    def fog_names():
        return sorted([g.name for g in bpy.data.node_groups if g.name.startswith("AnalyticFog Light")]
                      + [i.name for i in bpy.data.images if i.name.startswith("AnalyticFog")])

    s.anisotropy = 0.85
    R["names_at_g085"] = fog_names()
    s.anisotropy = -0.9   # node groups: below rungs.MIN_TABLE_ANISOTROPY
    R["names_after_refused_g"] = fog_names()
    s.anisotropy = 0.0
    R["names_back_at_g0"] = fog_names()
    R["materials_kept_by_anisotropy"] = snapshot()["materials"] == mats


def lights_follow(scene):
    mats = snapshot()["materials"]
    R["lights_start"] = light_instances()
    lamp = bpy.data.objects.new("Extra", bpy.data.lights.new("Extra", "POINT"))
    lamp.data.energy = 200.0
    lamp.location = (1.0, 2.0, 3.0)
    scene.collection.objects.link(lamp)
    bpy.context.view_layer.update()
    R["lights_after_add"] = light_instances()
    lamp.hide_render = True
    bpy.context.view_layer.update()
    R["lights_after_hide"] = light_instances()
    lamp.hide_render = False
    lamp.data.type = "AREA"
    bpy.context.view_layer.update()
    R["lights_after_area"] = light_instances()
    lamp.data.type = "SUN"
    bpy.context.view_layer.update()
    R["lights_after_sun"] = light_instances()
    lamp.data.type = "POINT"
    lamp.data.analytic_fog.use = False
    bpy.context.view_layer.update()
    R["lights_after_toggle_off"] = light_instances()
    lamp.data.analytic_fog.use = True
    bpy.context.view_layer.update()
    R["lights_after_toggle_on"] = light_instances()
    bpy.data.objects.remove(lamp)
    bpy.context.view_layer.update()
    R["lights_after_delete"] = light_instances()
    R["materials_kept_by_light_changes"] = snapshot()["materials"] == mats


def bad_input(scene):
    before = snapshot()
    R["bad_density"] = {repr(d): add(density=d) for d in (float("nan"), float("inf"), 1e6)}
    cam = scene.camera
    scene.camera = None
    R["no_camera"] = add(density=0.1)
    scene.camera = cam
    cam.data.type = "ORTHO"
    R["ortho_camera"] = add(density=0.1)
    cam.data.type = "PERSP"
    R["unchanged_by_bad_input"] = snapshot() == before


def light_notes(scene):
    """Zero power, a sun under fog without a top, non-uniform scale: reported by name (warnings), fog still added."""
    from fog_addon.ops import apply
    dark = bpy.data.objects.new("Dark", bpy.data.lights.new("Dark", "POINT"))
    dark.data.energy = 0.0
    sun = bpy.data.objects.new("Sunny", bpy.data.lights.new("Sunny", "SUN"))
    squashed = bpy.data.objects.new("Squashed", bpy.data.lights.new("Squashed", "POINT"))
    squashed.scale = (1.0, 1.0, 3.0)
    for o in (dark, sun, squashed):
        scene.collection.objects.link(o)
    bpy.context.view_layer.update()
    from fog_addon.ops import report
    lights, notes = apply.fog_lights(scene)
    notes += report.daylight_notes(scene, apply.spec_of(scene), "nodes", lights)   # a sun: the fog's top decides
    R["light_notes"] = {name: why for name, why in notes}
    R["lights_taking_part"] = sorted(o.name for o in lights)
    for o in (dark, sun, squashed):
        bpy.data.objects.remove(o)


def selected_only(scene):
    bpy.ops.fog.remove()
    for o in scene.objects:
        o.select_set(False)
    target = next(o for o in scene.objects if o.type == "MESH" and o.active_material is not None)
    target.select_set(True)
    bpy.context.view_layer.objects.active = target
    assert add(density=0.1, selected_only="SELECTED")[0] == "FINISHED"
    from fog_addon.nodes.owned import is_fogged
    R["fogged_selected"] = sorted(m.name for m in bpy.data.materials if is_fogged(m))
    R["selected_materials"] = sorted(s.material.name for s in target.material_slots)
    bpy.ops.fog.remove()


def invisible_note():
    """A haze in a 10 m scene is invisible: the add warns (and still adds)."""
    from fog_addon.ops import apply
    from fog_addon.precompute.core import presets
    scene = bpy.context.scene
    R["invisible_note"] = any("invisible" in why for _, why in
                              apply.apply_fog(scene, presets.PRESETS["haze"]))
    R["visible_note_at_scale_1000"] = any("invisible" in why for _, why in
                                          apply.apply_fog(scene, presets.PRESETS["haze"], scene_scale=1000.0))
    apply.remove_fog(scene)


class FakeLayout:
    """Stands in for a UI layout (drawing needs a window): records every prop it is asked to draw."""

    def __init__(self, log):
        self.log = log

    def __getattr__(self, name):
        def call(*args, **kw):
            if name == "prop":
                getattr(args[0], args[1])   # a wrong property name raises here, as it would in the panel
                self.log.append(args[1])
            if name == "label":
                self.log.append("label: " + kw.get("text", ""))
            return FakeLayout(self.log)
        return call


def panel_draws(scene):
    """The World/sidebar panel and the light toggle draw without error, fog off and on."""
    from fog_addon import ui
    drawn = []
    ui.draw_fog(FakeLayout(drawn), bpy.context)
    add(density=0.1)
    scene.analytic_fog.method = "OSL"
    ui.draw_fog(FakeLayout(drawn), bpy.context)
    scene.analytic_fog.method = "NODES"
    lamp = next(o for o in scene.objects if o.type == "LIGHT")

    class Ctx:
        light = lamp.data
    panel = types.SimpleNamespace(layout=FakeLayout(drawn))
    ui.DATA_PT_analytic_fog_light.draw(panel, Ctx)
    R["panel_props"] = sorted(set(drawn))


def main():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    fog_addon.register()
    scene = bpy.context.scene
    spheres.build(scene)
    # Dense Fog off: the flow checks that settings reach the groups; its tables for each new anisotropy (the haze
    # preset's 0.7, the switch's 0.85: 20-60 s of bakes on a cold cache) are tests/test_bake_bounds.py's
    scene.analytic_fog.use_multiple_scattering = False
    settings_and_presets(scene)
    method_switch(scene)
    anisotropy_switch(scene)
    lights_follow(scene)
    bad_input(scene)
    light_notes(scene)
    selected_only(scene)
    invisible_note()
    panel_draws(scene)
    fog_addon.unregister()
    print(json.dumps(R))


if __name__ == "__main__":
    main()
