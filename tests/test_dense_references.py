"""A lamp in dense fog (issue 28): the annulus profile that compares glows, and the analytic fog against Cycles'
path-traced single scattering of the same scene (fog_scenes/dense.py).

The fast test checks ``ring_means`` on a synthetic image whose annuli hold known values.  The slow one renders the
scene with the add-on (Compositor method) and compares it ring by ring with the cached single-scattering
reference (Cycles World volume, volume bounces 0, 4096 spp x 2 seeds), issue 28's case: lamp 15 m away through
fog of density 0.3 1/m (T = 4.5), g 0.85, albedo 0.9.
"""
import numpy as np
import pytest

from fog_scenes import dense

# Measured (docs/measurements/2026-11-27-dense-fog-references.md): reference / ours 1.0003 in every annulus;
# the two seeds' ring means agree within 1e-5.  The bound leaves room for the Quality target (1 %) being spent.
SS_RING_TOLERANCE = 0.005
SS_CASE = dict(distance=15.0, density=0.3, anisotropy=0.85, albedo=0.9)
SS_REFERENCE = dict(volume_bounces=0, samples=4096, seeds=2)


def _synthetic(values, edges, shape=(120, 120), centre=(60.0, 60.0)):
    """An image whose annulus i (edges[i] <= r < edges[i+1]) is values[i], 0 elsewhere."""
    y, x = np.mgrid[0:shape[0], 0:shape[1]]
    r = np.hypot(x + 0.5 - centre[0], y + 0.5 - centre[1])
    img = np.zeros(shape + (3,), np.float32)
    for v, lo, hi in zip(values, edges[:-1], edges[1:]):
        img[(r >= lo) & (r < hi)] = v
    return img, r


def test_ring_means_known_values_and_a_firefly():
    edges = dense.RING_EDGES_PX
    values = [5.0, 3.0, 2.0, 1.0, 0.5]
    img, r = _synthetic(values, edges)
    np.testing.assert_allclose(dense.ring_means(img, (60.0, 60.0), edges), values, rtol=1e-6)
    # a firefly 1000x its annulus (7.5-15 px): left out with the default factor, kept without rejection
    iy, ix = np.argwhere((r >= 7.5) & (r < 15.0))[0]
    img[iy, ix] = 2000.0
    means, kept, dropped = dense.ring_means(img, (60.0, 60.0), edges, return_counts=True)
    np.testing.assert_allclose(means, values, rtol=1e-6)
    assert list(dropped) == [0, 0, 1, 0, 0]
    n = kept[2] + 1
    raw = dense.ring_means(img, (60.0, 60.0), edges, firefly=None)
    assert raw[2] == pytest.approx((2.0 * (n - 1) + 2000.0) / n, rel=1e-6)
    # a bright pixel below the factor (10x median) stays in
    img[iy, ix] = 20.0
    assert dense.ring_means(img, (60.0, 60.0), edges)[2] == pytest.approx((2.0 * (n - 1) + 20.0) / n, rel=1e-6)


def test_ring_means_off_centre_luminance_and_pixel_counts():
    # an off-centre lamp on a coloured image: Rec. 709 luminance, annuli around the given centre
    edges = (0.0, 2.0, 4.0)
    img, r = _synthetic([1.0, 1.0], edges, shape=(20, 30), centre=(11.25, 7.5))
    img[..., 0] *= 2.0   # (2, 1, 1): luminance 0.2126 * 2 + 0.7152 + 0.0722 = 1.2126
    means, kept, dropped = dense.ring_means(img, (11.25, 7.5), edges, return_counts=True)
    np.testing.assert_allclose(means, [1.2126, 1.2126], rtol=1e-6)
    assert list(kept) == [int(((r >= 0) & (r < 2)).sum()), int(((r >= 2) & (r < 4)).sum())]
    assert list(dropped) == [0, 0]


def test_pixel_scale():
    # the lens makes the central pixel DEG_PER_PX wide: 50 px = 4.99 degrees (pinhole: atan(50 tan 0.1 deg))
    assert dense.pixel_angle_deg(1.0) == pytest.approx(dense.DEG_PER_PX, rel=1e-9)
    assert dense.pixel_angle_deg(50.0) == pytest.approx(4.98737, rel=1e-5)
    assert dense.lamp_image_centre() == (60.0, 60.0)


@pytest.mark.slow
@pytest.mark.render
def test_compositor_fog_matches_single_scattering_reference_by_annulus(regen, tmp_path):
    from fog_addon import imageio
    blend = dense.blend_path(SS_CASE["distance"], workdir=tmp_path)
    centre = dense.lamp_image_centre_from_blend(blend)
    assert centre == pytest.approx(dense.lamp_image_centre(), abs=1e-3)
    # Blender's projection of points 1 and 4.99 degrees right of the lamp: 10 and 50 px (the pixel scale)
    d = SS_CASE["distance"]
    pts = [(d * np.tan(np.radians(dense.pixel_angle_deg(n))), 0.0, 0.0) for n in (10.0, 50.0)]
    xs = [xy[0] for xy in dense.project_from_blend(blend, pts)]
    assert xs == pytest.approx([70.0, 110.0], abs=1e-3)
    ref = dense.render_ms_reference(**SS_CASE, **SS_REFERENCE, regen=regen, keep_seeds=False)
    ours = dense.render_ours(**SS_CASE, out=tmp_path / "ours.exr", blend=blend)
    r = dense.ring_means(imageio.read_rgb(ref), centre)
    o = dense.ring_means(imageio.read_rgb(ours), centre)
    ratio = r / o
    assert np.all(np.abs(ratio - 1.0) <= SS_RING_TOLERANCE), (
        "reference / ours by annulus " + ", ".join(f"{l}: {q:.4f}" for l, q in zip(dense.ring_labels(), ratio)))
