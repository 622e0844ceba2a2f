"""Operators: ``fog.add``, ``fog.remove`` (both undoable) and ``fog.preset_add`` (Blender's preset system)."""
import math

import bpy
from bl_operators.presets import AddPresetBase

from . import apply, progress
from ..precompute import presets

PRESET_SUBDIR = "analytic_fog"
PRESET_TITLES = {k: k.replace("_", " ").title() for k in (*presets.VISIBILITY_M, *presets.LAYERED)}


def _distance(m):
    return f"{m / 1000:g} km" if m >= 1000 else f"{m:g} m"


def _preset_items(key=lambda k: k):
    return [(key(k), PRESET_TITLES[k], f"Visibility {_distance(v)}") for k, v in presets.VISIBILITY_M.items()]


def _layer_text(key):
    """A layered preset's visibility and top, e.g. "200 m, top 100 m"."""
    layer = presets.LAYERED[key]
    return f"{_distance(presets.visibility_from_density(layer['density']))}, top {_distance(layer['fog_top'])}"


def _layered_items():
    return [(k, PRESET_TITLES[k], f"A fog layer: visibility {_layer_text(k)}") for k in presets.LAYERED]


def _report_skipped(op, skipped):
    for name, why in skipped:
        op.report({"WARNING"}, f"{name}: {why}")


class FOG_OT_add(bpy.types.Operator):
    """Add analytic fog to the scene (or update it): glows around point lights, fogged surfaces and background"""
    bl_idname = "fog.add"
    bl_label = "Add Fog"
    bl_options = {"REGISTER", "UNDO"}

    density: bpy.props.FloatProperty(name="Density", default=-1.0,
                                     description="Extinction coefficient in 1/m; negative keeps the scene's setting")
    preset: bpy.props.EnumProperty(
        name="Preset", default="NONE",
        items=[("NONE", "Scene Setting", "Keep the scene's density")]
        + _preset_items(str.upper))
    selected_only: bpy.props.EnumProperty(
        name="Materials", default="SCENE",
        items=[("SCENE", "Scene Setting", "As the scene's Selected Only setting"),
               ("ALL", "All", "Every material in the scene"),
               ("SELECTED", "Selected", "Only the selected objects' materials")])

    def execute(self, context):
        scene = context.scene
        settings = scene.analytic_fog
        only = settings.selected_only if self.selected_only == "SCENE" else self.selected_only == "SELECTED"
        objects = list(context.selected_objects) if only else None
        try:
            spec = apply.spec_of(scene)
            if self.preset != "NONE":
                spec = spec.replace(density=presets.PRESETS[self.preset.lower()])
            elif self.density >= 0 or math.isnan(self.density):
                spec = spec.replace(density=self.density)
            with progress.window_progress(context.window_manager) as report:
                skipped = apply.apply(scene, spec, objects, progress=report)
        except ValueError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        settings.enabled = True
        _report_skipped(self, skipped)
        lines = apply.explain()
        self.report({"INFO"}, lines[0])
        if len(lines) > 1 and lines[1].strip().startswith("Method"):
            self.report({"INFO"}, lines[1].strip())
        return {"FINISHED"}


class FOG_OT_remove(bpy.types.Operator):
    """Remove the analytic fog, restoring every material, light and world"""
    bl_idname = "fog.remove"
    bl_label = "Remove Fog"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        with progress.window_progress(context.window_manager) as report:
            apply.remove_fog(context.scene, progress=report)
        context.scene.analytic_fog.enabled = False
        return {"FINISHED"}


class FOG_OT_preset_builtin(bpy.types.Operator):
    """Set the fog's density from a visibility class of atmospheric optics, and its particles' anisotropy; a
    layered preset also sets the fog's top, its falloff and the air (the visibility classes keep them as they are)"""
    bl_idname = "fog.preset_builtin"
    bl_label = "Fog Preset"
    bl_options = {"REGISTER", "UNDO"}

    name: bpy.props.EnumProperty(
        name="Preset",
        items=_preset_items() + _layered_items())

    def execute(self, context):
        settings = context.scene.analytic_fog
        layer = presets.LAYERED.get(self.name)
        if layer is None:
            settings.density = presets.PRESETS[self.name]
            settings.color = (1.0, 1.0, 1.0)
            settings.anisotropy = presets.ANISOTROPY[self.name]
            return {"FINISHED"}
        settings.use_fog_top = True
        settings.fog_top = layer["fog_top"]
        settings.height_falloff = layer["height_falloff"]
        settings.air_density = layer["air"]
        settings.density = layer["density"]
        settings.color = layer["albedo"]
        settings.anisotropy = layer["anisotropy"]
        return {"FINISHED"}


class FOG_MT_presets(bpy.types.Menu):
    """Built-in presets (visibility classes, then fog layers), then the user's own (Blender's preset files)"""
    bl_label = "Fog Presets"
    preset_subdir = PRESET_SUBDIR
    preset_operator = "script.execute_preset"

    def draw(self, context):
        layout = self.layout
        for key, vis in presets.VISIBILITY_M.items():
            layout.operator(FOG_OT_preset_builtin.bl_idname,
                            text=f"{PRESET_TITLES[key]} ({_distance(vis)})").name = key
        layout.separator()
        for key in presets.LAYERED:
            layout.operator(FOG_OT_preset_builtin.bl_idname,
                            text=f"{PRESET_TITLES[key]} ({_layer_text(key)})").name = key
        layout.separator()
        bpy.types.Menu.draw_preset(self, context)


class FOG_OT_preset_add(AddPresetBase, bpy.types.Operator):
    """Save the fog's density, colour, anisotropy, top and air as a preset (or remove the active one)"""
    bl_idname = "fog.preset_add"
    bl_label = "Add Fog Preset"
    preset_menu = "FOG_MT_presets"
    preset_subdir = PRESET_SUBDIR
    preset_defines = ["fog = bpy.context.scene.analytic_fog"]
    preset_values = ["fog.density", "fog.color", "fog.anisotropy", "fog.use_fog_top", "fog.fog_top",
                     "fog.height_falloff", "fog.air_density"]


CLASSES = (FOG_OT_add, FOG_OT_remove, FOG_OT_preset_builtin, FOG_MT_presets, FOG_OT_preset_add)
register, unregister = bpy.utils.register_classes_factory(CLASSES)
