"""The ``render`` command: add the analytic fog to an opened scene and render it."""
import time

from . import measure
from .ops import apply
from .precompute import presets

DEFAULT_SAMPLES = {"CYCLES": 16, "BLENDER_EEVEE": 16}
EEVEE_LIGHT_THRESHOLD = 1e-4   # EEVEE's default 0.01 windows point lights (ratio 0.92 at 4.5 m for 100 W)


def apply_and_render(scene, args):
    """Add fog with the command's settings, set the engine and render to ``args.out``.

    Keeps the scene's camera, lights, materials and colour management.  The
    density defaults to the scene's own setting, else the "fog" preset.
    """
    engine = args.engine_id
    if args.method == "osl" and engine != "CYCLES":
        raise SystemExit("error: --method osl needs --engine cycles (EEVEE cannot run OSL); use --method nodes")
    density = args.density
    if density is None:
        settings = getattr(scene, "analytic_fog", None)
        density = settings.density if settings is not None else presets.PRESETS["fog"]
    t0 = time.perf_counter()
    skipped = apply.apply_fog(scene, density, anisotropy=args.anisotropy, method=args.method)
    for name, why in skipped:
        print(f"note: {name}: {why}")
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
    t1 = time.perf_counter()
    measure.render_to_file(scene, args.out)
    print(f"fog {density:g} 1/m added in {t1 - t0:.2f} s, rendered in {time.perf_counter() - t1:.2f} s")
