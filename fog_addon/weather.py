"""Weather on photographs: fog added to a linear HDR image with a depth map (Narasimhan et al. ``002`` §8),
numpy only (images through ``imageio``).

Each pixel is a small source seen through the fog.  With depth z and extinction beta (T = beta z), its own light
reaches the camera dimmed, the fog in front of it adds the horizon's light (Koschmieder; Narasimhan Eq. 30-31),
and the light it sends into the fog comes back as a glow around it:

    out = L e^{-T} + A (1 - e^{-T}) + sum over pixels s of L_s K(T_s, theta),
    K(T, theta) = Omega_px T^2 W0 [ I_1(T, theta) + I_{>=2}(T, theta) / W0 ],

Omega_px the pixel's solid angle (sr), I_1 the single-scattering field of an endless ray (Sun et al. 2005 Eq. 12,
the airlight table at extinction 1) and I_{>=2} the multiply scattered field (``precompute/physics/point/multiple.py``),
both per unit intensity: a patch of radiance L filling a pixel at depth z has intensity L Omega_px z^2, and the field at
extinction beta scales as beta^2.  The sum is the depth-dependent convolution of §7.3: the picture is split into
layers of T (each pixel shared between its two nearest layers, linearly in ``layer_coordinate``), and each layer
convolved with its kernel by FFT.  Pixels at infinite depth (the sky: depth above SKY_DEPTH) send no glow and take
the horizon's light A.  The image's own noise-free light sources (lamps, windows, neon) are what glows; a lit
surface glows too, as it does in fog, by the same kernel.

Units: radiance as in the image (linear), depth in metres (or Blender units with ``scale``), angles in radians.
"""
import math
import sys

import numpy as np

SKY_DEPTH = 1.0e6   # m: a depth beyond this is the sky (Blender writes 1e10 for the background)
LAYERS = 16         # layers of T between the nearest and farthest ground pixel (at least)
MAX_LAYER_STEP = 0.3   # the largest step between layers in ``layer_coordinate`` (more layers for a deeper picture)
LAYER_SLOPE = 0.5      # ``layer_coordinate``'s slope: ln T + LAYER_SLOPE T
SUBSAMPLES = 8      # the kernel's core (|offset| <= CORE px) is averaged over SUBSAMPLES^2 points of each pixel
CORE = 2


class WeatherError(ValueError):
    """Bad input to ``add_weather`` or a file ``read_image`` / ``read_depth`` cannot read as asked: a message a
    user understands."""


def _fields(g, albedo):
    """(single, multiple): functions (T, cos theta) -> I_1 and I_{>=2} / W0 per unit intensity (extinction 1)."""
    from .precompute.model import bakers
    from .precompute.physics.emitter import emitter_glow
    from .precompute.physics.point import multiple
    from .precompute.core.ops import NumpyOps
    spec = multiple.table_spec(g, albedo)
    m = NumpyOps({spec.name: bakers.table_array(spec, g)})
    return emitter_glow.single_field(g, bakers.READER), (lambda t, c: multiple.field(m, spec, t, c))


def glow_kernel(shape, pixel_angle, optical_distance, single, multiple_, albedo):
    """K (``shape``: the padded FFT grid, offsets wrapped) for sources at optical distance T, per unit source
    radiance (module docstring); ``pixel_angle`` rad a pixel."""
    h, w = shape
    dy = np.fft.fftfreq(h, 1.0 / h)[:, None]
    dx = np.fft.fftfreq(w, 1.0 / w)[None, :]
    r = np.hypot(dx, dy)
    t = float(optical_distance)

    def k_at(radius_px):
        c = np.cos(radius_px * pixel_angle)
        return albedo * (single(np.full(c.shape, t), c) + multiple_(np.full(c.shape, t), c))

    kern = k_at(r)
    core = np.argwhere((np.abs(dx) <= CORE) & (np.abs(dy) <= CORE))
    sub = (np.arange(SUBSAMPLES) + 0.5) / SUBSAMPLES - 0.5
    sx, sy = np.meshgrid(sub, sub)
    for i, j in core:
        kern[i, j] = float(np.mean(k_at(np.hypot(dx[0, j] + sx, dy[i, 0] + sy))))
    return kern * (pixel_angle ** 2) * t * t


def layer_coordinate(t):
    """The layers' coordinate of optical depth T: ln T + LAYER_SLOPE T (``emitter_glow.log_linear``).  The layers
    are even in it, geometric where T << 1 (the kernel's shape changes with ln T) and at most
    MAX_LAYER_STEP / LAYER_SLOPE apart in T where T >> 1 (the multiply scattered halo widens with T itself)."""
    from .precompute.physics.emitter import emitter_glow
    return emitter_glow.log_linear(t, LAYER_SLOPE)


def layer_depths(lo, hi, count):
    """``count`` optical depths from ``lo`` to ``hi``, even in ``layer_coordinate``."""
    from .precompute.physics.emitter import emitter_glow
    return emitter_glow.log_linear_depths(lo, hi, count, LAYER_SLOPE)


def add_weather(image, depth, visibility_m, anisotropy=0.85, sky=(1.0, 1.0, 1.0), fov_deg=39.6, albedo=0.9,
                scale=1.0, layers=LAYERS, progress=None):
    """``image`` (H, W, 3) linear radiance with fog added (module docstring).  ``depth`` (H, W) distance from the
    camera (Blender units, times ``scale`` m each); ``visibility_m``: the meteorological visibility, beta =
    3.912 / V (Koschmieder); ``sky``: the horizon's radiance A (RGB); ``fov_deg``: the horizontal field of view;
    ``albedo``: W0 of the multiply scattered light; ``progress(k, n, T)``: called per layer."""
    image = np.asarray(image, np.float64)
    depth = np.asarray(depth, np.float64)
    if image.ndim != 3 or image.shape[2] < 3:
        raise WeatherError(f"the image must have RGB channels, got shape {image.shape}")
    if depth.shape != image.shape[:2]:
        raise WeatherError(f"the depth map is {depth.shape[1]}x{depth.shape[0]} but the image "
                           f"{image.shape[1]}x{image.shape[0]}")
    if not (math.isfinite(visibility_m) and visibility_m > 0.0):
        raise WeatherError(f"--visibility must be a positive number of metres, got {visibility_m}")
    if not (math.isfinite(fov_deg) and 0.0 < fov_deg < 180.0):
        raise WeatherError(f"--fov must be in (0, 180) degrees, got {fov_deg}")
    if not (-0.95 <= anisotropy <= 0.95):
        raise WeatherError(f"--anisotropy must be in [-0.95, 0.95], got {anisotropy}")
    if np.any(np.isnan(depth)) or np.any(depth < 0.0):
        raise WeatherError("the depth map holds negative or NaN values")
    image = np.nan_to_num(np.maximum(image[..., :3], 0.0), nan=0.0, posinf=0.0)
    beta = 3.912 / float(visibility_m)
    sky_px = ~(depth < SKY_DEPTH)
    t = np.where(sky_px, np.inf, depth * float(scale) * beta)
    trans = np.exp(-t)[..., None]
    out = image * trans + np.asarray(sky, float)[None, None, :3] * (1.0 - trans)
    ground = ~sky_px & (t > 0.0)
    if not ground.any():
        return out.astype(np.float32)
    h, w = depth.shape
    pixel_angle = math.radians(fov_deg) / w
    single, multiple_ = _fields(float(anisotropy), float(albedo))
    lo, hi = float(t[ground].min()), float(t[ground].max())
    lo, hi = max(lo, 1e-3), max(hi, lo * 1.0001, 1.1e-3)
    layers = max(int(layers), int(math.ceil((layer_coordinate(hi) - layer_coordinate(lo)) / MAX_LAYER_STEP)) + 1)
    ts = layer_depths(lo, hi, layers)
    pos = np.interp(layer_coordinate(np.maximum(t, 1e-3)), layer_coordinate(ts), np.arange(layers))
    shape = (2 * h, 2 * w)
    glow = np.zeros((h, w, 3))
    for k, tk in enumerate(ts):
        weight = np.where(ground, np.clip(1.0 - np.abs(pos - k), 0.0, 1.0), 0.0)
        if not weight.any():
            continue
        if progress:
            progress(k + 1, layers, tk)
        kern = np.fft.rfft2(glow_kernel(shape, pixel_angle, tk, single, multiple_, float(albedo)))
        layer = np.pad(weight[..., None] * image, ((0, h), (0, w), (0, 0)))
        for c in range(3):
            glow[..., c] += np.fft.irfft2(np.fft.rfft2(layer[..., c]) * kern, s=shape)[:h, :w]
    return (out + np.maximum(glow, 0.0)).astype(np.float32)


# -- reading the picture and its depth ------------------------------------------------------------------------
#
# The physics needs linear radiance and metres; a file says what it holds only through its channels' names and
# types.  A multilayer EXR (Blender: one part per pass, channels "<layer>.<pass>.<channel>") holds many passes,
# so the picture and the depth are chosen by name, never by position, and anything a name does not settle is
# refused with the channels found.  An integer image is display-referred: its levels are sRGB-encoded light
# (decoded with a note) and never metres (refused as depth).

COMPOSITE_LAYER = "Composite"   # Blender's compositor output, written beside the view layers' passes


def describe_channels(chans):
    """The channels as a user reads them, grouped by pass: "ViewLayer.Combined (R, G, B, A); ViewLayer.Depth (Z)"
    ("R, G, B" for a file without layers)."""
    groups = {}
    for c in chans:
        groups.setdefault(c.pass_name, []).append(c.suffix)
    return "; ".join(f"{p} ({', '.join(x)})" if p else ", ".join(x) for p, x in groups.items())


def _passes(chans):
    """{pass name: [Channel]} in file order ("" holds the channels without layers: R, G, B, A, Z, Y)."""
    out = {}
    for c in chans:
        out.setdefault(c.pass_name, []).append(c)
    return out


def _rgb(pass_chans):
    """The R, G, B channels of one pass (in that order), or None."""
    by = {c.suffix.upper(): c for c in pass_chans}
    return [by[x] for x in "RGB"] if all(x in by for x in "RGB") else None


def _grey(pass_chans):
    """The one grey channel of a pass without R, G, B (Y, or a lone channel beside an alpha), or None."""
    rest = [c for c in pass_chans if c.suffix.upper() != "A"]
    if len(rest) == 1 and (rest[0].suffix.upper() == "Y" or len(pass_chans) <= 2):
        return rest[0]
    return None


def image_channels(chans, path, image_pass=None):
    """(channels, what): the R, G, B ``Channel``s of IMAGE (one grey channel for a grey image) and a phrase
    naming them.  With ``image_pass`` that pass; else the file's plain R, G, B, or in a multilayer EXR its
    Combined pass: the one there is, or among several Blender's composite ("Composite.Combined", the picture
    the compositor made of the view layers).  Anything else is a WeatherError naming the channels found."""
    passes = _passes(chans)
    found = describe_channels(chans)
    if image_pass is not None:
        if image_pass not in passes:
            raise WeatherError(f"{path}: no pass {image_pass!r} (--image-pass); its channels: {found}")
        rgb = _rgb(passes[image_pass])
        if rgb is None:
            raise WeatherError(f"{path}: the pass {image_pass!r} has no R, G, B channels; its channels: {found}")
        return rgb, f"{image_pass} (R, G, B)"
    cands = [p for p in passes if (p == "" or p.rpartition(".")[2].lower() == "combined") and _rgb(passes[p])]
    why = ""
    if len(cands) > 1:
        composite = [p for p in cands if p.split(".")[0] == COMPOSITE_LAYER]
        if len(composite) == 1:
            other = next(p for p in cands if p != composite[0]) or "''"
            cands = composite
            why = f" (the compositor's picture; --image-pass {other} for the render's own)"
        else:
            raise WeatherError(f"{path}: several pictures ({', '.join(p or 'R, G, B' for p in cands)}); choose one "
                               f"with --image-pass (channels: {found})")
    if cands:
        return _rgb(passes[cands[0]]), (f"{cands[0]} (R, G, B)" if cands[0] else "R, G, B") + why
    if len(passes) == 1:
        grey = _grey(next(iter(passes.values())))
        if grey is not None:
            return [grey], f"{grey.name} (grey, as R = G = B)"
    raise WeatherError(f"{path}: no picture to fog: no R, G, B channels without a layer, and no Combined pass "
                       f"(a multilayer EXR's <layer>.Combined.R, G, B); its channels: {found}")


def _is_depth_name(name):
    """Whether a channel's name says it holds depth: "Z" or "depth" alone, a pass named Depth or Z
    ("ViewLayer.Depth.Z", "depth.Z"), or a last component "depth".  Blender's Mist ("ViewLayer.Mist.Z", 0-1) and
    the Z of Position, Normal and Vector are not depth."""
    parts = name.split(".")
    last = parts[-1].lower()
    if last == "depth":
        return True
    return last == "z" and (len(parts) == 1 or parts[-2].lower() in ("depth", "z"))


def _bits(channel):
    """"8-bit" for uint8 (and int8), "16-bit" for uint16 (and int16), else the type's name."""
    return {"uint8": "8-bit", "int8": "8-bit", "uint16": "16-bit", "int16": "16-bit"}.get(channel.format,
                                                                                          channel.format)


def _integer_depth_message(path, chans):
    """Why an integer DEPTH is refused, and what to give instead."""
    return (f"{path} is an integer image ({_bits(chans[0])}; {describe_channels(chans)}): it holds grey levels "
            "of a picture, not metres, so it cannot be a depth map.  Give a float EXR of the distance in metres: "
            "Blender's Depth pass (a multilayer EXR with the Z pass on, or the Depth pass saved alone as OpenEXR), "
            "or your depth map converted to metres and saved as a float EXR (--scale converts other units)")


def depth_channel(chans, path, depth_pass=None):
    """The ``Channel`` of DEPTH that holds the distance: with ``depth_pass``, that channel (a full name,
    "ViewLayer.Depth.Z") or the one channel (or Z) of that pass ("ViewLayer.Depth"); else a file's only
    channel (unless it is Blender's Mist, 0-1), or its one channel named as depth (``_is_depth_name``:
    Blender's "ViewLayer.Depth.Z", a plain EXR's "Z").  Several, or none in a file of several channels, is a
    WeatherError naming them.  An integer channel (PNG, JPEG) holds no metres and is refused."""
    found = describe_channels(chans)
    if depth_pass is not None:
        exact = [c for c in chans if c.name == depth_pass]
        of_pass = [c for c in chans if c.pass_name == depth_pass]
        zs = [c for c in of_pass if c.suffix.upper() == "Z"]
        pick = exact or (of_pass if len(of_pass) == 1 else zs)
        if len(pick) != 1:
            raise WeatherError(f"{path}: --depth-pass {depth_pass!r} names no single channel; its channels: {found}")
        chosen = pick[0]
    elif len(chans) == 1:
        chosen = chans[0]
        if chosen.pass_name.rpartition(".")[2].lower() == "mist":
            raise WeatherError(f"{path}: its one channel, {chosen.name}, is Blender's Mist pass (0 to 1 between the "
                               "mist's start and depth), not metres.  Give the Depth (Z) pass, or name this channel "
                               "with --depth-pass to use it anyway")
    else:
        if not any(c.is_float for c in chans):
            raise WeatherError(_integer_depth_message(path, chans))
        cands = [c for c in chans if _is_depth_name(c.name)]
        if len(cands) > 1:
            raise WeatherError(f"{path}: several depth channels ({', '.join(c.name for c in cands)}); choose one "
                               f"with --depth-pass (channels: {found})")
        if not cands:
            raise WeatherError(f"{path}: no depth channel (Z, or a multilayer EXR's <layer>.Depth.Z) among its "
                               f"channels: {found}.  Give a single-channel EXR of the distance in metres, an EXR "
                               f"with a Z channel, or name the channel with --depth-pass")
        chosen = cands[0]
    if not chosen.is_float:
        raise WeatherError(_integer_depth_message(path, [chosen]))
    return chosen


def _linear_light(arr, chans, path, note):
    """``arr`` as linear light: float channels as they are (scene-referred, as EXR holds them); integer ones
    decoded from sRGB unless the file says it is linear, with a note either way."""
    if all(c.is_float for c in chans):
        return arr
    c0 = chans[0]
    if "lin" in c0.colorspace.lower():
        note(f"{path} is an integer image ({_bits(c0)}) that says it is linear ({c0.colorspace}): read as linear "
             "light")
        return arr
    note(f"{path} is a display-referred integer image ({_bits(c0)}): converted from sRGB to linear light.  Its "
         "highlights are clipped at 1, so lamps and windows glow less than they would in an HDR EXR of the scene")
    from . import imageio
    return imageio.srgb_to_linear(arr)


def read_image(path, image_pass=None, note=None):
    """IMAGE as linear radiance (H, W, 3) float32: the channels ``image_channels`` chooses, grey broadcast to
    R = G = B, an integer image decoded from sRGB (``_linear_light``).  ``note(text)`` is told what was read."""
    from . import imageio
    note = note or (lambda text: None)
    chans = imageio.channels(path)
    picked, what = image_channels(chans, path, image_pass)
    arr = _linear_light(imageio.read_channels(path, picked), picked, path, note)
    if arr.shape[2] == 1:
        arr = np.repeat(arr, 3, axis=2)
    note(f"image: {what} of {path}")
    return np.ascontiguousarray(arr, np.float32)


def read_depth(path, depth_pass=None, note=None):
    """DEPTH as (H, W) float64, the value of one channel (``depth_channel``): a single-channel float EXR (or
    float image), else the channel named as depth, e.g. the Z of a plain EXR's R, G, B, A, Z or Blender's
    multilayer "<layer>.Depth.Z"; ``depth_pass`` names it when the names do not settle it.  The values are taken
    as metres (times ``--scale``) from the camera; Blender's Depth pass is the distance along the view axis,
    the same as along the pixel's ray only at the centre of the picture.  ``note(text)`` is told what was read."""
    return read_depth_channel(path, depth_pass, note)[0]


def read_depth_channel(path, depth_pass=None, note=None):
    """(``read_depth``'s array, the ``Channel`` it was read from)."""
    from . import imageio
    note = note or (lambda text: None)
    chans = imageio.channels(path)
    chosen = depth_channel(chans, path, depth_pass)
    note(f"depth: {chosen.name} of {path}")
    return np.asarray(imageio.read_channels(path, [chosen])[..., 0], np.float64), chosen


def is_view_depth(channel):
    """Whether ``channel`` is Blender's Depth pass ("<layer>.Depth.Z"): depth along the view axis, not along the
    pixel's ray."""
    return channel.pass_name.rpartition(".")[2].lower() == "depth"


def ray_distance(z, fov_deg):
    """(H, W) distance along each pixel centre's ray from depth along the view axis ``z`` (a pinhole camera whose
    horizontal field of view ``fov_deg`` spans the width, square pixels): z / cos(angle to the axis), the sky
    (>= SKY_DEPTH) kept as it is."""
    z = np.asarray(z, np.float64)
    h, w = z.shape
    t = math.tan(math.radians(fov_deg) / 2.0) / (w / 2.0)   # tan per pixel at unit depth
    y, x = np.mgrid[0:h, 0:w]
    tan2 = (t * (x + 0.5 - w / 2.0)) ** 2 + (t * (y + 0.5 - h / 2.0)) ** 2
    return np.where(z >= SKY_DEPTH, z, z * np.sqrt(1.0 + tan2))


def run(image_path, depth_path, out_path, visibility_m, anisotropy=0.85, sky=(1.0, 1.0, 1.0), fov_deg=39.6,
        albedo=0.9, scale=1.0, stream=sys.stderr, image_pass=None, depth_pass=None, depth_kind="auto"):
    """The command line's ``weather``: read (``read_image``, ``read_depth``: what was read is said on ``stream``),
    add the weather with progress on ``stream``, write an EXR.  ``depth_kind``: "distance" (along each pixel's
    ray, what ``add_weather`` takes), "z" (along the view axis: turned into distance, ``ray_distance``) or "auto"
    (Blender's Depth pass is z, anything else distance)."""
    from . import imageio

    def note(text):
        print(f"weather: {text}", file=stream, flush=True)
    image = read_image(image_path, image_pass, note)
    depth, channel = read_depth_channel(depth_path, depth_pass, note)
    if depth_kind == "z" or (depth_kind == "auto" and is_view_depth(channel)):
        depth = ray_distance(depth, fov_deg)
        note(f"depth: {channel.name} taken as depth along the view axis and turned into distance along each "
             f"pixel's ray (horizontal field of view {fov_deg:g} degrees)")

    def progress(k, n, t):
        print(f"weather: layer {k}/{n} (optical depth {t:.3g})", file=stream, flush=True)
    print(f"weather: {image.shape[1]}x{image.shape[0]}, visibility {visibility_m:g} m, g {anisotropy:g}; the "
          "multiple-scattering table is baked once per g (10-20 s)", file=stream, flush=True)
    out = add_weather(image, depth, visibility_m, anisotropy, sky, fov_deg, albedo, scale, progress=progress)
    imageio.write_exr(out_path, out)
    print(f"weather: wrote {out_path}", file=stream, flush=True)
    return out
