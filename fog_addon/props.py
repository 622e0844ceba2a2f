"""The fog's settings: ``scene.analytic_fog`` and each light's ``light.analytic_fog``.

These properties are the one store of the fog's settings: ``spec_of`` reads them as a validated
``precompute.core.spec.FogSpec``, and everything that decides reads that.  Changing a setting while the fog is on
schedules a sync (``schedule_sync``): the shared node groups follow (the viewport too); materials are never
rebuilt for it.  A sync that fails keeps the fog as it was, and the panel says why.

The properties have soft limits only (the sliders' range): a value typed beyond them reaches the spec's
validation (``FogSpec.validated``), which refuses it with the message the operator gives for the same value,
shown in the panel (``ops/sync.sync_error``, and ``settings_error`` before the fog is added).  Hard limits would
clamp it in silence.
"""
import contextlib

import bpy

from .precompute.core import presets, tables
from .precompute.core import spec as spec_
from .precompute.core.spec import FogSpec


_quiet = []   # non-empty while the add-on itself writes the settings (``quiet``): no sync for those writes
_pending = {}   # scene name -> the sync level (``SYNC_LEVELS``) waiting for the timer
SYNC_LEVELS = ("params", "groups", "rechoose")   # what a sync does: the params group; + the scene groups
#                                                  (lights keep their steps); + every light's models chosen again
_sync = []   # the sync functions (``set_sync``): in line, and with a window


def set_sync(fn, windowed=None):
    """``fn(scene, level)`` makes the fog follow the settings (``ops/sync.py`` sets it when imported);
    ``windowed(scene, level)`` does it from the timer of a session with a window (``ops``: Dense Fog's missing
    tables are baked first by the cancellable ``fog.bake_tables``).  Default: ``fn``."""
    _sync[:] = [fn, windowed or fn]


@contextlib.contextmanager
def quiet():
    """Write settings without scheduling a sync (``store_spec``: the fog is being built from them)."""
    _quiet.append(True)
    try:
        yield
    finally:
        _quiet.pop()


def schedule_sync(scene, level):
    """A setting changed: the fog follows it (``ops/sync.sync``) once the change is done.

    With a user interface, a timer runs the sync after the callback returns (several changes at once, such
    as a preset's, sync once, at the highest level asked for); a background process (scripts, the command
    line, farms) has no event loop to run timers, so it syncs at once.  A failed sync keeps the fog as it
    was built, and the panel says why (``ops/sync.sync_error``)."""
    if _quiet or not scene.analytic_fog.enabled or not _sync:
        return
    if bpy.app.background:
        _sync[0](scene, level)
        return
    request_sync(scene, level)


def request_sync(scene, level):
    """Queue a sync of ``scene`` at ``level`` for the timer (the highest level asked for wins): a setting's change,
    or the depsgraph handler's build that found Dense Fog tables missing (``ops/build.TablesMissing``: the timer's
    sync bakes them first, cancellable)."""
    old = _pending.get(scene.name)
    _pending[scene.name] = level if old is None or SYNC_LEVELS.index(level) > SYNC_LEVELS.index(old) else old
    if not bpy.app.timers.is_registered(_run_pending):
        bpy.app.timers.register(_run_pending, first_interval=0.0)


def _run_pending():
    pending = dict(_pending)
    _pending.clear()
    for name, level in pending.items():
        scene = bpy.data.scenes.get(name)
        if scene is not None and scene.analytic_fog.enabled and _sync:
            _sync[1](scene, level)
    return None


def _push(self, context):
    """A density, colour, scale or World Light change: the shared params group follows."""
    schedule_sync(context.scene, "params")


def _rebuild(self, context):
    """A method, anisotropy or fog passes change: the scene groups follow (the lights keep their steps)."""
    schedule_sync(context.scene, "groups")


def _quality_changed(self, context):
    """A Quality change: every light's models are chosen again."""
    schedule_sync(context.scene, "rechoose")


def _light_changed(self, context):
    """A light's Fog Glow toggle: the scene groups follow (the light joins or leaves them)."""
    schedule_sync(context.scene, "groups")


def _get_visibility(self):
    return min(presets.visibility_from_density(self.density), 1e9)


def _set_visibility(self, value):
    """Visibility -> density by Koschmieder's law; a visibility of 0 or less becomes a density the fog's
    validation refuses with its message (as the operator does), never a silent clamp."""
    self.density = presets.density_from_visibility(value) if value > 0.0 else (-1.0 if value < 0.0 else 3.4e38)


class AnalyticFogSettings(bpy.types.PropertyGroup):
    enabled: bpy.props.BoolProperty(
        name="Fog", default=False, options=set(),
        description="The fog is on in this scene (set by Add Fog / Remove Fog)")
    density: bpy.props.FloatProperty(
        name="Density", default=presets.PRESETS["fog"], soft_min=0.0, soft_max=1.0,
        precision=5, step=0.1, update=_push,
        description="Extinction coefficient beta in 1/m (equal to the scattering coefficient: no absorption). "
                    "Visibility V = 3.912 / beta (Koschmieder)")
    visibility: bpy.props.FloatProperty(
        name="Visibility", subtype="DISTANCE", unit="LENGTH",
        soft_min=1.0, soft_max=50000.0, get=_get_visibility, set=_set_visibility, options=set(),
        description="Meteorological visibility in real metres: the distance at which a black object's contrast "
                    "falls to 2 %. Sets the density by Koschmieder's law, beta = 3.912 / V")
    scene_scale: bpy.props.FloatProperty(
        name="Scene Scale", default=1.0, soft_min=0.001, soft_max=1000.0, update=_push,
        description="Real metres per Blender unit. A 1:100 model of a street (1 unit = 100 m) needs 100 "
                    "to show a real fog's density; the fog's density per unit is Density x Scene Scale")
    color: bpy.props.FloatVectorProperty(
        name="Color", subtype="COLOR", size=3, default=(1.0, 1.0, 1.0), soft_min=0.0, soft_max=1.0, update=_push,
        description="Single-scattering albedo of the fog: the fraction of extinguished light it scatters")
    anisotropy: bpy.props.FloatProperty(
        name="Anisotropy", default=0.0, soft_min=-tables.MAX_ANISOTROPY, soft_max=tables.MAX_ANISOTROPY,
        update=_rebuild,
        description="Henyey-Greenstein g of the fog's phase function: 0 isotropic, > 0 forward scattering "
                    "(droplets: haze about 0.7, fog about 0.85), so lamps glow brighter seen against their "
                    "light. Below -0.8 only the OSL method serves it")
    use_fog_top: bpy.props.BoolProperty(
        name="Fog Top", default=False, update=_rebuild,
        description="The fog is a layer over the ground up to Fog Top (valley fog, sea mist, a summer's haze). "
                    "Off: the fog fills all space")
    fog_top: bpy.props.FloatProperty(
        name="Fog Top", subtype="DISTANCE", unit="LENGTH", default=100.0, soft_min=0.0, soft_max=2000.0,
        update=_push,
        description="Height of the fog layer's top in real metres above Ground Level; below it the density "
                    "is Density")
    height_falloff: bpy.props.FloatProperty(
        name="Height Falloff", subtype="DISTANCE", unit="LENGTH", default=0.0, soft_min=0.0, soft_max=2000.0,
        update=_push,
        description="Softness of the fog's top, H in real metres: above the top the density falls by e "
                    "every H metres (e^-(height - top) / H). 0 is a hard top: no fog above it")
    air_density: bpy.props.FloatProperty(
        name="Air", default=0.0, soft_min=0.0, soft_max=4.0, update=_push,
        description="Density of the clear air (its Rayleigh scattering) as a multiple of sea-level air: 1 is the "
                    "standard atmosphere, which blues and greys the distance of a daylight scene; 0 no air. "
                    "Only with a Fog Top")
    ground_level: bpy.props.FloatProperty(
        name="Ground Level", subtype="DISTANCE", unit="LENGTH", default=0.0, update=_push,
        description="Height z of the ground in Blender units (as the scene's Z coordinates): the fog's "
                    "heights are measured from it")
    method: bpy.props.EnumProperty(
        name="Method", default="AUTO", update=_rebuild,
        items=[("AUTO", "Auto", "Per scene, the Node Groups or the Compositor method, whichever is predicted to "
                                "render faster, unless the scene needs what only one has (fog passes, a panoramic "
                                "camera, see-through materials): the choice and its reason are shown below"),
               ("NODES", "Node Groups", "Every model from shader node groups with packed tables: Cycles and EEVEE"),
               ("OSL", "OSL", "Prefer OSL models where one exists (the glow by quadrature in an OSL script): "
                              "Cycles only (switches Cycles' OSL on)"),
               ("COMPOSITOR", "Compositor", "The node groups' models evaluated once per pixel in the compositor "
                                            "from render passes: far cheaper with many lights; Cycles and "
                                            "EEVEE; a pixel that sees two surfaces gets one point's fog light")],
        description="Preference for the fog's models: each light gets, per term, the model this preference "
                    "chooses (shown below)")
    quality: bpy.props.EnumProperty(
        name="Quality", default=spec_.DEFAULT_QUALITY.upper(), update=_quality_changed,
        items=[("DRAFT", "Draft", f"Each light gets the cheapest models that keep the fog within "
                                  f"{spec_.QUALITY['draft']:.0%} of exact in every pixel the camera sees"),
               ("FINAL", "Final", f"The fog within {spec_.QUALITY['final']:.0%} of exact in every pixel"),
               ("EXACT", "Exact", "Every light fully modelled"),
               ("CUSTOM", "Custom", "Your own target error (Target Error)")],
        description="Model no more than the picture needs: leave out the fog light a light adds where the "
                    "error it makes stays under the target (predicted from the camera's view; see the list "
                    "of lights below)")
    target_error: bpy.props.FloatProperty(
        name="Target Error", default=0.01, soft_min=1e-4, soft_max=0.5, subtype="FACTOR", precision=4,
        update=_quality_changed,
        description="Largest relative change of any pixel's fog light the Custom quality allows")
    world_light: bpy.props.BoolProperty(
        name="World Light", default=False, update=_push,
        description="Let the World light surfaces through the fog. Off (physical, as Cycles' World volume): "
                    "the fog fills all space, so no light from the infinitely far World gets through it and "
                    "the lamps light the scene alone. On: surfaces keep the World's light, an artistic "
                    "ambient (the camera still sees the fog, not the World). With a Fog Top the World always "
                    "lights surfaces, through the layer")
    use_shafts: bpy.props.BoolProperty(
        name="Light Shafts", default=True, update=_rebuild,
        description="Objects cast shadows into the fog: beams through windows, shafts between columns, no glow "
                    "above a lamp's hood. Only lights with an object near them get a shadow map (Compositor "
                    "method: Cycles and EEVEE)")
    use_multiple_scattering: bpy.props.BoolProperty(
        name="Dense Fog (Multiple Scattering)", default=True, update=_rebuild,
        description="Model the light scattered more than once (the wide halo of thick fog, the fog light it "
                    "adds on surfaces) wherever it changes a pixel by more than the Quality's target: thin fog "
                    "pays nothing. Off: single scattering only, a stylised look; the predicted error and a note "
                    "then say what it leaves out. The first use of an anisotropy bakes its tables (8-20 s each, "
                    "then cached): the status bar shows the bake, and Esc cancels it")
    use_passes: bpy.props.BoolProperty(
        name="Fog Passes", default=False, update=_rebuild,
        description="Write the render passes Fog Light (the light the fog adds) and Fog Transmittance "
                    "(e^-beta*distance) for compositing. They cost render time (about a quarter more in "
                    "Cycles); the denoising set-up does not need them")
    selected_only: bpy.props.BoolProperty(
        name="Selected Only", default=False,
        description="Add the fog only to the materials of the selected objects (the World and lights always)")


class AnalyticFogLight(bpy.types.PropertyGroup):
    use: bpy.props.BoolProperty(
        name="Fog Glow", default=True, update=_light_changed,
        description="This light lights the analytic fog (glow, fog-lit surfaces)")


CLASSES = (AnalyticFogSettings, AnalyticFogLight)
_register_classes, _unregister_classes = bpy.utils.register_classes_factory(CLASSES)


def ensure_registered():
    """Register the property groups unless they are: the settings' one store exists even in a process that
    adds the fog without enabling the add-on (scripts, the command line, farms).  Without them Blender keeps a
    file's ``scene.analytic_fog`` and ``light.analytic_fog`` as bare ID properties that nothing reads."""
    if not hasattr(bpy.types.Scene, "analytic_fog") or not hasattr(bpy.types.Light, "analytic_fog"):
        register()


def spec_of(scene):
    """The scene's fog settings as a validated ``FogSpec`` (``scene.analytic_fog``); raises ValueError."""
    ensure_registered()
    return FogSpec.from_settings(scene.analytic_fog)


def store_spec(scene, spec):
    """Write ``spec`` into ``scene.analytic_fog`` (the one store of the fog's settings), without its callbacks."""
    ensure_registered()
    settings = scene.analytic_fog
    with quiet():
        for key, value in spec.settings_values().items():
            if key == "color" or getattr(settings, key) != value:
                setattr(settings, key, value)


def register():
    if AnalyticFogSettings.is_registered:   # (``ensure_registered`` did, before the add-on was enabled)
        return
    _register_classes()
    bpy.types.Scene.analytic_fog = bpy.props.PointerProperty(type=AnalyticFogSettings)
    bpy.types.Light.analytic_fog = bpy.props.PointerProperty(type=AnalyticFogLight)


def unregister():
    del bpy.types.Light.analytic_fog
    del bpy.types.Scene.analytic_fog
    _unregister_classes()
