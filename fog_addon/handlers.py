"""The depsgraph handler: the fog follows lights that are added, deleted, hidden, retyped or toggled,
and fog appended from another file is folded onto this file's shared copies.

Only the two scene groups are rebuilt (``apply.refresh_lights``), never the
materials.  Positions, power and colour are followed by drivers without it.
"""
import bpy
from bpy.app.handlers import persistent

from .nodes import dedupe
from .ops import apply


def _merge_appended():
    """Timer callback: data-blocks are not removed from inside a depsgraph handler."""
    for name, why in apply.merge_appended():
        print(f"Analytic Fog: {name} {why}")
    scene = bpy.context.scene
    if scene is not None and scene.analytic_fog.enabled:
        apply.refresh_lights(scene)


@persistent
def on_depsgraph_update(scene, depsgraph):
    settings = getattr(scene, "analytic_fog", None)
    if settings is None or not settings.enabled:
        return
    if depsgraph.id_type_updated("NODETREE") and dedupe.pending():
        if not bpy.app.timers.is_registered(_merge_appended):
            bpy.app.timers.register(_merge_appended, first_interval=0.0)
        return
    if any(depsgraph.id_type_updated(t) for t in ("OBJECT", "LIGHT", "SCENE", "COLLECTION")):
        apply.refresh_lights(scene)


def register():
    if on_depsgraph_update not in bpy.app.handlers.depsgraph_update_post:
        bpy.app.handlers.depsgraph_update_post.append(on_depsgraph_update)


def unregister():
    while on_depsgraph_update in bpy.app.handlers.depsgraph_update_post:
        bpy.app.handlers.depsgraph_update_post.remove(on_depsgraph_update)
    if bpy.app.timers.is_registered(_merge_appended):
        bpy.app.timers.unregister(_merge_appended)
