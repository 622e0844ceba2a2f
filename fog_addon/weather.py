"""Weather on photographs: fog added to a linear HDR image with a depth map (Narasimhan et al. ``002`` §8),
numpy only (images through ``imageio``).

Each pixel is a small source seen through the fog.  With depth z and extinction beta (T = beta z), its own light
reaches the camera dimmed, the fog in front of it adds the horizon's light (Koschmieder; Narasimhan Eq. 30-31),
and the light it sends into the fog comes back as a glow around it:

    out = L e^{-T} + A (1 - e^{-T}) + sum over pixels s of L_s K(T_s, theta),
    K(T, theta) = Omega_px T^2 W0 [ I_1(T, theta) + I_{>=2}(T, theta) / W0 ],

Omega_px the pixel's solid angle (sr), I_1 the single-scattering field of an endless ray (Sun et al. 2005 Eq. 12,
the airlight table at extinction 1) and I_{>=2} the multiply scattered field (``precompute/multiple.py``), both per
unit intensity: a patch of radiance L filling a pixel at depth z has intensity L Omega_px z^2, and the field at
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
    """Bad input to ``add_weather``: a message a user understands."""


def _fields(g, albedo):
    """(single, multiple): functions (T, cos theta) -> I_1 and I_{>=2} / W0 per unit intensity (extinction 1)."""
    from .precompute import bakers, emitter_glow, multiple
    from .precompute.ops import NumpyOps
    spec = multiple.table_spec(g, albedo)
    m = NumpyOps({spec.name: bakers.table_array(spec, g)})
    return emitter_glow.single_field(g), (lambda t, c: multiple.field(m, spec, t, c))


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
    from .precompute import emitter_glow
    return emitter_glow.log_linear(t, LAYER_SLOPE)


def layer_depths(lo, hi, count):
    """``count`` optical depths from ``lo`` to ``hi``, even in ``layer_coordinate``."""
    from .precompute import emitter_glow
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


def read_depth(path):
    """The depth map of ``path``: a single-channel EXR (or image), or the Z / depth channel of a multi-channel one
    (else its first channel)."""
    from . import imageio
    arr = imageio.read(path)
    if arr.ndim == 3 and arr.shape[2] > 1:
        arr = arr[..., 0]
    return np.asarray(arr, np.float64).reshape(arr.shape[:2])


def run(image_path, depth_path, out_path, visibility_m, anisotropy=0.85, sky=(1.0, 1.0, 1.0), fov_deg=39.6,
        albedo=0.9, scale=1.0, stream=sys.stderr):
    """The command line's ``weather``: read, add the weather with progress on ``stream``, write an EXR."""
    from . import imageio
    image = imageio.read_rgb(image_path)
    depth = read_depth(depth_path)

    def progress(k, n, t):
        print(f"weather: layer {k}/{n} (optical depth {t:.3g})", file=stream, flush=True)
    print(f"weather: {image.shape[1]}x{image.shape[0]}, visibility {visibility_m:g} m, g {anisotropy:g}; the "
          "multiple-scattering table is baked once per g (about a minute)", file=stream, flush=True)
    out = add_weather(image, depth, visibility_m, anisotropy, sky, fov_deg, albedo, scale, progress=progress)
    imageio.write_exr(out_path, out)
    print(f"weather: wrote {out_path}", file=stream, flush=True)
    return out
