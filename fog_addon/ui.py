"""The "Analytic Fog" panel in Properties > World and the 3D viewport sidebar, and each light's toggle."""
import bpy

from .methods.node_groups import MANY_LIGHTS
from .ops import apply
from .ops.operators import FOG_MT_presets
from .precompute.model import capabilities, rungs

ENGINE_NOTES = {
    "AUTO": "Auto: Node Groups or Compositor, per scene",
    "NODES": "Node groups: Cycles and EEVEE",
    "OSL": "OSL: Cycles only (EEVEE shows no glow)",
    "COMPOSITOR": "Compositor: Cycles and EEVEE, Compositing on",
}


MAX_LISTED = 12   # lights listed by name in the panel; the rest are counted


def _draw_models(layout, settings):
    """The Quality, and the models each light got with the error they are predicted to make."""
    col = layout.column()
    col.use_property_split = True
    col.prop(settings, "quality")
    if settings.quality == "CUSTOM":
        col.prop(settings, "target_error")
    box = layout.box()
    choice = apply.stored_choice() if settings.enabled else None
    preference = settings.method.lower() if settings.method != "AUTO" else (choice or {}).get("method", "nodes")
    full = rungs.choose(preference)
    box.label(text="Full models: " + ", ".join(f"{r.name} ({r.predicted_error():.0e})" for r in full[:3]))
    if choice is None:
        box.label(text="Add the fog to see each light's models")
        return
    if (line := apply.method_line(choice)) is not None:
        for i, part in enumerate(line.split(" (", 1)):
            box.label(text=part if i == 0 else "(" + part, icon="SETTINGS" if i == 0 else "BLANK1")
    box.label(text=apply.quality_head(choice))
    if (limit := apply.limit_text(choice)) is not None:   # EEVEE's uniform block: a warning of its own
        box.label(text=limit[0].upper() + limit[1:], icon="ERROR")
    left_out = apply.left_out_lines(choice)
    for line in left_out:   # what the picture lacks, the largest first
        box.label(text=line, icon="INFO")
    lines = apply.explain(choice)
    cheaper = [line for line in lines[1:] if not line.endswith(": full") and not line.strip().startswith("Method")
               and line.strip() not in left_out]
    for line in cheaper[:MAX_LISTED]:
        box.label(text=line.strip(), icon="DOT")
    if len(cheaper) > MAX_LISTED:
        box.label(text=f"... and {len(cheaper) - MAX_LISTED} more lights with cheaper models")
    full = sum(1 for name, (step, _) in choice["lights"].items() if step == 0 and name not in choice.get("rims", {}))
    box.label(text=f"{full} light(s) fully modelled")


def _draw_layer(col, settings):
    """Fog Top: the checkbox with the top's height beside it, then the falloff, the ground and the clear air under
    it (greyed out without a top: they act only in a layer)."""
    row = col.row(heading="Fog Top")
    row.prop(settings, "use_fog_top", text="")
    sub = row.row()
    sub.enabled = settings.use_fog_top
    sub.prop(settings, "fog_top", text="")
    sub = col.column()
    sub.active = settings.use_fog_top
    sub.prop(settings, "height_falloff")
    sub.prop(settings, "ground_level")
    sub.prop(settings, "air_density")


def draw_fog(layout, context):
    scene = context.scene
    s = scene.analytic_fog
    if s.enabled and (why := apply.sync_error(scene)) is not None:
        box = layout.box()
        box.label(text="The fog keeps what it was built with:", icon="ERROR")
        box.label(text=why, icon="BLANK1")
    elif not s.enabled and (why := apply.settings_error(scene)) is not None:
        box = layout.box()
        box.label(text="Add Fog will refuse these settings:", icon="ERROR")
        box.label(text=why, icon="BLANK1")
    row = layout.row(align=True)
    if s.enabled:
        row.operator("fog.add", text="Update Fog", icon="FILE_REFRESH")
        row.operator("fog.remove", text="", icon="X")
    else:
        row.operator("fog.add", text="Add Fog", icon="ADD")
    row = layout.row(align=True)
    row.menu(FOG_MT_presets.__name__, text=FOG_MT_presets.bl_label)
    row.operator("fog.preset_add", text="", icon="ADD")
    row.operator("fog.preset_add", text="", icon="REMOVE").remove_active = True
    col = layout.column()
    col.use_property_split = True
    col.prop(s, "visibility")
    col.prop(s, "density")
    col.prop(s, "color")
    col.prop(s, "anisotropy")
    col.prop(s, "scene_scale")
    _draw_layer(col, s)
    col.prop(s, "method")
    col.label(text=ENGINE_NOTES[s.method], icon="INFO")
    if s.method != "AUTO" and not capabilities.runs(s.method.lower(), scene.render.engine):
        col.label(text=f"Switch the render engine to Cycles to see {s.method.title()} fog", icon="ERROR")
    col.prop(s, "selected_only")
    row = col.row()
    row.active = not s.use_fog_top   # with a Fog Top the World always lights surfaces, through the layer
    row.prop(s, "world_light")
    col.prop(s, "use_shafts")
    col.prop(s, "use_multiple_scattering")
    col.prop(s, "use_passes")
    _draw_models(layout, s)
    try:
        notes = apply.panel_notes(scene, apply.spec_of(scene))
    except ValueError:   # (said above)
        notes = []
    for note in notes:
        box = layout.box()
        for i, line in enumerate(note.replace(": ", ". ").split(". ")):
            box.label(text=line, icon="ERROR" if i == 0 else "BLANK1")
    for note in apply.stored_caveats() if s.enabled else ():
        box = layout.box()
        head, _, rest = note.partition(": ")
        box.label(text=head[0].upper() + head[1:], icon="ERROR")
        box.label(text=rest, icon="BLANK1")
    lights, notes = apply.fog_lights(scene)
    layout.label(text=f"{len(lights)} light(s) light the fog", icon="LIGHT_POINT")
    if (len(lights) >= MANY_LIGHTS and s.method != "AUTO"
            and not capabilities.can(s.method.lower(), "per_pixel_lights", scene.render.engine)):
        layout.label(text="With this many lights the Compositor method renders far faster", icon="INFO")
    for name, why in notes:
        layout.label(text=f"{name}: {why}", icon="ERROR")


class _FogPanel:
    bl_label = "Analytic Fog"

    def draw(self, context):
        draw_fog(self.layout, context)


class WORLD_PT_analytic_fog(_FogPanel, bpy.types.Panel):
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "world"


class VIEW3D_PT_analytic_fog(_FogPanel, bpy.types.Panel):
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Fog"


class DATA_PT_analytic_fog_light(bpy.types.Panel):
    bl_label = "Analytic Fog"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "data"

    @classmethod
    def poll(cls, context):
        return context.light is not None

    def draw(self, context):
        light = context.light
        self.layout.prop(light.analytic_fog, "use")
        if light.type not in apply.SUPPORTED_LIGHTS:
            self.layout.label(text=f"{light.type.title()} lights don't light the fog yet", icon="INFO")


CLASSES = (WORLD_PT_analytic_fog, VIEW3D_PT_analytic_fog, DATA_PT_analytic_fog_light)
register, unregister = bpy.utils.register_classes_factory(CLASSES)
