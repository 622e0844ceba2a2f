"""Glowing objects' glows (issue 28, item 3): ``precompute/physics/emitter/emitter_glow.py`` (the point spread function
of a depth as a ladder of Gaussian blurs) and the Compositor method's glow of an emissive sphere against Cycles.

The render compares ``fog_scenes/glowing_sphere.py``'s sphere (radius 0.15 m, radiance 100, 15 m away; fog
beta 0.1, g 0.85, albedo 0.9, T 1.5) with the path-traced single scattering by annulus means, as
test_weather.py does.  Both render pixel centres: 112 pixel centres fall on the sphere's disc of 103.1 px, so
the Emission pass holds 8.6 % more light than the sphere sends into the fog; the glow (ours less the
fog-free render dimmed) is scaled to the disc's area before comparing (unscaled it is about 5 % too bright).
Measured, ours / reference by annulus 1.5-50 px: 1.007, 1.008, 1.055, 1.021, 1.024.
"""
import math

import numpy as np
import pytest

from fog_addon import imageio
from fog_addon.precompute.model import bakers
from fog_addon.precompute.physics.emitter import emitter_glow as eg

G = 0.85
PIXEL_ANGLE = math.radians(0.1)


@pytest.fixture(scope="module")
def single():
    return eg.single_field(G, bakers.READER)


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
    """The ladder's fit of the kernel's near part, plus its far part (K times the far window, which the points'
    glows carry), against the whole kernel (the airlight field at extinction 1, itself against quadrature in
    test_airlight.py): ring sums within 3 % out to 120 px, 11 % beyond, the whole within 0.5 %."""
    half = 300
    kern = eg.kernel_grid(t, PIXEL_ANGLE, single, 1.0, half, near=False)
    near = eg.kernel_grid(t, PIXEL_ANGLE, single, 1.0, half)
    a = eg.fit_weights(near, scale=kern)
    approx = sum(w * eg.blur_kernel_2d(s, half) for w, s in zip(a, eg.SIZES)) + (kern - near)
    d = np.arange(-half, half + 1)
    r = np.hypot(*np.meshgrid(d, d))
    for lo, hi, bound in ((0, 1.5, 0.03), (1.5, 7.5, 0.03), (7.5, 30, 0.03), (30, 120, 0.03), (120, 300, 0.11)):
        ring = (r >= lo) & (r < hi)
        assert approx[ring].sum() / kern[ring].sum() == pytest.approx(1.0, abs=bound), (t, lo, hi)
    assert approx.sum() / kern.sum() == pytest.approx(1.0, abs=5e-3)


def test_far_window_hands_the_tail_to_the_points():
    """The far window (``emitter_glow.far_window``): 0 near a source, 1 from the far angle on (0.3 rad, or 300 px
    where that is less), a smooth step from a tenth of it."""
    from fog_addon.precompute.core.ops import NumpyOps
    m = NumpyOps()
    for pixel_angle, top in ((0.012, 0.3), (PIXEL_ANGLE, 0.3), (0.0003, 0.09)):
        assert eg.far_angle(pixel_angle) == pytest.approx(top)
        gamma = np.linspace(0.0, 1.2 * top, 61)
        s = eg.far_window(m, gamma, pixel_angle)
        assert s[0] == 0.0 and s[-1] == 1.0 and np.all(np.diff(s) >= 0.0)
        assert np.all(s[gamma <= top / 10.0] == 0.0) and np.all(s[gamma >= top] == 1.0)


def test_weights_table_is_finite_and_non_negative():
    table = eg.bake_table(G, PIXEL_ANGLE, bakers.READER)
    assert table.shape == (len(eg.SIZES) + 1, eg.T_COUNT)
    shares = table[:-1]
    assert np.isfinite(table).all() and (shares >= 0.0).all()
    np.testing.assert_allclose(shares.sum(axis=0), 1.0, rtol=1e-5)


def test_table_columns_are_the_optical_depths_of_its_coordinate():
    """The columns' T, inverted by Newton's method, map back to evenly spaced table X (``table_x``), from T_MIN to
    T_MAX."""
    from fog_addon.precompute.core.ops import NumpyOps
    t = eg.optical_depths(eg.T_COUNT)
    assert t[0] == pytest.approx(eg.T_MIN, rel=1e-9) and t[-1] == pytest.approx(eg.T_MAX, rel=1e-9)
    np.testing.assert_allclose(eg.table_x(NumpyOps(), t), np.linspace(0.0, 1.0, eg.T_COUNT), atol=1e-9)


@pytest.mark.parametrize("dense", [False, pytest.param(True, marks=pytest.mark.slow)])   # (Dense Fog's: 16-30 s)
def test_the_table_read_between_its_columns_holds_the_kernel(dense):
    """The glow's weights read from the table halfway between two columns (as the compositor reads them:
    ``source_weight`` x ``rung_share``) against the ladder fitted at that very T, ring sums 1.5-160 px: within
    1 % for single scattering, 6 % with Dense Fog's field (whose halo widens between columns; the point table's
    own Monte Carlo noise moves this by 2-3 points from one seed to another: 2.9-5.2 % with the 100k-photon
    walks, 4.3 % with the bounded ones, docs/measurements/2026-11-29-bake-time.md).  A linear read of
    the weights themselves over ln T (24 columns) was 13 % bright at T 4.5 and 3 % dark at T 1.6: a glowing
    object's single scattering read 1.12-1.15 of Cycles' at T 4.5."""
    from fog_addon.precompute.core.ops import NumpyOps
    field = eg.glow_field(G, bakers.READER, 0.9 if dense else None)
    spec = eg.table_spec(G, PIXEL_ANGLE, 0.9 if dense else None)
    m = NumpyOps({spec.name: eg.bake_weights(field, PIXEL_ANGLE, spec.width)})
    columns = eg.optical_depths(spec.width)
    half = 160
    d = np.arange(-half, half + 1)
    r = np.hypot(*np.meshgrid(d, d))
    rings = [(r >= lo) & (r < hi) for lo, hi in ((1.5, 3.5), (3.5, 7.5), (7.5, 15), (15, 30), (30, 50), (50, 160))]
    basis = [eg.blur_kernel_2d(s, half) for s in eg.SIZES]

    def ring_sums(weights):
        k = sum(w * b for w, b in zip(weights, basis))
        return np.array([k[ring].sum() for ring in rings])

    bound = 0.06 if dense else 0.01
    for k in range(1, len(columns)):
        x = (k - 0.5) / (len(columns) - 1)
        t = float(eg.optical_depths(2 * len(columns) - 1)[2 * k - 1])   # the T of table X x
        if t > 12.0:
            break
        assert float(eg.table_x(m, t)) == pytest.approx(x, abs=1e-9)
        read = [float(eg.source_weight(m, spec, t) * eg.rung_share(m, spec, x, j)) * math.exp(-t)
                for j in range(len(eg.SIZES))]
        fitted = eg.fit_weights(eg.kernel_grid(t, PIXEL_ANGLE, field, 1.0, eg.HALF),
                                scale=eg.kernel_grid(t, PIXEL_ANGLE, field, 1.0, eg.HALF, near=False))
        np.testing.assert_allclose(ring_sums(read) / ring_sums(fitted), 1.0, atol=bound, err_msg=f"T {t:.3f}")


def test_facing_mean_against_quadrature():
    """E(c), the mean |n . omega| of a flat emitter's glow, against scipy's double quadrature over theta and the
    azimuth phi (the HG-weighted definition, written out here), and at g = 0 against its closed form
    (4 / pi^2) E_ell(1 - c^2) (2 / pi face-on, 4 / pi^2 edge-on)."""
    from scipy import integrate, special
    c = np.array([0.0, 0.1, 0.4, 0.8, 1.0])
    np.testing.assert_allclose(eg.facing_mean(c, 0.0), 4.0 / np.pi ** 2 * special.ellipe(1.0 - c * c), rtol=1e-5)
    for g, cc in ((0.85, 0.05), (0.5, 0.5), (-0.3, 1.0)):
        hg = lambda th: (1 - g * g) / (1 + g * g + 2 * g * np.sin(th)) ** 1.5
        s = math.sqrt(1.0 - cc * cc)
        num = integrate.dblquad(lambda ph, th: hg(th) * abs(cc * np.sin(th) + s * np.cos(th) * np.cos(ph)),
                                -np.pi / 2, np.pi / 2, 0.0, 2 * np.pi, epsabs=1e-9, epsrel=1e-6)[0]
        den = 2 * np.pi * integrate.quad(hg, -np.pi / 2, np.pi / 2, epsabs=1e-12)[0]
        assert eg.facing_mean(cc, g) == pytest.approx(num / den, rel=2e-4), (g, cc)


def test_facing_dipole_against_quadrature():
    """D(c), the cos(phi) coefficient of a flat emitter's glow, against scipy's double quadrature of its
    definition (the HG-weighted mean over theta of |-c sin(theta) + s cos(phi) cos(theta)|, its first Fourier
    coefficient in phi), and 0 face-on and edge-on."""
    from scipy import integrate
    for g, cc in ((0.85, 0.5), (0.5, 0.2), (0.0, 0.8)):
        hg = lambda th: (1 - g * g) / (1 + g * g + 2 * g * np.sin(th)) ** 1.5
        s = math.sqrt(1.0 - cc * cc)
        num = integrate.dblquad(lambda ph, th: hg(th) * abs(-cc * np.sin(th) + s * np.cos(ph) * np.cos(th))
                                * np.cos(ph), -np.pi / 2, np.pi / 2, 0.0, 2 * np.pi, epsabs=1e-10, epsrel=1e-7)[0]
        den = integrate.quad(hg, -np.pi / 2, np.pi / 2, epsabs=1e-12)[0]
        assert float(eg.facing_dipole(cc, g)) == pytest.approx(num / (math.pi * den), rel=2e-3), (g, cc)
    assert abs(float(eg.facing_dipole(1.0, 0.85))) < 1e-9 and abs(float(eg.facing_dipole(0.0, 0.85))) < 1e-9


def test_glowing_objects_notes():
    """What the fog cannot do with glowing objects is said: no glow but with the compositor, no fog light on other
    surfaces but the compositor's (from points along each, without shadows), no dimming of their light in
    EEVEE."""
    from types import SimpleNamespace
    from fog_addon import caveats
    sign = [SimpleNamespace(name="Neon")]
    assert caveats.glow_notes([], "nodes") == []
    cycles = caveats.glow_notes(sign, "compositor")
    assert len(cycles) == 1 and "from points along each" in cycles[0]
    eevee = caveats.glow_notes(sign, "nodes", "BLENDER_EEVEE_NEXT")
    assert "no glow" in eevee[0] and "does not light other surfaces" in eevee[1] and "not dimmed" in eevee[-1]
    assert len(eevee) == 3


@pytest.mark.parametrize("g", [0.0, 0.7])
def test_a_spheres_pixels_keep_its_glow(g):
    """The pixels of a sphere's disc (c = sqrt(1 - r^2), uniform over the disc) weighted by the facing factor sum to
    the isotropic sources' (the visible hemisphere, two-sided, has the sphere's intensity in every direction): within
    1 % (the limb's c < MIN_FACING is held; without that clamp within 0.1 %); a face-on flat emitter's factor is
    E(1) < 1."""
    from fog_addon.precompute.core.ops import NumpyOps
    m = NumpyOps()
    c = (np.arange(4000) + 0.5) / 4000   # over the disc dA = 2 pi c dc (r^2 = 1 - c^2): the mean is 2 int f c dc
    mean = eg.facing_mean(c, g)
    assert 2.0 * float(np.mean(eg.facing_factor(m, c, mean) * c)) == pytest.approx(1.0, abs=0.01)
    assert 2.0 * float(np.mean(mean)) == pytest.approx(1.0, abs=1e-3)
    assert float(eg.facing_factor(m, 1.0, eg.facing_mean(1.0, g))) < 1.0
    table = eg.bake_facing(g)
    assert table.shape == (2, eg.FACING_COUNT) and np.isfinite(table).all() and (table[0] > 0).all()


@pytest.mark.render
@pytest.mark.parametrize("engine,beta,dense", [
    ("cycles", 0.1, False),
    pytest.param("eevee", 0.1, False, marks=pytest.mark.slow),
    pytest.param("cycles", 0.1, True, marks=pytest.mark.slow),
    pytest.param("cycles", 0.3, True, marks=pytest.mark.slow),
])
def test_glowing_sphere_against_path_traced_fog(tmp_path, engine, beta, dense):
    """Single scattering against 0 volume bounces (measured 1.000, 1.004, 1.046, 1.033, 1.026 by annulus, with the
    pixels' facing factor: the third annulus, just beyond the sphere's limb, is its near field); with Dense Fog (the
    multiply scattered field in the kernel, the pixels isotropic sources) against 64 bounces at T 1.5 and 4.5,
    measured 1.008, 1.006, 1.012, 0.972, 0.987 and 0.996, 1.009, 0.998, 1.002, 1.057 (the ladder holding the near
    kernel, the sphere's point its far part; before, the ladder the whole: 1.007, 1.008, 1.055, 1.021, 1.024;
    1.008, 1.006, 1.018, 0.964, 1.009; 0.994, 1.007, 1.011, 0.980, 1.007)."""
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


@pytest.mark.render
@pytest.mark.slow
@pytest.mark.parametrize("beta,dense", [
    (0.1, True), (0.3, True), (0.1, False), (0.3, False),
])
def test_flat_glowing_square_against_path_traced_fog(tmp_path, beta, dense):
    """A 0.3 m glowing square turned 60 degrees from the camera (``glowing_sphere.py`` shape "flat", a helper's
    references), the rings beside it (its own pixels left out) within 10 % of 64 bounces with Dense Fog (measured
    0.990-1.030 at T 1.5, 0.991-1.090 at T 4.5, the outermost ring the brightest: there the square is its point,
    an isotropic source of its two faces' mean intensity L A / 2 with the Dense Fog lamp's halo; 0.983-1.037 and
    0.985-1.037 while the ladder held the whole kernel, before the points took its far part:
    ``emitter_glow.far_window``) and within 5 % of 0 bounces without (0.989-1.009 at T 1.5 and at T 4.5;
    1.116-1.146 there while the weights' table was read linearly over ln T).  Without Dense Fog each half
    of the picture, left and right of the square, within 8 % ring by ring (measured 0.945-1.063; as isotropic
    sources about each pixel, without the dipole of ``emitter_glow.facing_dipole``, 0.86-0.89 on the right, to
    which the normal leans, and 1.15-1.20 on the left), and the picture within 5 % relative RMSE (measured 0.5 %
    and 2.4 %; 6.0 % and 6.6 % without the square's own pixels, 16 % without the dipole)."""
    from fog_scenes import glowing_sphere as gs
    from fog_scenes import render_harness as h
    vb, spp = (64, 1024) if dense else (0, 4096)
    ref = gs.render_fog_reference(beta, G, 0.9, volume_bounces=vb, samples=spp, seeds=2, shape="flat")
    log = []
    out = gs.render_ours(beta, tmp_path / "ours.exr", multiple_scattering="on" if dense else "off", shape="flat",
                         log=log)
    assert not h.log_errors(log[0]), h.log_errors(log[0])
    ratio = np.asarray(gs.compare_rings(out, ref, beta, shape="flat", leave_out_emitter=True))[1:]
    print(f"flat beta {beta} dense {dense}: ours / path traced by annulus {np.round(ratio, 3)}")
    assert np.all(np.abs(ratio - 1.0) <= (0.10 if dense else 0.05)), ratio
    if not dense:   # the side the square's normal leans to (image right) glows more: each half by itself
        right = np.arange(gs.RESOLUTION[0])[None, :] + 0.5 > gs.image_centre()[0]
        right = np.broadcast_to(right, (gs.RESOLUTION[1], gs.RESOLUTION[0]))
        halves = [np.asarray(gs.compare_rings(out, ref, beta, shape="flat", leave_out_emitter=True,
                                              mask=half))[1:] for half in (~right, right)]
        print(f"flat beta {beta}: left {np.round(halves[0], 3)}, right {np.round(halves[1], 3)}")
        assert all(np.all(np.abs(h - 1.0) <= 0.08) for h in halves), halves
        from fog_addon import compare   # the picture: relative RMSE (issue 28's goal: 5 % in Cycles)
        picture = compare.metrics(gs.area_scaled(imageio.read_rgb(out), beta, shape="flat"), imageio.read_rgb(ref))
        print(f"flat beta {beta}: relative RMSE {picture['rel_rmse']:.4f}")
        assert picture["rel_rmse"] <= 0.05, picture


# --- a neon sign cut by the frame's edge, over a street (tests/scenes/neon_sign.py) ----------------------------

SIGN_BETA = 0.15


def _sign_geometry(shape):
    """(camera, unit ray directions (H, W, 3), ground distance or inf, sign hit mask) of the sign scene."""
    h, w = shape
    half = math.tan(math.atan(18.0 / 50.0))
    u = ((np.arange(w) + 0.5) / w * 2 - 1) * half
    v = (1 - (np.arange(h) + 0.5) / h * 2) * half * h / w
    cam, pitch = np.array([0.0, 0.0, 1.6]), math.radians(85.0)
    fwd = np.array([0.0, math.sin(pitch), -math.cos(pitch)])
    up = np.array([0.0, math.cos(pitch), math.sin(pitch)])
    d = fwd + u[None, :, None] * np.array([1.0, 0.0, 0.0]) + v[:, None, None] * up
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    ground = np.where(d[..., 2] < 0, -cam[2] / np.minimum(d[..., 2], -1e-9), np.inf)
    t = (8.0 - cam[1]) / np.maximum(d[..., 1], 1e-9)
    hit = cam + t[..., None] * d
    sign = (np.abs(hit[..., 0]) <= 0.5) & (np.abs(hit[..., 2] - 2.0) <= 0.5) & (t < ground)
    return cam, d, ground, sign


@pytest.fixture(scope="module")
def sign_renders(tmp_path_factory):
    from fog_scenes import render_harness as h
    tmp = tmp_path_factory.mktemp("sign")
    blend = tmp / "sign.blend"
    h.run([str(h.ROOT / "tests" / "scenes" / "neon_sign.py"), str(blend)])
    out, logs = {}, {}
    for name, method, density in (("clear", "nodes", 0.0), ("nodes", "nodes", SIGN_BETA),
                                  ("compositor", "compositor", SIGN_BETA)):
        log = []
        out[name] = imageio.read_rgb(h.render_test("sign", density, tmp / f"{name}.exr", engine="cycles",
                                                   method=method, resolution=(160, 90), blend=blend, samples=64,
                                                   cast_shadows=True, interreflection=True, log=log,
                                                   extra=("--color", "1,1,1")))
        logs[name] = log[0]
    return out, logs


@pytest.mark.render
def test_a_glowing_objects_light_on_the_ground_is_dimmed(sign_renders):
    """Cycles: the sign's light on the ground dimmed by its own path through the fog, as a light's is: ground
    pixels, fog / fog-free, within 2 % of e^{-beta (D + r)} (D the camera's distance, r the sign's centre's;
    without the dimming it is e^{-beta D}, 1.3-1.6x that)."""
    out, logs = sign_renders
    assert not any(h_ for h_ in logs.values() if "Traceback" in h_)
    cam, d, ground, _ = _sign_geometry(out["clear"].shape[:2])
    for r, c in ((85, 80), (70, 80), (65, 30), (75, 130)):
        point = cam + ground[r, c] * d[r, c]
        want = math.exp(-SIGN_BETA * (ground[r, c] + np.linalg.norm(point - np.array([0.0, 8.0, 2.0]))))
        got = float(out["nodes"][r, c, 0] / out["clear"][r, c, 0])
        assert got == pytest.approx(want, rel=0.02), ((r, c), got, want)


@pytest.mark.render
def test_a_sign_cut_by_the_frame_glows_as_its_pixels_do(sign_renders):
    """The compositor's glow beside a sign cut by the frame's top edge against the single scattering of the sign
    (both faces, ``area.airlight_background``, itself against quadrature over the emitter in test_area.py), over
    the rows beside it: each pixel taken as the two-sided Lambertian source its surface is
    (``emitter_glow.facing_factor``; as isotropic sources of the light they show the camera, Narasimhan's 7.2, the
    sign glowed 1.64x too bright there), measured 0.970 (1.066 before its far glow was its centre's point of both
    faces' mean intensity: ``methods.compositor.emitting_sides``); the Blur nodes' edges kept black (Extend Bounds:
    without it Blender extends the edge pixels outwards and the glow was 5.5x)."""
    from fog_addon.precompute.physics.area import area
    from fog_addon.precompute.physics.point import model
    from fog_addon.precompute.core.ops import NumpyOps
    out, _ = sign_renders
    cam, d, ground, sign = _sign_geometry(out["clear"].shape[:2])
    m = NumpyOps()
    o = np.broadcast_to(cam, d.shape)
    light = np.array([0.0, 8.0, 2.0])
    d_sv, along, h = model.ray_light_geometry(m, o, d, light)
    exact = 0.0
    for normal_y in (-1.0, 1.0):
        rows = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -normal_y, 0.0]])
        p, dd = (o - light) @ rows.T, d @ rows.T
        exact = exact + 20.0 * area.airlight_background(m, SIGN_BETA, d_sv, along, h, *np.moveaxis(p, -1, 0),
                                                        *np.moveaxis(dd, -1, 0), 0.5, 0.5)
    beside = ~sign & ~np.isfinite(ground)
    beside[30:] = False
    ratio = float(out["compositor"][..., 0][beside].mean() / exact[beside].mean())
    print(f"sign: compositor / exact single scattering beside it {ratio:.3f}")
    assert 0.93 <= ratio <= 1.10, ratio
