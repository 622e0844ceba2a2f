"""The ``render`` command: add the analytic fog to an opened scene, as the file has it, and render it.

Every fog setting comes from the .blend's own ``scene.analytic_fog`` (density,
colour, scene scale, method, anisotropy, Selected Only) and each light's
``light.analytic_fog.use``, unless a command-line flag overrides it: without
flags the file's fog is rendered as the artist left it.
"""
import time

import bpy

from . import measure, props
from .ops import apply, progress

DEFAULT_SAMPLES = {"CYCLES": 16, "BLENDER_EEVEE": 16}
CYCLES_ONLY = {"osl": "EEVEE cannot run OSL"}
EEVEE_LIGHT_THRESHOLD = 1e-4   # EEVEE's default 0.01 windows point lights (ratio 0.92 at 4.5 m for 100 W)


def ensure_properties():
    """Register the add-on's property groups unless they are (the add-on need not be enabled).

    Without them Blender keeps a file's ``scene.analytic_fog`` and
    ``light.analytic_fog`` as bare ID properties that nothing reads: the saved
    settings and per-light Fog Glow toggles would be ignored.
    """
    if not hasattr(bpy.types.Scene, "analytic_fog") or not hasattr(bpy.types.Light, "analytic_fog"):
        props.register()


def _flag(args, name):
    return getattr(args, name, None)


def fog_settings(scene, args):
    """The fog to render: each setting from its flag, else from the file's ``scene.analytic_fog``.

    Returns (keyword arguments for ``apply.apply_fog``, {setting: (value, "flag" | "file")},
    [notes]).  Without a flag the method is the file's; a file whose method
    is OSL rendered with EEVEE gets the node groups, with a note.  Selected Only in the
    file fogs only the materials of the objects selected in the file (as *Update Fog* would with it open).
    """
    ensure_properties()
    s = scene.analytic_fog
    notes, source = [], {}

    def pick(key, flag, from_file):
        value = _flag(args, flag)
        source[key] = "flag" if value is not None else "file"
        return from_file() if value is None else value

    density = pick("density", "density", lambda: s.density)
    albedo = tuple(float(c) for c in pick("colour", "color", lambda: tuple(s.color)))
    scene_scale = pick("scene scale", "scene_scale", lambda: s.scene_scale)
    anisotropy = pick("anisotropy", "anisotropy", lambda: s.anisotropy)
    method = pick("method", "method", lambda: s.method.lower())
    with_passes = bool(pick("fog passes", "passes", lambda: s.use_passes))
    quality = pick("quality", "error", lambda: props.quality_setting(s))
    world_light = pick("world light", "world_light", lambda: "on" if s.world_light else "off")
    if method in CYCLES_ONLY and args.engine_id != "CYCLES":
        if source["method"] == "flag":
            raise SystemExit(f"error: --method {method} needs --engine cycles ({CYCLES_ONLY[method]}); "
                             "use --method nodes")
        notes.append(("method", f"the file's method is {method}, which needs Cycles ({CYCLES_ONLY[method]}): "
                                "rendering with the node groups"))
        method = "nodes"
    objects = None
    if s.selected_only:
        objects = [o for o in scene.objects if o.select_get()]
        source["materials"] = "file"
        notes.append(("materials", f"the file's fog is Selected Only: fogging the materials of "
                                   f"{len(objects)} selected object(s) (and those fogged already)"))
    kwargs = dict(density=density, albedo=albedo, anisotropy=anisotropy, method=method, objects=objects,
                  scene_scale=scene_scale, with_passes=with_passes, error=quality, world_light=world_light == "on")
    shown = {"density": density, "colour": albedo, "scene scale": scene_scale, "anisotropy": anisotropy,
             "method": method, "fog passes": with_passes, "quality": quality, "world light": world_light}
    return kwargs, {k: (v, source[k]) for k, v in shown.items()}, notes


def describe(shown):
    """One line: each setting with where it came from."""
    def fmt(v):
        return "(" + ", ".join(f"{c:g}" for c in v) + ")" if isinstance(v, tuple) else (
            f"{v:g}" if isinstance(v, float) else str(v))
    return ", ".join(f"{k} {fmt(v)} ({src})" for k, (v, src) in shown.items())


def apply_and_render(scene, args):
    """Add the fog (the file's settings, overridden by the command's flags), set the engine and render
    to ``args.out``.  Keeps the scene's camera, lights, materials and colour management.
    """
    engine = args.engine_id
    kwargs, shown, notes = fog_settings(scene, args)
    # the render settings first: the fog keeps Cycles' denoiser off its light only if the scene
    # still denoises once they are made (``nodes/compositor.py``)
    scene.render.engine = engine
    measure.set_samples(scene, args.samples or DEFAULT_SAMPLES[engine])
    measure.set_cycles_cpu(scene)
    if engine == "BLENDER_EEVEE":
        scene.eevee.light_threshold = min(scene.eevee.light_threshold, EEVEE_LIGHT_THRESHOLD)
    if getattr(args, "pixel_centre", False):
        measure.set_pixel_centre_filter(scene)
    if getattr(args, "no_interreflection", False):
        from . import reference
        reference.disable_interreflection(scene)
    t0 = time.perf_counter()
    skipped = apply.apply_fog(scene, **kwargs, progress=progress.ConsoleProgress())
    print(f"fog: {describe(shown)}")
    for name, why in notes + list(skipped):
        print(f"note: {name}: {why}")
    lines = apply.explain()
    for line in lines if getattr(args, "explain", False) else lines[:1]:
        print(f"models: {line}")
    t1 = time.perf_counter()
    measure.render_to_file(scene, args.out)
    print(f"fog added in {t1 - t0:.2f} s, rendered in {time.perf_counter() - t1:.2f} s")
