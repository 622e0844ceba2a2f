"""Command line: ``python -m fog_addon render|reference|compare ...``.

    render SCENE.blend --engine cycles|eevee [--method auto|nodes|osl|compositor] [--preset NAME | --density BETA]
           [--color R,G,B] [--scene-scale S] [--anisotropy G] [--error E|draft|final|exact] [--explain]
           [--fog-top METRES | --no-fog-top] [--height-falloff METRES] [--ground-level Z] [--air X]
           [--samples N] [--resolution WxH] --out OUT.png|OUT.exr
    reference SCENE.blend [--preset NAME | --density BETA] [--anisotropy G] [--samples N]
           [--resolution WxH] --out OUT.exr
    compare TEST.exr REF.exr [--diff OUT.png]
    weather IMAGE.exr --depth DEPTH.exr --visibility METRES [--anisotropy G] [--sky R,G,B] --out OUT.exr

``render`` takes every fog setting the flags leave out from the file's own
``scene.analytic_fog`` (and each light's Fog Glow toggle): see render.py.

Exit codes: 0 success, 1 render/compare failure, 2 bad input (argparse errors too).
Arguments are validated before Blender is imported, so bad input fails fast.
"""
import argparse
import math
import os
import sys

EXIT_OK, EXIT_FAIL, EXIT_USAGE = 0, 1, 2


class UsageError(Exception):
    """Bad command-line input (exit code 2)."""


def _presets():
    """{name: density 1/m} of every preset: the visibility classes, then the fog layers (``presets.LAYERED``)."""
    try:
        from .precompute.core.presets import LAYERED, PRESETS
    except ImportError:
        LAYERED, PRESETS = {}, {k: 3.912 / v for k, v in
                                {"haze": 8000.0, "mist": 2000.0, "fog": 500.0, "dense_fog": 150.0}.items()}
    return dict(PRESETS, **{k: v["density"] for k, v in LAYERED.items()})


def _layered():
    """The fog layer presets (``presets.LAYERED``): {name: {density, anisotropy, albedo, fog_top, ...}}."""
    try:
        from .precompute.core.presets import LAYERED
    except ImportError:
        return {}
    return LAYERED


def _finite_float(name):
    def conv(s):
        try:
            v = float(s)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{name} must be a number, got {s!r}")
        if not math.isfinite(v):
            raise argparse.ArgumentTypeError(f"{name} must be finite, got {s!r}")
        return v
    return conv


def _non_negative_float(name):
    finite = _finite_float(name)

    def conv(s):
        v = finite(s)
        if v < 0:
            raise argparse.ArgumentTypeError(f"{name} must be >= 0, got {s!r}")
        return v
    return conv


def _air(s):
    """``--air``: the clear air's density, a multiple of sea-level air in [0, spec.MAX_AIR]."""
    from .precompute.core.spec import MAX_AIR
    v = _non_negative_float("air")(s)
    if v > MAX_AIR:
        raise argparse.ArgumentTypeError(f"air must be at most {MAX_AIR:g} (times sea-level clear air; 1 is the "
                                         f"standard atmosphere), got {s!r}")
    return v


def _positive_int(name):
    def conv(s):
        try:
            v = int(s)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{name} must be a positive integer, got {s!r}")
        if v <= 0:
            raise argparse.ArgumentTypeError(f"{name} must be a positive integer, got {s!r}")
        return v
    return conv


def _resolution(s):
    parts = s.lower().split("x")
    try:
        w, h = (int(p) for p in parts)
    except ValueError:
        raise argparse.ArgumentTypeError(f"resolution must look like 640x360, got {s!r}")
    if w <= 0 or h <= 0 or w > 16384 or h > 16384:
        raise argparse.ArgumentTypeError(f"resolution out of range: {s!r}")
    return (w, h)


def _color(s):
    try:
        rgb = tuple(float(c) for c in s.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"color must look like 0.9,0.7,0.5, got {s!r}")
    if len(rgb) != 3 or not all(0.0 <= c <= 1.0 for c in rgb):
        raise argparse.ArgumentTypeError(f"color must be three numbers in [0, 1] like 0.9,0.7,0.5, got {s!r}")
    return rgb


def _quality(s):
    named = {"draft": "draft", "final": "final", "exact": "exact"}
    if s.strip().lower() in named:
        return named[s.strip().lower()]
    try:
        v = float(s)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--error must be a fraction such as 0.01, or draft, final or exact; "
                                         f"got {s!r}")
    if not (math.isfinite(v) and 0.0 < v < 1.0):
        raise argparse.ArgumentTypeError(f"--error must be a fraction in (0, 1) such as 0.01 for 1 %, got {s!r}")
    return v


def _positive_float(name):
    finite = _finite_float(name)

    def conv(s):
        v = finite(s)
        if v <= 0:
            raise argparse.ArgumentTypeError(f"{name} must be > 0, got {s!r}")
        return v
    return conv


def _add_fog_flags(p, file_default=""):
    g = p.add_mutually_exclusive_group()
    g.add_argument("--preset", help="named fog: its density and (unless --anisotropy) its particles' anisotropy; "
                   "a fog layer (" + ", ".join(_layered()) + ") also its top, height falloff and colour unless "
                   "their flags give them: " + ", ".join(sorted(_presets())) + file_default)
    g.add_argument("--density", type=_finite_float("density"), metavar="BETA",
                   help="extinction = scattering coefficient in 1/m (>= 0)" + file_default)
    p.add_argument("--anisotropy", type=_finite_float("anisotropy"), default=None, metavar="G",
                   help="Henyey-Greenstein g in [-0.95, 0.95]: 0 isotropic, > 0 forward scattering (haze ~0.7, "
                        "fog ~0.85); below -0.8 only with --method osl" + (file_default or "; default 0"))
    p.add_argument("--samples", type=_positive_int("samples"), metavar="N", help="samples per pixel")
    p.add_argument("--resolution", type=_resolution, metavar="WxH", help="output size in pixels")
    p.add_argument("--out", required=True, help="output image (.exr = linear float, .png = display)")
    p.add_argument("--no-cast-shadows", action="store_true",
                   help="hide objects from shadow rays (tests: the analytic model has no cast shadows)")
    p.add_argument("--no-interreflection", action="store_true",
                   help="hide objects from diffuse/glossy bounce rays (tests: no surface-to-surface light)")


def build_parser():
    ap = argparse.ArgumentParser(prog="python -m fog_addon",
                                 description="Analytic Fog: render, path-traced reference, compare")
    sub = ap.add_subparsers(dest="command", required=True)

    r = sub.add_parser("render", help="render a scene with the analytic fog")
    r.add_argument("scene", metavar="SCENE.blend")
    r.add_argument("--engine", required=True, choices=["cycles", "eevee"])
    from_file = " (default: the file's setting)"
    r.add_argument("--passes", action="store_const", const=True, default=None,
                   help="write the Fog Light and Fog Transmittance passes: an --out .exr is then a multilayer EXR "
                        "with every pass (default: the file's setting)")
    r.add_argument("--shafts", choices=["on", "off"], default=None,
                   help="light shafts: objects cast shadows into the fog (default: the file's setting, on)")
    r.add_argument("--multiple-scattering", choices=["on", "off"], default=None,
                   help="dense fog: the light scattered more than once, modelled wherever it changes a pixel by "
                        "more than the Quality's target; off leaves it out (single scattering) and the predicted "
                        "error counts it (default: the file's setting, on)")
    r.add_argument("--method", choices=["auto", "nodes", "osl", "compositor"], default=None,
                   help="auto (node groups or compositor, whichever the scene is predicted to render faster with, "
                        "unless it needs one: --explain says which and why), node groups (Cycles, EEVEE), OSL "
                        "(Cycles) or compositor (the fog's light once per pixel in the compositor, Cycles and "
                        "EEVEE) (default: the file's Method, Auto in a new scene)")
    _add_fog_flags(r, from_file)
    r.add_argument("--color", type=_color, metavar="R,G,B",
                   help="the fog's colour (single-scattering albedo), each in [0, 1]" + from_file)
    r.add_argument("--scene-scale", type=_positive_float("scene scale"), metavar="S",
                   help="real metres per Blender unit" + from_file)
    r.add_argument("--error", type=_quality, metavar="E",
                   help="Quality: the largest relative error of any pixel's fog light, a fraction such as 0.01, "
                        "or draft (5 %%), final (1 %%), exact (every light fully modelled)" + from_file)
    r.add_argument("--world-light", choices=["on", "off"], default=None,
                   help="on: the World keeps lighting surfaces through the fog (an artistic ambient); off: the fog "
                        "extinguishes it, as Cycles' World volume does" + from_file)
    top = r.add_mutually_exclusive_group()
    top.add_argument("--fog-top", type=_non_negative_float("fog top"), metavar="METRES",
                     help="the fog is a layer up to this height in real metres above the ground (default: the "
                          "file's setting; a new scene's fog fills all space)")
    top.add_argument("--no-fog-top", action="store_true",
                     help="the fog fills all space, whatever the file's Fog Top")
    r.add_argument("--height-falloff", type=_non_negative_float("height falloff"), metavar="METRES",
                   help="above the fog's top its density falls by e every METRES real metres; 0 is a hard top"
                        + from_file)
    r.add_argument("--ground-level", type=_finite_float("ground level"), metavar="Z",
                   help="the ground's height z in Blender units (the fog's top is measured from it)"
                        + from_file)
    r.add_argument("--air", type=_air, metavar="X",
                   help="clear air's density (its Rayleigh scattering) as a multiple of sea-level air, at most 100: "
                        "1 is the standard atmosphere, which blues and greys a daylight scene's distance; only "
                        "with a fog top" + from_file)
    r.add_argument("--viewport", action="store_true",
                   help="render what the rendered viewport shows: with the Compositor method, its preview in the "
                        "materials and the World (the lights that matter most, no shafts), not the compositor's fog")
    r.add_argument("--explain", action="store_true",
                   help="print the models each light got and the error predicted for them")
    r.add_argument("--pixel-centre", action="store_true",
                   help="sample pixel centres (Gaussian 0.01 px filter), as the reference does")

    f = sub.add_parser("reference", help="render the Cycles path-traced single-scattering reference")
    f.add_argument("scene", metavar="SCENE.blend")
    _add_fog_flags(f)
    f.add_argument("--seed", type=int, default=0, help="Cycles sampling seed (noise estimates)")

    w = sub.add_parser("weather", help="add fog (attenuation, airlight, glows) to a linear HDR image with a depth map")
    w.add_argument("image", metavar="IMAGE.exr",
                   help="the fog-free picture, linear light: an EXR's R, G, B, or a multilayer EXR's Combined pass "
                        "(Composite.Combined if Blender's compositor wrote one); an 8- or 16-bit PNG or JPEG is "
                        "converted from sRGB to linear, with a note")
    w.add_argument("--image-pass", metavar="NAME",
                   help="the multilayer EXR pass to read R, G, B from when there are several (e.g. ViewLayer.Combined)")
    w.add_argument("--depth", required=True, metavar="DEPTH.exr",
                   help="metres from the camera per pixel (1e6 and beyond: sky), one float channel: a single-channel "
                        "EXR, an EXR's Z channel, or a multilayer EXR's Depth pass (<layer>.Depth.Z, Blender's Z: "
                        "along the view axis, see --depth-kind); may be the same file as IMAGE.  Integer images "
                        "(PNG, JPEG) are refused")
    w.add_argument("--depth-kind", choices=("auto", "distance", "z"), default="auto",
                   help="what the depth measures: distance along each pixel's ray, or z along the view axis "
                        "(turned into distance with --fov); auto (the default): Blender's Depth pass is z, "
                        "anything else distance")
    w.add_argument("--depth-pass", metavar="NAME",
                   help="the channel or pass to read the depth from when the names do not settle it "
                        "(e.g. Second.Depth or Second.Depth.Z)")
    w.add_argument("--visibility", required=True, type=_finite_float("visibility"), metavar="METRES",
                   help="meteorological visibility; the density is 3.912 / visibility (Koschmieder)")
    w.add_argument("--anisotropy", type=_finite_float("anisotropy"), default=0.85, metavar="G",
                   help="Henyey-Greenstein g of the fog (default 0.85)")
    w.add_argument("--sky", default="1,1,1", metavar="R,G,B", help="the horizon's radiance (default 1,1,1)")
    w.add_argument("--fov", type=_finite_float("fov"), default=39.6, metavar="DEG",
                   help="horizontal field of view of the image (default 39.6: Blender's 50 mm lens)")
    w.add_argument("--albedo", type=_finite_float("albedo"), default=0.9,
                   help="single-scattering albedo of the multiply scattered light (default 0.9)")
    w.add_argument("--scale", type=_finite_float("scale"), default=1.0,
                   help="metres per unit of the depth map (default 1)")
    w.add_argument("--out", required=True, metavar="OUT.exr")
    c = sub.add_parser("compare", help="compare a test image with a reference")
    c.add_argument("test", metavar="TEST.exr")
    c.add_argument("ref", metavar="REF.exr")
    c.add_argument("--diff", metavar="OUT.png", help="write test | reference | error map")
    c.add_argument("--max-rel", type=_finite_float("max-rel"), default=0.1,
                   help="relative error shown as white in the diff image (default 0.1)")
    return ap


def _resolve_density(args, required, layers=False):
    """The density (and anisotropy) of ``--preset`` into ``args``; a fog layer preset also sets the top, the
    falloff, the air and the colour its flags leave unset (``layers``: the command has those flags, else refused)."""
    if args.preset is not None:
        presets = _presets()
        if args.preset not in presets:
            raise UsageError(f"unknown preset {args.preset!r}; choose one of: {', '.join(sorted(presets))}")
        args.density = float(presets[args.preset])
        layer = _layered().get(args.preset)
        if layer is not None:
            if not layers:
                raise UsageError(f"preset {args.preset!r} is a fog layer with a top, and the reference's fog "
                                 f"fills all space: give --density {layer['density']:.6g} instead")
            if args.anisotropy is None:
                args.anisotropy = layer["anisotropy"]
            if args.fog_top is None and not args.no_fog_top:
                args.fog_top = layer["fog_top"]
            if args.height_falloff is None:
                args.height_falloff = layer["height_falloff"]
            if args.air is None:
                args.air = layer.get("air", 0.0)
            if args.color is None:
                args.color = tuple(layer["albedo"])
        elif args.anisotropy is None:
            try:
                from .precompute.core.presets import ANISOTROPY
                args.anisotropy = ANISOTROPY[args.preset]
            except ImportError:
                pass
    if args.density is None:
        if required:
            raise UsageError("give the fog density with --density BETA (1/m) or --preset NAME")
        return
    if args.density < 0:
        raise UsageError(f"density must be >= 0 (1/m), got {args.density}")
    try:
        from .precompute.core.presets import validate_density
    except ImportError:
        return
    try:
        args.density = validate_density(args.density)
    except ValueError as exc:
        raise UsageError(str(exc))


def _validate_common(args, density_required, layers=False):
    _resolve_density(args, density_required, layers)
    if args.anisotropy is not None:
        from .precompute.core.medium import validate_anisotropy
        try:
            args.anisotropy = validate_anisotropy(args.anisotropy)
        except ValueError as exc:
            raise UsageError(str(exc))
    if not os.path.isfile(args.scene):
        raise UsageError(f"scene file not found: {args.scene}")
    if not args.scene.lower().endswith(".blend"):
        raise UsageError(f"scene must be a .blend file: {args.scene}")
    ext = os.path.splitext(args.out)[1].lower()
    if ext not in (".exr", ".png"):
        raise UsageError(f"--out must end in .exr or .png, got {args.out!r}")
    out_dir = os.path.dirname(os.path.abspath(args.out))
    if not os.path.isdir(out_dir):
        raise UsageError(f"output directory does not exist: {out_dir}")


def _open(args):
    from . import measure
    scene = measure.open_scene(args.scene)
    if args.resolution:
        measure.set_resolution(scene, *args.resolution)
    return scene


def cmd_render(args):
    _validate_common(args, density_required=False, layers=True)
    try:
        from . import render as render_mod
    except ImportError as exc:
        print(f"error: the analytic renderer (fog_addon/render.py) is not available: {exc}", file=sys.stderr)
        return EXIT_FAIL
    if not hasattr(render_mod, "apply_and_render"):
        print("error: fog_addon.render has no apply_and_render(scene, args)", file=sys.stderr)
        return EXIT_FAIL
    from . import reference
    render_mod.ensure_properties()   # before loading: the file's fog settings and light toggles are read
    scene = _open(args)
    if args.no_cast_shadows:
        reference.disable_cast_shadows(scene)
    args.engine_id = {"cycles": "CYCLES", "eevee": "BLENDER_EEVEE"}[args.engine]
    result = render_mod.apply_and_render(scene, args)
    if not os.path.isfile(args.out):
        print(f"error: render did not write {args.out}", file=sys.stderr)
        return EXIT_FAIL
    print(f"wrote {args.out}")
    return EXIT_OK if result is None or result is True or result == 0 else int(bool(result))


def cmd_reference(args):
    _validate_common(args, density_required=True)
    import time
    from . import measure, reference
    scene = _open(args)
    reference.configure_reference(scene, args.density, anisotropy=args.anisotropy or 0.0,
                                  samples=args.samples or reference.DEFAULT_SAMPLES)
    if args.no_cast_shadows:
        reference.disable_cast_shadows(scene)
    if args.no_interreflection:
        reference.disable_interreflection(scene)
    scene.cycles.seed = args.seed
    t0 = time.perf_counter()
    measure.render_to_file(scene, args.out)
    r = scene.render
    print(f"wrote {args.out} ({r.resolution_x}x{r.resolution_y}, {scene.cycles.samples} spp, "
          f"density {args.density:g} 1/m, {time.perf_counter() - t0:.2f} s)")
    return EXIT_OK


def cmd_compare(args):
    for p in (args.test, args.ref):
        if not os.path.isfile(p):
            raise UsageError(f"image not found: {p}")
    if args.max_rel <= 0:
        raise UsageError("--max-rel must be > 0")
    from . import compare
    try:
        m = compare.compare_files(args.test, args.ref, diff=args.diff, max_rel=args.max_rel)
    except ValueError as exc:
        raise UsageError(str(exc))
    except OSError as exc:
        raise UsageError(f"cannot read image: {exc}")
    print(compare.format_metrics(m))
    if args.diff:
        print(f"diff image {args.diff}")
    return EXIT_OK


def cmd_weather(args):
    """``weather``: fog added to a photograph or render with its depth (``weather.py``)."""
    from . import weather
    try:
        sky = tuple(float(x) for x in args.sky.split(","))
    except ValueError:
        raise UsageError(f"--sky needs three numbers R,G,B, got {args.sky!r}")
    if len(sky) != 3 or not all(math.isfinite(x) and x >= 0.0 for x in sky):
        raise UsageError(f"--sky needs three numbers >= 0, got {args.sky!r}")
    if not 0.0 <= args.albedo <= 1.0:
        raise UsageError(f"--albedo must be in [0, 1], got {args.albedo}")
    try:
        weather.run(args.image, args.depth, args.out, args.visibility, args.anisotropy, sky, args.fov, args.albedo,
                    args.scale, image_pass=args.image_pass, depth_pass=args.depth_pass, depth_kind=args.depth_kind)
    except weather.WeatherError as exc:
        raise UsageError(str(exc))
    except (OSError, FileNotFoundError) as exc:
        raise UsageError(f"cannot read image: {exc}")
    return EXIT_OK


def main(argv=None):
    ap = build_parser()
    args = ap.parse_args(argv)
    handler = {"render": cmd_render, "reference": cmd_reference, "compare": cmd_compare,
               "weather": cmd_weather}[args.command]
    try:
        return handler(args)
    except UsageError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_USAGE
