"""The depsgraph handler: the fog follows lights that are added, deleted, hidden, retyped or toggled,
and fog appended from another file is folded onto this file's shared copies.

Only the two scene groups are rebuilt (``apply.refresh_lights``), never the
materials.  Positions, power and colour are followed by drivers without it.
When the camera, lights or objects moved, the lights' models are chosen again
for the Quality (``ops/plan.choose_models``), RECHOOSE_DELAY_S after the scene
stopped changing (not while rendering: a render keeps the stored choice, as a
farm without the add-on does).  The Compositor method's windows (``view.windows``) grow at once by the
current frame's (and by each frame an animation plays or renders); they are computed over an animation's
range again before the file is saved.
"""
import bpy
from bpy.app.handlers import persistent

from .methods import compositor as compositor_method
from .nodes import comp_fog, compositor, dedupe, preview, preview_sampled
from . import sunsky, view
from .ops import apply


def _merge_appended():
    """Timer callback: data-blocks are not removed from inside a depsgraph handler."""
    for name, why in apply.merge_appended():
        print(f"Analytic Fog: {name} {why}")
    scene = bpy.context.scene
    if scene is not None and scene.analytic_fog.enabled:
        apply.refresh_lights(scene)


RECHOOSE_DELAY_S = 0.5
_refreshing = []   # non-empty while the depsgraph handler refreshes the fog (it must not run inside itself)
_choosing = []   # non-empty while the timer re-chooses (its frame changes must not schedule it again)


def _rechoose():
    """Timer callback: choose every light's models again from the view, once the scene is still."""
    scene = bpy.context.scene
    if scene is None or not scene.analytic_fog.enabled:
        return None
    if bpy.app.is_job_running("RENDER"):
        return RECHOOSE_DELAY_S
    _choosing.append(True)
    try:
        apply.refresh_lights(scene, rechoose=True, this_frame=True)   # (the windows: at saving, over the range)
    finally:
        _choosing.clear()
    return None


def _schedule_rechoose():
    if bpy.app.timers.is_registered(_rechoose):
        bpy.app.timers.unregister(_rechoose)
    bpy.app.timers.register(_rechoose, first_interval=RECHOOSE_DELAY_S)


@persistent
def on_depsgraph_update(scene, depsgraph):
    apply.scene_changed()   # the panel's notes are computed again at its next redraw
    settings = getattr(scene, "analytic_fog", None)
    if settings is None or not settings.enabled or _choosing:
        return
    if depsgraph.id_type_updated("NODETREE") and dedupe.pending():
        if not bpy.app.timers.is_registered(_merge_appended):
            bpy.app.timers.register(_merge_appended, first_interval=0.0)
        return
    if _refreshing:   # the refresh's own depsgraph evaluation (the shadow maps' meshes) updates again
        return
    if any(depsgraph.id_type_updated(t) for t in ("OBJECT", "LIGHT", "SCENE", "COLLECTION")):
        _refreshing.append(True)
        try:
            apply.refresh_lights(scene, this_frame=True)
        finally:
            _refreshing.clear()
        if not bpy.app.is_job_running("RENDER"):
            _schedule_rechoose()


@persistent
def on_frame_change(scene, *_):
    """Each frame of an animation that plays or renders: the windows grow by the frame's (``apply.grow_windows``)."""
    settings = getattr(scene, "analytic_fog", None)
    if settings is not None and settings.enabled and not view.sampling_frames():
        apply.grow_windows(scene)


@persistent
def on_save_pre(*_):
    """A saved file renders on a farm without the add-on: its windows hold every frame of the range (computed
    again if they were grown by single frames since: stepping through the frames costs seconds in a big scene),
    and the atlases of the shafts' maps of an animation hold every frame's (baked again if a frame change found one
    out of date, or the range changed: ``methods.compositor.complete_shadows``), the sun's too (the fog is rebuilt
    where its atlas is due: ``sunsky.sun_atlas_due``)."""
    scene = bpy.context.scene
    settings = getattr(scene, "analytic_fog", None)
    if settings is not None and settings.enabled and sunsky.sun_atlas_due(scene, apply.usable_spec(scene)):
        apply.refresh_lights(scene, rebuild=True)
    elif settings is not None and settings.enabled and comp_fog.windows_partial():
        apply.refresh_lights(scene)
    if settings is not None and settings.enabled:
        compositor_method.complete_shadows(scene, apply.usable_spec(scene))
        compositor.follow_passes_directory(scene)   # (and writes the fog passes beside its output)
    preview.before_save()   # a farm renders the file as F12 does: without the viewport's preview
    preview_sampled.pack_table()


@persistent
def on_render_pre(scene=None, *_):
    """A final render (each frame of an animation): the viewport's preview off (``nodes/preview.py``), the
    Compositor method's fog passes written beside the render's output (``compositor.follow_passes_directory``)."""
    preview.before_render()
    scene = scene if isinstance(scene, bpy.types.Scene) else bpy.context.scene
    settings = getattr(scene, "analytic_fog", None)
    if settings is not None and settings.enabled:
        compositor.follow_passes_directory(scene)


@persistent
def on_preview_back(*_):
    """A render ended or was cancelled, the file was saved or opened: the preview as the session has it."""
    preview.after_render()


HANDLERS = (("depsgraph_update_post", on_depsgraph_update), ("save_pre", on_save_pre),
            ("frame_change_post", on_frame_change), ("render_pre", on_render_pre),
            ("render_complete", on_preview_back), ("render_cancel", on_preview_back), ("save_post", on_preview_back),
            ("load_post", on_preview_back))


def register():
    for name, fn in HANDLERS:
        if fn not in getattr(bpy.app.handlers, name):
            getattr(bpy.app.handlers, name).append(fn)
    preview.after_render()


def unregister():
    for name, fn in HANDLERS:
        while fn in getattr(bpy.app.handlers, name):
            getattr(bpy.app.handlers, name).remove(fn)
    preview.show(False)
    for timer in (_merge_appended, _rechoose):
        if bpy.app.timers.is_registered(timer):
            bpy.app.timers.unregister(timer)
