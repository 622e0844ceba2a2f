"""The ``render`` command: add the analytic fog to an opened scene, as the file has it, and render it.

Every fog setting comes from the .blend's own ``scene.analytic_fog`` (density,
colour, scene scale, method, anisotropy, the fog's top, Selected Only) and each light's
``light.analytic_fog.use``, unless a command-line flag overrides it: without
flags the file's fog is rendered as the artist left it.
"""
import dataclasses
import os
import subprocess
import sys
import time

from . import imageio, measure, props
from .ops import apply, progress
from .precompute.model import capabilities
from .precompute.core.spec import FogSpec

DEFAULT_SAMPLES = {"CYCLES": 16, "BLENDER_EEVEE": 16}
EEVEE_LIGHT_THRESHOLD = 1e-4   # EEVEE's default 0.01 windows point lights (ratio 0.92 at 4.5 m for 100 W)


def ensure_properties():
    """Register the add-on's property groups unless they are (``props.ensure_registered``): the file's fog
    settings and per-light Fog Glow toggles are read from them."""
    props.ensure_registered()


def _flag(args, name):
    return getattr(args, name, None)


def fog_settings(scene, args):
    """The fog to render: each setting from its flag, else from the file's ``scene.analytic_fog``.

    Returns (the ``FogSpec``, the objects whose materials to fog (None: all), {setting: (value, "flag" |
    "file")}, [notes]).  Without a flag the method is the file's (Auto by default); a file whose method is
    OSL rendered with EEVEE gets the node groups, with a note.  Selected Only in the file fogs only the
    materials of the objects selected in the file (as *Update Fog* would with it open).  Raises ValueError
    for settings that fail validation.
    """
    ensure_properties()
    s = scene.analytic_fog
    notes = []
    flags = dict(density=_flag(args, "density"), albedo=_flag(args, "color"), scene_scale=_flag(args, "scene_scale"),
                 anisotropy=_flag(args, "anisotropy"), method=_flag(args, "method"), passes=_flag(args, "passes"),
                 quality=_flag(args, "error"),
                 shafts=None if _flag(args, "shafts") is None else _flag(args, "shafts") == "on",
                 multiple_scattering=(None if _flag(args, "multiple_scattering") is None
                                      else _flag(args, "multiple_scattering") == "on"),
                 world_light=None if _flag(args, "world_light") is None else _flag(args, "world_light") == "on",
                 fog_top=_flag(args, "fog_top"), height_falloff=_flag(args, "height_falloff"),
                 ground_level=_flag(args, "ground_level"), air=_flag(args, "air"))
    spec = FogSpec.from_settings(s).replace(**flags)
    source = {k: "flag" if v is not None else "file" for k, v in flags.items()}
    if _flag(args, "no_fog_top"):   # (``replace`` keeps the file's value for None: the flag clears it here)
        spec = dataclasses.replace(spec, fog_top=None).validated()
        source["fog_top"] = "flag"
    if spec.fog_top is None and any(flags[k] is not None for k in ("height_falloff", "ground_level", "air")):
        notes.append(("fog top", "the fog fills all space, so the height falloff, the ground level and the air "
                                 "change nothing: give --fog-top for a fog layer"))
    if spec.method != "auto" and not capabilities.runs(spec.method, args.engine_id):
        runs_in = " or ".join(capabilities.engines_of(spec.method))
        if source["method"] == "flag":
            raise SystemExit(f"error: --method {spec.method} needs --engine {runs_in.lower()} (it renders in "
                             f"{runs_in} only); use --method nodes or auto")
        engine = capabilities.ENGINE_LABELS.get(args.engine_id, args.engine_id)
        notes.append(("method", f"the file's method is {spec.method}, which renders in {runs_in} only, not in "
                                f"{engine}: rendering with the node groups"))
        spec = spec.replace(method="nodes")
    objects = None
    if s.selected_only:
        objects = [o for o in scene.objects if o.select_get()]
        notes.append(("materials", f"the file's fog is Selected Only: fogging the materials of "
                                   f"{len(objects)} selected object(s) (and those fogged already)"))
    shown = {"density": ("density", spec.density), "colour": ("albedo", spec.albedo),
             "scene scale": ("scene_scale", spec.scene_scale), "anisotropy": ("anisotropy", spec.anisotropy),
             "method": ("method", spec.method), "fog passes": ("passes", spec.passes),
             "quality": ("quality", spec.quality),
             "world light": ("world_light", "on" if spec.world_light else "off"),
             "light shafts": ("shafts", "on" if spec.shafts else "off"),
             "multiple scattering": ("multiple_scattering", "on" if spec.multiple_scattering else "off"),
             "fog top": ("fog_top", "unbounded" if spec.fog_top is None else spec.fog_top),
             "height falloff": ("height_falloff", spec.height_falloff),
             "ground level": ("ground_level", spec.ground_level), "air": ("air", spec.air)}
    return spec, objects, {k: (v, source[f]) for k, (f, v) in shown.items()}, notes


def add_compositor_passes(scene, out):
    """After a render to the multilayer EXR ``out``, with the Compositor method's fog passes (its File Output nodes,
    ``nodes/compositor.py``, which wrote them beside the render's output): each view layer's file is added to
    ``out`` as its "Fog Light" and "Fog Transmittance" (``imageio.add_parts``, in a process that has not rendered)
    and removed, so ``out`` holds them as it holds the node groups' passes."""
    import bpy
    from .nodes import compositor
    for n in compositor.passes_outputs(scene):
        layer = n.file_name.rpartition(f" {compositor.PASSES_SUFFIX}")[0]
        folder = bpy.path.abspath(n.directory)
        stem = n.file_name.replace("####", f"{scene.frame_current:04d}")
        path = next((os.path.join(folder, f) for f in sorted(os.listdir(folder)) if f.startswith(stem)), None)
        if path is None:   # (the file's extension follows the render's Output File Extensions)
            raise RuntimeError(f"the Compositor method's fog passes of {layer!r} were not written ({stem} in "
                               f"{folder})")
        subprocess.run([sys.executable, imageio.__file__, "add-parts", os.path.abspath(os.fspath(out)), path, layer],
                       check=True)
        os.remove(path)


def fog_passes():
    """The fog passes' (name, type) as the view layers hold them (``nodes/passes.AOVS``)."""
    from .nodes import passes
    return passes.AOVS


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
    spec, objects, shown, notes = fog_settings(scene, args)
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
    skipped = apply.apply(scene, spec, objects, progress=progress.ConsoleProgress())
    print(f"fog: {describe(shown)}")
    for name, why in notes + list(skipped):
        print(f"note: {name}: {why}")
    lines = apply.explain()
    for line in lines if getattr(args, "explain", False) else lines[:1]:
        print(f"models: {line}")
    if not getattr(args, "explain", False) and (line := apply.method_line(apply.stored_choice() or {})):
        print(f"models: {line}")
    multilayer = bool(spec.passes) and str(args.out).lower().endswith(".exr")
    if spec.passes and not multilayer:
        print("note: fog passes: a PNG holds the picture only: give --out an .exr (multilayer) for the passes")
    t1 = time.perf_counter()
    if getattr(args, "viewport", False):   # what the rendered viewport shows: the preview, no compositing
        from .nodes import preview
        scene.render.use_compositing = False
        with preview.forced():
            measure.render_to_file(scene, args.out, multilayer=multilayer)
    else:
        measure.render_to_file(scene, args.out, multilayer=multilayer)
        if multilayer:
            add_compositor_passes(scene, args.out)
    if multilayer:
        print(f"passes: {args.out} is a multilayer EXR: the picture, the view layers' passes and the fog's "
              f"({', '.join(name for name, _ in fog_passes())})")
    print(f"fog added in {t1 - t0:.2f} s, rendered in {time.perf_counter() - t1:.2f} s")
