"""The depsgraph handler: the fog follows lights that are added, deleted, hidden, retyped or toggled.

Only the two scene groups are rebuilt (``apply.refresh_lights``), never the
materials.  Positions, power and colour are followed by drivers without it.
"""
import bpy
from bpy.app.handlers import persistent

from .ops import apply


@persistent
def on_depsgraph_update(scene, depsgraph):
    settings = getattr(scene, "analytic_fog", None)
    if settings is None or not settings.enabled:
        return
    if any(depsgraph.id_type_updated(t) for t in ("OBJECT", "LIGHT", "SCENE", "COLLECTION")):
        apply.refresh_lights(scene)


def register():
    if on_depsgraph_update not in bpy.app.handlers.depsgraph_update_post:
        bpy.app.handlers.depsgraph_update_post.append(on_depsgraph_update)


def unregister():
    while on_depsgraph_update in bpy.app.handlers.depsgraph_update_post:
        bpy.app.handlers.depsgraph_update_post.remove(on_depsgraph_update)
