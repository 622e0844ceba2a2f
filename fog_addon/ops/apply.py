"""Adding and removing the fog on a scene, and the ops layer's entry points: what the operators, the handlers,
the command line and scripts call.

``apply`` stores the spec, wraps the materials and the World around the fog's shared groups and builds them
(``build.py``, for the plan of ``plan.py``); ``remove_fog`` takes every piece off again.  The rest of the entry
points are handed on from the modules that hold them: following changes (``sync.py``), the plan (``plan.py``), what
the fog tells the user (``report.py``) and the build (``build.py``).
"""
import json

import bpy

from .. import methods, shadow_maps, sunsky
from ..nodes import comp_fog, compositor, dedupe, groups, images, osl, passes, preview, preview_sampled, surface_group
from ..nodes.light import unwrap_light
from ..nodes.material import unwrap_material, wrap_material
from ..nodes.world import unwrap_world, wrap_world
from ..precompute.model import capabilities
from ..precompute.core import spec as spec_
from ..precompute.core.spec import FogSpec
from ..props import spec_of, store_spec
from . import progress as progress_
from .build import (AOV_KINDS, SPEC_KEY, TablesMissing, build_scene_groups, follow_compositor, missing_tables,
                    rebuilt, use_osl)
from .plan import (SUPPORTED_LIGHTS, built_method, check_method, choose_models, fog_lights, scene_materials,
                   stored_choice)
from .report import (CAVEATS_KEY, explain, left_out_lines, limit_text, method_line, not_modelled, panel_notes,
                     quality_head, scene_changed, scene_notes, stored_caveats)
from .sync import (accept_bake, bake_declined, decline_bake, grow_windows, refresh_lights, set_anisotropy,
                   set_method, set_passes, set_quality, settings_error, sync, sync_error, update_params, usable_spec)

__all__ = [   # the entry points
    "apply", "apply_fog", "check_camera", "merge_appended", "remove_fog",
    "spec_of", "store_spec",
    "AOV_KINDS", "SPEC_KEY", "TablesMissing", "build_scene_groups", "follow_compositor", "missing_tables", "rebuilt",
    "use_osl",
    "SUPPORTED_LIGHTS", "built_method", "check_method", "choose_models", "fog_lights", "scene_materials",
    "stored_choice",
    "CAVEATS_KEY", "explain", "left_out_lines", "limit_text", "method_line", "not_modelled", "quality_head", "scene_notes",
    "stored_caveats", "panel_notes", "scene_changed",
    "accept_bake", "bake_declined", "decline_bake", "grow_windows", "refresh_lights", "set_anisotropy", "set_method",
    "set_passes", "set_quality", "settings_error", "sync", "sync_error", "update_params", "usable_spec",
]


def check_camera(camera):
    """Raise ValueError unless ``camera`` can see analytic fog (a perspective or panoramic camera)."""
    if camera is None:
        raise ValueError("the scene has no camera: set one (Scene properties > Camera), then add the fog")
    if camera.type != "CAMERA":
        raise ValueError(f"the scene camera {camera.name!r} is not a camera object")
    if camera.data.type == "ORTHO":
        raise ValueError(f"camera {camera.name!r} is orthographic: the fog model needs rays from one point "
                         "(a perspective camera)")


def merge_appended():
    """Fold fog data appended from another fogged file onto this file's copies (``dedupe``).

    Returns [(name, reason)] notes for objects the other file's drivers pulled in.
    """
    _, pulled = dedupe.merge_duplicates()
    return [(name, "came in with fog appended from another file (its drivers' target); delete it if unwanted")
            for name in pulled]


def apply(scene, spec, objects=None, progress=progress_.silent):
    """Add (or update) the fog of ``spec`` (a ``FogSpec``) on ``scene``; adding twice is the same as once.

    The spec is stored in ``scene.analytic_fog`` (the one store of the fog's settings); then the lights
    taking part are found, the method resolved (``spec.method`` "auto": ``methods/auto.py`` chooses),
    checked, planned (each light's models for the Quality) and built.  ``objects``: fog only their
    materials (default: all in the scene).  Returns a list of (data-block name, reason) for what was left
    out or fogged with a caveat.  Raises ValueError for bad settings before anything is changed.
    ``progress(stage, done, total)`` is called as the work advances (``progress.py``).
    """
    spec = spec.validated()
    check_camera(scene.camera)
    _evaluate(scene)
    lights, notes = fog_lights(scene)
    method, reason = methods.resolve(scene, spec, lights, scene_materials(scene, objects))
    check_method(scene, spec, method)
    store_spec(scene, spec)
    spec = spec_of(scene)   # as stored (float32 properties): what every later refresh builds for
    progress("appended fog", 0, 1)
    skipped = merge_appended()   # first: the tables and groups are looked up by name below
    skipped += notes
    progress("lights and tables", 0, 1)
    groups.set_params(spec.beta_per_unit, spec.albedo, spec.anisotropy, world_light=spec.world_light,
                          preview=preview.working())
    if bpy.data.node_groups.get(groups.SURFACE) is None:
        # The materials are wrapped around a Surface group without lights, which the lights' group then
        # replaces (``groups.install``): every node Blender's API adds to a material costs more the
        # bigger the groups it links (1 000 materials, 64 lights: 25.9 -> 16.1 s CPU,
        # benchmarks/apply_order.py).
        surface_group.build_surface([], [], images.all_table_images(spec.anisotropy), spec.passes)
    mats = scene_materials(scene, objects)
    for k, mat in enumerate(mats):
        progress("materials", k, len(mats))
        why = wrap_material(mat)
        if why:
            skipped.append((mat.name, why))
    progress("materials", len(mats), len(mats))
    progress("world", 0, 1)
    skipped += build_scene_groups(scene, spec, lights, method, reason, progress=progress)
    if scene.world is None:
        skipped.append((scene.name, "has no World: no airlight on the background"))
    else:
        why = wrap_world(scene.world)
        if why:
            skipped.append((scene.world.name, why))
    skipped += follow_compositor(scene, rebuild=True)   # Cycles' denoiser kept off the fog's light
    if not lights and not sunsky.is_daylit(scene, spec):
        skipped.append((scene.name, "has no light taking part: the fog only dims"
                        + (" (and the glowing objects glow)"
                           if capabilities.can(getattr(method, "name", method), "emitters", scene.render.engine)
                           and methods.compositor.glowing_objects(scene) else "")
                        + ("" if spec.layered or spec.world_light or spec.density <= 0.0 else
                           ", and the World is hidden behind it (the fog fills all space), so the picture is dark: "
                           "add a light, turn on World Light, or give the fog a top (Fog Top)")))
    skipped += [(scene.name, note) for note in scene_notes(scene, spec)]
    notes = not_modelled(scene, spec, lights, mats, method)
    surface = bpy.data.node_groups[groups.SURFACE]
    surface[CAVEATS_KEY] = json.dumps(notes)
    return skipped + [(scene.name, n) for n in notes]


def _evaluate(scene):
    """Bring the objects' world matrices up to date (a script that made or moved objects and adds fog at once: the
    lights' positions and the camera's are read from them, not from drivers)."""
    layer = bpy.context.view_layer if bpy.context.scene == scene else scene.view_layers[0]
    layer.update()


def apply_fog(scene, density, albedo=(1.0, 1.0, 1.0), anisotropy=0.0, method="nodes", objects=None,
              scene_scale=1.0, with_passes=False, error=spec_.DEFAULT_QUALITY, world_light=False, shafts=True,
              multiple_scattering=False, fog_top=None, height_falloff=0.0, progress=progress_.silent):
    """``apply`` with the spec's fields as arguments, for scripts: ``density`` (1/m), ``albedo``, ``anisotropy``
    (g), ``method`` ("auto", "nodes", "osl", "compositor"), ``scene_scale`` (m per unit), ``with_passes``,
    ``error`` (the Quality: a preset name or a target error; None is Exact), ``world_light``, ``shafts``,
    ``multiple_scattering`` (Dense Fog), ``fog_top`` (m above the ground, None: fog fills all space) and
    ``height_falloff`` (m).  This function's defaults are a single-scattering fog by the node groups
    (the probes' and tests' models); a ``FogSpec``'s, the panel's and the command line's are Auto and Dense Fog by
    the Quality.  See ``precompute/core/spec.py``."""
    spec = FogSpec(density=density, scene_scale=scene_scale, albedo=tuple(albedo), anisotropy=anisotropy,
                   method=method, quality=error, passes=with_passes, world_light=world_light, shafts=shafts,
                   multiple_scattering=multiple_scattering, fog_top=fog_top, height_falloff=height_falloff)
    return apply(scene, spec, objects, progress)


def remove_fog(scene, progress=progress_.silent):
    """Take the fog out of every material, light and world, and delete its node groups and tables."""
    mats = list(bpy.data.materials)
    for k, mat in enumerate(mats):
        progress("materials", k, len(mats))
        unwrap_material(mat)
    progress("materials", len(mats), len(mats))
    progress("world", 0, 1)
    for world in bpy.data.worlds:
        unwrap_world(world)
        if sunsky.PROBE_KEY in world:   # the sky's mean colour, kept for the fog layer
            del world[sunsky.PROBE_KEY]
    progress("lights", 0, 1)
    for light in bpy.data.lights:
        unwrap_light(light)
    for s in bpy.data.scenes:   # first: the compositor's chains use the fog's compositor groups
        compositor.teardown(s)
    for name in comp_fog.all_group_names() + groups.all_group_names():
        ng = bpy.data.node_groups.get(name)
        if ng is not None:
            bpy.data.node_groups.remove(ng)
    for name in images.table_names() + [preview_sampled.TABLE]:
        img = bpy.data.images.get(name)
        if img is not None:
            bpy.data.images.remove(img)
    shadow_maps.remove_unused()
    for name in osl.text_names():
        text = bpy.data.texts.get(name)
        if text is not None:
            bpy.data.texts.remove(text)
    use_osl(scene, False)
    for s in bpy.data.scenes:
        passes.remove_view_layer_aovs(s, AOV_KINDS)
