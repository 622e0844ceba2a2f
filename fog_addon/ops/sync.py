"""The fog following the scene: its settings' changes (``sync``, the ``set_*`` of scripts), the depsgraph and
frame handlers' refreshes (``refresh_lights``, ``grow_windows``) and a Dense Fog bake the user cancelled.

A sync that fails leaves the fog as it was built; why is kept for the panel (``sync_error``).  Materials are never
rebuilt here: only the shared node groups.
"""
import traceback

import bpy

from .. import props
from ..nodes import groups, preview
from ..precompute.model import bakers
from ..precompute.core.spec import FogSpec, validate_quality
from ..props import spec_of, store_spec
from . import progress as progress_
from .build import SPEC_KEY, TablesMissing, build_scene_groups, follow_compositor, rebuilt
from .plan import built_method, check_method, fog_lights, lights_in_groups, resolve_method, stored_choice

_sync_errors = {}   # scene name -> why the last sync failed (the panel shows it), absent if it succeeded
_handler_errors = {}   # scene name -> what the handlers said last (a refusal or a fault), cleared once mended
_declined = {}   # scene name -> the spec (JSON) whose bake the user cancelled (``decline_bake``)


def sync(scene, level="groups"):
    """Make the fog follow the scene's settings (``spec_of``): the params group, and at ``level`` "groups" or
    "rechoose" the scene groups (materials are not touched).  A failure (a setting the method can't serve)
    changes nothing, and is kept for the panel (``sync_error``) and returned."""
    try:
        spec = spec_of(scene)
        surface = bpy.data.node_groups.get(groups.SURFACE)
        if surface is not None and surface.library is not None:
            return None
        if spec.layered and level == "params":   # the layer's fog light is baked for the density and the top
            level = "groups"
        if level != "params" and surface is not None:
            lights = fog_lights(scene)[0]
            method, reason = resolve_method(scene, spec, lights)
            check_method(scene, spec, method)
            groups.set_params(spec.beta_per_unit, spec.albedo, spec.anisotropy, world_light=spec.world_light,
                              preview=preview.working())
            build_scene_groups(scene, spec, lights, method, reason, rechoose=level == "rechoose",
                               progress=progress_.ConsoleProgress(prefix="Analytic Fog: "))
            follow_compositor(scene, rebuild=True)
        else:
            groups.set_params(spec.beta_per_unit, spec.albedo, world_light=spec.world_light,
                              preview=preview.working())
    except ValueError as e:
        _sync_errors[scene.name] = str(e)
        print(f"Analytic Fog: the fog keeps what it was built with: {e}")
        return str(e)
    except Exception as e:   # noqa: BLE001 - a fault of the add-on's: said, and the user's compositor spliced again
        why = f"the fog could not follow this change ({type(e).__name__}: {e}); Update Fog rebuilds it"
        _sync_errors[scene.name] = why
        traceback.print_exc()
        try:
            follow_compositor(scene, rebuild=True)
        except Exception:   # noqa: BLE001
            traceback.print_exc()
        return why
    _sync_errors.pop(scene.name, None)
    return None


def _handler_error(scene, why):
    _sync_errors[scene.name] = _handler_errors[scene.name] = why


def sync_error(scene):
    """Why the fog could not follow the scene's last settings change, or None."""
    return _sync_errors.get(scene.name)


def settings_error(scene):
    """Why the scene's fog settings can't be used (``spec_of``'s message: the operator's for the same values), or
    None.  The panel shows it before the fog is added (after, ``sync_error`` says it)."""
    try:
        spec_of(scene)
    except ValueError as e:
        return str(e)
    return None


def usable_spec(scene):
    """The scene's settings as a spec (``spec_of``), or None while they can't be used (``settings_error`` says
    why): the fog keeps what it was built with."""
    try:
        return spec_of(scene)
    except ValueError:
        return None


def update_params(scene):
    """Push the scene's density, colour, scale and World Light into the shared params group."""
    return sync(scene, "params")


def set_anisotropy(scene, g):
    """Set the anisotropy and follow it: the lights keep their steps, now with g's models (materials are not
    touched).  Raises ValueError, changing nothing, for a g outside the range or one the method's models
    don't serve."""
    _set_and_sync(scene, anisotropy=g)


def set_method(scene, method):
    """Set the method and follow it: the lights keep their steps, now with ``method``'s models."""
    _set_and_sync(scene, method=method)


def set_passes(scene, with_passes):
    """Switch the fog passes on or off and follow it (materials are not touched)."""
    _set_and_sync(scene, passes=bool(with_passes))


def set_quality(scene, quality):
    """Set the Quality and choose every light's models again (materials are not touched)."""
    _set_and_sync(scene, "rechoose", quality=validate_quality(quality))


def _set_and_sync(scene, level="groups", **changes):
    """Store ``changes`` to the scene's spec and sync; raises ValueError (the settings kept) if it fails."""
    old = spec_of(scene)
    new = old.replace(**changes)
    surface = bpy.data.node_groups.get(groups.SURFACE)
    if surface is not None:
        lights = fog_lights(scene)[0]
        check_method(scene, new, resolve_method(scene, new, lights)[0])
    store_spec(scene, new)
    why = sync(scene, level)
    if why is not None:
        store_spec(scene, old)
        raise ValueError(why)


def refresh_lights(scene, rechoose=False, this_frame=False, rebuild=False):
    """Rebuild the scene groups if the fog lights, their models or the camera changed; materials are not
    touched.  Called from the depsgraph handler: when nothing changed it only compares names (and sets the
    Compositor method's windows).  ``rechoose``: also choose the lights' models (and Auto's method) again from
    the view (camera, lights or objects moved); the handler does that after the scene has stopped changing
    (``handlers.py``).  ``this_frame``: the handlers' calls, which do not step through frames (the windows
    of an animation grow by this frame's; saving the file computes them over the range again).  ``rebuild``:
    the groups are built again even if nothing changed (``build_scene_groups``' force)."""
    surface = bpy.data.node_groups.get(groups.SURFACE)
    if surface is None or surface.library is not None:
        return
    rebuilt.discard(scene.name)
    try:
        lights = fog_lights(scene)[0]
        spec, refused = followed_spec(scene, surface, lights, rechoose)
        if refused is not None:
            _handler_error(scene, refused)
        if spec is None:
            return
        build_scene_groups(scene, spec, lights, rechoose=rechoose, this_frame=this_frame,
                           progress=progress_.ConsoleProgress(prefix="Analytic Fog: "),
                           bake_in_line=bpy.app.background, force=rebuild)
    except ValueError as e:
        _handler_error(scene, str(e))
        return
    except TablesMissing:   # with a window: baked by the cancellable operator, which then syncs
        if not bake_declined(scene):
            props.request_sync(scene, "rechoose" if rechoose else "groups")
        return
    except Exception as e:   # noqa: BLE001 - a fault of the add-on's in a handler: said, the compositor spliced again
        _handler_error(scene, f"the fog could not follow the scene ({type(e).__name__}: {e}); Update Fog rebuilds it")
        traceback.print_exc()
        follow_compositor(scene, rebuild=True)
        return
    if refused is None and _sync_errors.get(scene.name) == _handler_errors.pop(scene.name, None):
        _sync_errors.pop(scene.name, None)   # what the handlers said last is mended: the scene is served again
    # the engine or the denoiser flag may have changed; rebuilt groups need the chain built anew
    follow_compositor(scene, rebuild=scene.name in rebuilt)


def followed_spec(scene, surface, lights, rechoose=False):
    """(spec, why) of the handlers' build: the scene's settings and None, or, while the method refuses them (a
    setting the panel was told the method can't serve), the settings the fog was built with and why, so that
    lamps and the camera are still followed.  The spec is None while neither can be used."""
    try:
        spec = spec_of(scene)
        check_method(scene, spec, resolve_method(scene, spec, lights, keep=not rechoose)[0])
    except ValueError as e:
        built = surface.get(SPEC_KEY)
        return (FogSpec.from_json(built) if built else None), str(e)
    return spec, None


def grow_windows(scene):
    """The frame changed (an animation plays or renders): the built method follows (``Method.frame_change``:
    the Compositor method's windows grow by this frame's, so a light moved since they were computed over the
    range is not cut on this frame), for the scene's settings (``usable_spec``)."""
    method = built_method()
    if method is None:
        return
    lights = lights_in_groups(fog_lights(scene)[0], stored_choice() or {"lights": {}})
    method.frame_change(scene, usable_spec(scene), lights)


def decline_bake(scene, table, error=None):
    """The bake of ``table`` for ``scene``'s settings was cancelled (or failed with ``error``): the fog keeps what
    it was built with, the panel says why (``sync_error``), and the handlers do not start it again for the same
    settings (``bake_declined``).  Returns the message."""
    what = bakers.label(table) if table is not None else "Dense Fog's tables"
    why = (f"the bake of {what} was cancelled" if error is None else f"the bake of {what} failed ({error})")
    why += ": the fog keeps what it was built with; Update Fog bakes it, or turn Dense Fog off"
    _sync_errors[scene.name] = why
    try:
        _declined[scene.name] = spec_of(scene).to_json()
    except ValueError:
        pass
    return why


def bake_declined(scene):
    """True if the user cancelled the bake of the tables ``scene``'s present settings need."""
    try:
        return _declined.get(scene.name) == spec_of(scene).to_json()
    except ValueError:
        return False


def accept_bake(scene):
    """Add Fog / Update Fog asked for the fog again: a bake cancelled before may start again."""
    _declined.pop(scene.name, None)


props.set_sync(sync)   # the settings' changes reach the fog through ``sync`` (props never imports this module)
