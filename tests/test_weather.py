"""Weather on photographs (issue 28, item 4; ``fog_addon/weather.py``, ``python -m fog_addon weather``).

Independent sources: Cycles' path-traced World volume with 64 volume bounces around a point lamp
(``fog_scenes/dense.py``'s reference), which a lamp's pixels with their depth must glow like; Koschmieder's
law (a black surface at depth z takes A (1 - e^{-beta z})); the sky (infinite depth) is the horizon's light.
"""
import math
import subprocess
import sys

import numpy as np
import pytest

from fog_addon import imageio, weather
from fog_scenes import dense as dn

BOUND = 0.09   # measured (docs/measurements/2026-11-27-multiple-scattering.md)


def lamp_picture(distance=15.0, power=1000.0, size=120, deg_per_px=0.1):
    """A fog-free picture of an isotropic lamp of ``power`` W at ``distance`` m on the axis of a camera of
    ``deg_per_px``: its intensity spread over the 4 pixels around the image centre (radiance I0 / (Omega z^2)),
    the rest sky."""
    img = np.zeros((size, size, 3))
    depth = np.full((size, size), 1e10)
    omega = math.radians(deg_per_px) ** 2
    c = size // 2
    img[c - 1:c + 1, c - 1:c + 1] = power / (4.0 * math.pi) / (omega * distance ** 2) / 4.0
    depth[c - 1:c + 1, c - 1:c + 1] = distance
    return img, depth


def test_a_lamps_pixels_glow_like_path_traced_fog():
    """The lamp's pixels, fogged at visibility 13 m (beta 0.3, g 0.85, albedo 0.9, T 4.5), against Cycles with
    64 volume bounces: the issue's annuli (1.5 to 50 px) within BOUND."""
    ref = imageio.read_rgb(dn.render_ms_reference(15.0, 0.3, 0.85, 0.9, volume_bounces=64, samples=2048, seeds=4))
    img, depth = lamp_picture()
    out = weather.add_weather(img, depth, 3.912 / 0.3, anisotropy=0.85, sky=(0.0, 0.0, 0.0), fov_deg=12.0,
                              albedo=0.9)
    centre = (60.0, 60.0)
    ratio = np.array(dn.ring_means(out, centre)) / np.array(dn.ring_means(ref, centre))
    print("weather / 64 bounces:", np.round(ratio, 3))
    assert np.all(np.abs(ratio - 1.0) <= BOUND), ratio


def test_koschmieder_and_the_sky():
    """A black surface at depth z takes A (1 - e^{-beta z}); the sky is A; nothing glows."""
    depth = np.full((8, 10), 40.0)
    depth[:3] = 1e10
    out = weather.add_weather(np.zeros((8, 10, 3)), depth, 500.0, sky=(0.5, 0.6, 0.7), fov_deg=30.0)
    beta = 3.912 / 500.0
    np.testing.assert_allclose(out[5, 5], np.array([0.5, 0.6, 0.7]) * (1.0 - math.exp(-beta * 40.0)), rtol=1e-6)
    np.testing.assert_allclose(out[0, 0], [0.5, 0.6, 0.7], rtol=1e-6)


def test_bad_input_is_refused():
    img = np.zeros((4, 4, 3))
    with pytest.raises(weather.WeatherError, match="depth map is"):
        weather.add_weather(img, np.ones((4, 5)), 100.0)
    with pytest.raises(weather.WeatherError, match="negative or NaN"):
        weather.add_weather(img, np.full((4, 4), np.nan), 100.0)
    with pytest.raises(weather.WeatherError, match="visibility"):
        weather.add_weather(img, np.ones((4, 4)), 0.0)


@pytest.mark.parametrize("t_source", [1.6, 7.9, 13.5, 20.8])
def test_a_pixel_between_layers_glows_with_its_own_kernel(t_source):
    """One bright pixel among black ones whose depths span T 0.01-30, its glow against ``glow_kernel`` at its own
    T (the field at that T, evaluated directly): ring sums 1-30 px within 2.5 % (measured within 1.7 % over 40 T
    from 0.02 to 25).  With 16 layers even in ln T, read linearly, it was 0.96 at T 1.6, 1.4-2.1 at T 7.9 and
    1.5-2.6 at T 13.5."""
    size, fov = 64, 3.2
    visibility = 3.912 / 0.1                            # beta 0.1: depth = 10 T
    img = np.zeros((size, size, 3))
    img[32, 32] = 100.0
    depth = np.full((size, size), 10.0 * t_source)
    depth[0, 0], depth[0, 1] = 0.1, 300.0                # black pixels at T 0.01 and 30 set the layers' range
    out = weather.add_weather(img, depth, visibility, 0.85, sky=(0.0, 0.0, 0.0), fov_deg=fov)[..., 0]
    glow = out - img[..., 0] * np.exp(-t_source)
    single, multiple_ = weather._fields(0.85, 0.9)
    kern = np.fft.fftshift(weather.glow_kernel((2 * size, 2 * size), math.radians(fov) / size, t_source, single,
                                               multiple_, 0.9))[size - 32:size + 32, size - 32:size + 32] * 100.0
    d = np.hypot(*np.meshgrid(np.arange(size) - 32, np.arange(size) - 32))
    for lo, hi in ((1, 3), (3, 8), (8, 15), (15, 30)):
        ring = (d >= lo) & (d < hi)
        assert glow[ring].sum() / kern[ring].sum() == pytest.approx(1.0, abs=0.025), (t_source, lo, hi)


def test_layer_depths_are_even_in_their_coordinate():
    t = weather.layer_depths(0.01, 30.0, 40)
    assert t[0] == 0.01 and t[-1] == 30.0 and np.all(np.diff(t) > 0)
    np.testing.assert_allclose(np.diff(weather.layer_coordinate(t)), np.diff(weather.layer_coordinate(t)).mean(),
                               rtol=1e-9)


def test_command_line(tmp_path):
    """``python -m fog_addon weather`` writes the fogged EXR and reports each layer; a bad flag exits 2."""
    img, depth = lamp_picture(size=40)
    img[:] = 0.0
    img[18:22, 8:12] = 5.0   # a window in a black wall on the left half, 30 m away
    depth[:, :20] = 30.0
    imageio.write_exr(tmp_path / "in.exr", img.astype(np.float32))
    imageio.write_exr(tmp_path / "z.exr", depth[..., None].astype(np.float32))
    cmd = [sys.executable, "-m", "fog_addon", "weather", str(tmp_path / "in.exr"), "--depth", str(tmp_path / "z.exr"),
           "--visibility", "50", "--sky", "0.2,0.2,0.3", "--fov", "4", "--out", str(tmp_path / "out.exr")]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert "weather: layer" in proc.stderr and "wrote" in proc.stderr
    out = imageio.read_rgb(tmp_path / "out.exr")
    assert out.shape == (40, 40, 3) and np.isfinite(out).all()
    assert out[20, 10, 0] > out[20, 17, 0] > 0.2 * (1.0 - math.exp(-3.912 / 50.0 * 30.0))   # the window glows
    np.testing.assert_allclose(out[0, -1], [0.2, 0.2, 0.3], rtol=0.02)   # the sky, and a little of the glow
    bad = subprocess.run(cmd[:-4] + ["--visibility", "-1", "--out", str(tmp_path / "x.exr")], capture_output=True,
                         text=True)
    assert bad.returncode == 2 and "visibility" in bad.stderr


@pytest.mark.slow
@pytest.mark.parametrize("beta", [0.1, 0.3])
def test_a_rendered_glowing_sphere_against_path_traced_fog(beta):
    """A fog-free Cycles render of an emissive sphere 15 m away with its distance pass, fogged by ``weather``
    (T 1.5 and 4.5, g 0.85, albedo 0.9), against Cycles' World volume with 64 bounces of the same scene
    (``fog_scenes/glowing_sphere.py``), in the three annuli off the sphere's disc (7.5 to 50 px): within 4 %
    (measured 0.989-0.995).  The render samples pixel centres: 112 of them fall on a disc of 103.1 px, so its
    light is scaled to the disc's area first (unscaled, the glow is that 8.6 % too bright)."""
    from fog_scenes import glowing_sphere as gs
    root = dn.h.REFERENCES / "glowing_sphere_d15_R0.15_L100_120x120"
    clear = imageio.read_rgb(f"{root}_clear.exr")
    distance = weather.read_depth(f"{root}_clear_distance.exr")
    clear *= math.pi * gs.sphere_pixel_radius() ** 2 / np.count_nonzero(clear[..., 0] > 0.0)
    ref = imageio.read_rgb(f"{root}_beta{beta}_g0.85_a0.9_vb64_1024spp_x2.exr")
    out = weather.add_weather(clear, distance, 3.912 / beta, anisotropy=0.85, sky=(0.0, 0.0, 0.0), fov_deg=11.956,
                              albedo=0.9)
    ratio = (np.array(dn.ring_means(out, gs.image_centre())) / np.array(dn.ring_means(ref, gs.image_centre())))[2:]
    print("weather / 64 bounces (sphere), 7.5-50 px:", np.round(ratio, 3))
    assert np.all(np.abs(ratio - 1.0) <= 0.04), ratio
