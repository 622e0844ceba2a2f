"""Operators: ``fog.add``, ``fog.remove`` (both undoable), ``fog.bake_tables`` and ``fog.preset_add`` (Blender's
preset system).

A build that needs a Dense Fog table not yet baked (``apply.missing_tables``) bakes it first on a worker thread
(``bake_job``) when there is a window: the status bar says what is baking and how long is left, the progress
cursor follows it, and Esc cancels it with nothing changed.  Without a window (scripts, ``-b``) the bake runs in
line, announced on the console (``progress.ConsoleProgress``).
"""
import math

import bpy
from bl_operators.presets import AddPresetBase

from . import apply, bake_job, progress
from .. import props
from ..precompute.core import presets

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


class _BakesFirst:
    """Mixin of the operators that bake missing tables first (``invoke``): ``modal`` polls the ``BakeJob`` each
    timer tick, Esc cancels it; once nothing is left to bake it calls ``after_bake(context)``."""
    _job = _timer = None

    def missing(self, context):
        """The tables still to bake for the build this operator does (``apply.missing_tables``)."""
        return apply.missing_tables(context.scene, apply.spec_of(context.scene))

    def start_bakes(self, context):
        """Start the bake of what ``missing`` lists and go modal; None if nothing is missing (or no window)."""
        if context.window is None:
            return None
        try:
            tables = self.missing(context)
        except ValueError:
            return None   # the build itself says why
        if not tables:
            return None
        self._job = bake_job.BakeJob(tables, apply.spec_of(context.scene).anisotropy).start()
        wm = context.window_manager
        self._timer = wm.event_timer_add(0.2, window=context.window)
        wm.modal_handler_add(self)
        wm.progress_begin(0.0, 1.0)
        context.workspace.status_text_set(self._job.status())
        return {"RUNNING_MODAL"}

    def _end(self, context):
        wm = context.window_manager
        wm.event_timer_remove(self._timer)
        wm.progress_end()
        context.workspace.status_text_set(None)

    def modal(self, context, event):
        job = self._job
        if event.type == "ESC" and event.value == "PRESS":
            job.cancel()
        if event.type != "TIMER" and not job.done:
            return {"PASS_THROUGH"}
        if not job.done:
            context.window_manager.progress_update(job.overall())
            context.workspace.status_text_set(job.status())
            return {"RUNNING_MODAL"}
        self._end(context)
        if job.cancelled or job.error:
            why = apply.decline_bake(context.scene, job.current, job.error)
            self.report({"WARNING"} if job.cancelled else {"ERROR"}, why)
            return {"CANCELLED"}
        restarted = self.start_bakes(context)   # the lights' tables, once the point table let them be chosen
        return restarted if restarted is not None else self.after_bake(context)


class FOG_OT_add(_BakesFirst, bpy.types.Operator):
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

    def invoke(self, context, event):
        apply.accept_bake(context.scene)   # asked for by the user: a bake declined before is started again
        return self.start_bakes(context) or self.execute(context)

    def after_bake(self, context):
        return self.execute(context)

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


class FOG_OT_bake_tables(_BakesFirst, bpy.types.Operator):
    """Bake the Dense Fog tables the fog's settings need (Esc cancels), then let the fog follow the settings"""
    bl_idname = "fog.bake_tables"
    bl_label = "Bake Fog Tables"

    level: bpy.props.StringProperty(name="Sync Level", default="rechoose",
                                    description="What the fog rebuilds once the tables are baked (props.SYNC_LEVELS)")

    def invoke(self, context, event):
        return self.start_bakes(context) or self.after_bake(context)

    def after_bake(self, context):
        if context.scene.analytic_fog.enabled:
            why = apply.sync(context.scene, self.level)
            if why:
                self.report({"WARNING"}, why)
        return {"FINISHED"}

    def execute(self, context):
        """Without a window: bake in line (announced on the console), then sync."""
        for table, seconds in self.missing(context):
            bake_job.bakers.table_array(table, apply.spec_of(context.scene).anisotropy,
                                        progress=progress.ConsoleProgress(prefix="Analytic Fog: ").bake(
                                            bake_job.bakers.label(table), seconds))
        return self.after_bake(context)


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


def sync_in_window(scene, level):
    """The settings' timer (``props.set_sync``): a change that needs Dense Fog tables not yet baked (Dense Fog
    turned on, a new anisotropy) bakes them first with the cancellable ``fog.bake_tables`` in a window showing
    ``scene``, which then syncs at ``level``; anything else syncs at once (``apply.sync``).  A bake declined
    (cancelled) for these very settings is not started again: the panel says so (``apply.sync_error``)."""
    if level != "params" and not bake_job.running() and not apply.bake_declined(scene):
        for window in bpy.context.window_manager.windows:
            if window.scene == scene:
                with bpy.context.temp_override(window=window, scene=scene):
                    bpy.ops.fog.bake_tables("INVOKE_DEFAULT", level=level)   # it syncs, at once if nothing is missing
                return
    if not bake_job.running():
        apply.sync(scene, level)


CLASSES = (FOG_OT_add, FOG_OT_bake_tables, FOG_OT_remove, FOG_OT_preset_builtin, FOG_MT_presets, FOG_OT_preset_add)
_register, unregister = bpy.utils.register_classes_factory(CLASSES)


def register():
    _register()
    props.set_sync(apply.sync, sync_in_window)
