"""Operators: ``bpy.ops.fog.add`` and ``bpy.ops.fog.remove`` (both undoable)."""
import math

import bpy

from . import apply
from ..precompute import presets


class FOG_OT_add(bpy.types.Operator):
    """Add analytic fog to the scene: glows around point lights, fogged surfaces and background"""
    bl_idname = "fog.add"
    bl_label = "Add Fog"
    bl_options = {"REGISTER", "UNDO"}

    density: bpy.props.FloatProperty(name="Density", default=-1.0,
                                     description="Extinction coefficient in 1/m; negative keeps the scene's setting")
    preset: bpy.props.EnumProperty(
        name="Preset", default="NONE",
        items=[("NONE", "Scene Setting", "Keep the scene's density")]
        + [(k.upper(), k.replace("_", " ").title(), f"Visibility {v:g} m") for k, v in presets.VISIBILITY_M.items()])

    def execute(self, context):
        scene = context.scene
        settings = scene.analytic_fog
        density = settings.density
        if self.preset != "NONE":
            density = presets.PRESETS[self.preset.lower()]
        elif self.density >= 0 or math.isnan(self.density):
            density = self.density
        try:
            skipped = apply.apply_fog(scene, density, tuple(settings.color), settings.anisotropy,
                                      settings.method.lower())
        except ValueError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        settings.density = density
        settings.enabled = True
        for name, why in skipped:
            self.report({"WARNING"}, f"{name}: {why}")
        return {"FINISHED"}


class FOG_OT_remove(bpy.types.Operator):
    """Remove the analytic fog, restoring every material, light and world"""
    bl_idname = "fog.remove"
    bl_label = "Remove Fog"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        apply.remove_fog(context.scene)
        context.scene.analytic_fog.enabled = False
        return {"FINISHED"}


CLASSES = (FOG_OT_add, FOG_OT_remove)


def register():
    for c in CLASSES:
        bpy.utils.register_class(c)


def unregister():
    for c in reversed(CLASSES):
        bpy.utils.unregister_class(c)
