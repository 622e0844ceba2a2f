"""Glowing objects' glows (issue 28, item 3): ``precompute/emitter_glow.py`` (the point spread function of a
depth as a ladder of Gaussian blurs) and the Compositor method's glow of an emissive sphere against Cycles.

The render compares ``fog_scenes/glowing_sphere.py``'s sphere (radius 0.15 m, radiance 100, 15 m away; fog
beta 0.1, g 0.85, albedo 0.9, T 1.5) with the path-traced single scattering by annulus means, as
test_weather.py does.  Both render pixel centres: 112 pixel centres fall on the sphere's disc of 103.1 px, so
the Emission pass holds 8.6 % more light than the sphere sends into the fog; the glow (ours less the
fog-free render dimmed) is scaled to the disc's area before comparing (unscaled it is about 5 % too bright).
Measured, ours / reference by annulus 1.5-50 px: 1.004, 1.002, 0.984, 0.954, 0.958.
"""
import math

import numpy as np
import pytest

from fog_addon import imageio
from fog_addon.precompute import emitter_glow as eg

G = 0.85
PIXEL_ANGLE = math.radians(0.1)


@pytest.fixture(scope="module")
def single():
    return eg.single_field(G)


def test_nnls_against_scipy():
    """The add-on's own non-negative least squares (numpy only) finds scipy's solution."""
    from scipy.optimize import nnls
    rng = np.random.default_rng(4)
    for _ in range(20):
        a = rng.normal(size=(40, 8))
        b = rng.normal(size=40)
        ours = eg._nnls(a, b)
        theirs = nnls(a, b)[0]
        assert np.all(ours >= 0.0)
        assert np.linalg.norm(a @ ours - b) == pytest.approx(np.linalg.norm(a @ theirs - b), rel=1e-9, abs=1e-12)


def test_blur_weights_are_blenders_gaussian():
    """Blender's Gaussian Blur of size S: sigma = S / 3 (measured on the node: 1.33 px at S = 4, 10.5 at 32),
    cut at |i| <= S, unit sum."""
    for size in (4, 32, 256):
        w = eg.blur_weights(size)
        i = np.arange(len(w)) - size
        assert len(w) == 2 * size + 1 and w.sum() == pytest.approx(1.0)
        assert math.sqrt(float(np.sum(w * i * i))) == pytest.approx(size / 3.0, rel=0.02)
    assert list(eg.blur_weights(0)) == [1.0]


@pytest.mark.parametrize("t", [0.01, 0.3, 1.5, 4.5, 20.0])
def test_ladder_holds_the_kernel_ring_by_ring(single, t):
    """The ladder's fit against the kernel it fits (the airlight field at extinction 1, itself against
    quadrature in test_airlight.py): ring sums within 3 % out to 120 px, 11 % beyond, the whole within 0.5 %."""
    half = 300
    kern = eg.kernel_grid(t, PIXEL_ANGLE, single, 1.0, half)
    a = eg.fit_weights(kern)
    approx = sum(w * eg.blur_kernel_2d(s, half) for w, s in zip(a, eg.SIZES))
    d = np.arange(-half, half + 1)
    r = np.hypot(*np.meshgrid(d, d))
    for lo, hi, bound in ((0, 1.5, 0.03), (1.5, 7.5, 0.03), (7.5, 30, 0.03), (30, 120, 0.03), (120, 300, 0.11)):
        ring = (r >= lo) & (r < hi)
        assert approx[ring].sum() / kern[ring].sum() == pytest.approx(1.0, abs=bound), (t, lo, hi)
    assert approx.sum() / kern.sum() == pytest.approx(1.0, abs=5e-3)


def test_weights_table_is_finite_and_non_negative():
    table = eg.bake_table(G, PIXEL_ANGLE)
    assert table.shape == (len(eg.SIZES), eg.T_COUNT)
    assert np.isfinite(table).all() and (table >= 0.0).all() and table.max() > 0.0


@pytest.mark.render
@pytest.mark.parametrize("engine,beta,dense", [
    ("cycles", 0.1, False),
    pytest.param("eevee", 0.1, False, marks=pytest.mark.slow),
    pytest.param("cycles", 0.1, True, marks=pytest.mark.slow),
    pytest.param("cycles", 0.3, True, marks=pytest.mark.slow),
])
def test_glowing_sphere_against_path_traced_fog(tmp_path, engine, beta, dense):
    """Single scattering against 0 volume bounces; with Dense Fog (the multiply scattered field in the kernel)
    against 64 bounces at T 1.5 and 4.5, measured 1.006, 1.003, 0.987, 0.941, 0.991 and 1.017, 1.033, 1.058,
    1.009, 1.018."""
    from fog_scenes import dense as dn
    from fog_scenes import glowing_sphere as gs
    from fog_scenes import render_harness as h
    root = h.REFERENCES / "glowing_sphere_d15_R0.15_L100_120x120"
    ref = imageio.read_rgb(f"{root}_beta{beta}_g0.85_a0.9_" + ("vb64_1024spp_x2.exr" if dense else "vb0_4096spp_x2.exr"))
    clear = imageio.read_rgb(f"{root}_clear.exr")
    log = []
    out = h.render_test("glowing_sphere", beta, tmp_path / "ours.exr", engine=engine, resolution=gs.RESOLUTION,
                        blend=gs.blend_path(workdir=tmp_path), log=log,
                        extra=("--anisotropy", repr(G), "--color", "0.9,0.9,0.9", "--multiple-scattering",
                               "on" if dense else "off"))
    assert not h.log_errors(log[0]), h.log_errors(log[0])
    assert "Method Auto: Compositor (glowing objects (GlowingSphere)" in log[0]
    ours = imageio.read_rgb(out)
    assert np.isfinite(ours).all()
    direct = clear * math.exp(-beta * gs.DISTANCE_M)
    disc = math.pi * gs.sphere_pixel_radius() ** 2 / np.count_nonzero(clear[..., 0] > 0.0)
    scaled = direct + (ours - direct) * disc
    ratio = np.array(dn.ring_means(scaled, gs.image_centre())) / np.array(dn.ring_means(ref, gs.image_centre()))
    print(f"{engine} beta {beta} dense {dense}: ours / path traced by annulus {np.round(ratio, 3)}")
    assert np.all(np.abs(ratio - 1.0) <= 0.06), ratio
