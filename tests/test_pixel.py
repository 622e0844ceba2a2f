"""The Compositor method's per-pixel formulas (fog_addon/precompute/model/pixel.py) against independent sources:
the pixel-filter table against scipy's adaptive quadrature in Cartesian coordinates about the pixel (the
baker integrates in polar coordinates about the light, by the midpoint rule), the filter-width scaling
against the same quadrature at another width, and the picture position against a pinhole projection."""
import math

import numpy as np
import pytest
from scipy import integrate

from fog_addon.precompute.model import pixel
from fog_addon.precompute.core.ops import NumpyOps

WIDTH = pixel.FILTER_WIDTH   # the table's filter support (px)


@pytest.fixture(scope="module")
def table():
    return pixel.bake_filter()


def mean_inverse_distance(dx, dy, width=WIDTH):
    """E[1 / |delta + s|] over the offsets s = (x, y) of a pixel's samples, x and y independent with density
    proportional to the Blackman-Harris filter of support ``width``: adaptive quadrature over the filter's
    square, split at the light's coordinates (the integrand's singular point)."""
    half = width / 2
    norm = integrate.quad(lambda x: pixel.blackman_harris(x, width), -half, half)[0] ** 2

    def inner(y):
        pts = [-dx] if -half < -dx < half else None
        return integrate.quad(lambda x: pixel.blackman_harris(x, width) / math.hypot(x + dx, y + dy), -half, half,
                              points=pts, limit=200, epsabs=1e-11, epsrel=1e-9)[0] * pixel.blackman_harris(y, width)
    ys = [-dy] if -half < -dy < half else None
    return integrate.quad(inner, -half, half, points=ys, limit=200, epsabs=1e-10, epsrel=1e-8)[0] / norm


@pytest.mark.parametrize("dx,dy", [(0.0, 0.0), (0.0, 1.0), (0.5, 0.25), (1.25, 2.0), (3.0, 3.0), (6.0, 0.0)])
def test_filter_table_at_its_nodes(table, dx, dy):
    step = pixel.FILTER_REACH / (pixel.FILTER.width - 1)
    got = table[round(dy / step), round(dx / step)]
    want = mean_inverse_distance(dx, dy)
    assert got == pytest.approx(want, rel=2e-4), (dx, dy, got, want)


def eevee_mean_inverse_distance(dx, dy, radius=pixel.DEFAULT_FILTER_WIDTH):
    """E[1 / |delta + s|] over EEVEE's film filter (a Gaussian of sigma 0.284 radius cut at the radius,
    Blender 5.0 ``film_filter_weight``; written out here, not taken from ``pixel``): adaptive quadrature in
    Cartesian coordinates over the filter's disk, split at the light's coordinates."""
    sigma = 0.284 * radius

    def w(x, y):
        return math.exp(-0.5 * (x * x + y * y) / sigma ** 2)

    def inner(y, f):
        half = math.sqrt(max(radius * radius - y * y, 0.0))
        pts = [-dx] if -half < -dx < half else None
        return integrate.quad(lambda x: f(x, y), -half, half, points=pts, limit=200, epsabs=1e-12, epsrel=1e-10)[0]

    ys = [-dy] if -radius < -dy < radius else None

    def outer(f):
        return integrate.quad(lambda y: inner(y, f), -radius, radius, points=ys, limit=200, epsabs=1e-11,
                              epsrel=1e-9)[0]
    return outer(lambda x, y: w(x, y) / math.hypot(x + dx, y + dy)) / outer(w)


@pytest.fixture(scope="module")
def eevee_table():
    return pixel.bake_eevee_filter()


@pytest.mark.parametrize("dx,dy", [(0.0, 0.0), (0.0, 1.0), (0.5, 0.25), (1.25, 2.0), (1.5, 0.0), (3.0, 3.0),
                                   (6.0, 0.0)])
def test_eevee_filter_table_at_its_nodes(eevee_table, dx, dy):
    """EEVEE's table (``bake_eevee_filter``: polar coordinates about the light, one mean per distance) against
    the Cartesian quadrature over EEVEE's filter."""
    step = pixel.FILTER_REACH / (pixel.EEVEE_FILTER.width - 1)
    got = eevee_table[round(dy / step), round(dx / step)]
    want = eevee_mean_inverse_distance(dx, dy)
    assert got == pytest.approx(want, rel=2e-4), (dx, dy, got, want)


def test_eevee_filter_differs_from_cycles(table, eevee_table):
    """The two filters' tables differ where the peak factor acts (so one could not stand for the other at the
    tables' accuracy): by up to 1.1 % at offsets under a pixel (quadrature: 0.9887 at (0.5, 0.5) px)."""
    step = pixel.FILTER_REACH / (pixel.FILTER.width - 1)
    k = round(0.5 / step)
    assert eevee_table[k, k] / table[k, k] == pytest.approx(
        eevee_mean_inverse_distance(0.5, 0.5) / mean_inverse_distance(0.5, 0.5), rel=3e-4)
    assert eevee_table[k, k] / table[k, k] < 0.992


def test_filter_table_between_nodes(table):
    """Bilinear lookups between the nodes (what the compositor's Map UV does) within 0.3 % of the pixel's
    mean glow, r A(delta), where the peak factor applies."""
    m = NumpyOps({pixel.FILTER.name: table})
    worst = 0.0
    for dx, dy in [(0.03, 0.02), (0.31, 0.77), (1.1, 0.4), (2.23, 1.61), (4.4, 3.3)]:
        a = float(m.table(pixel.FILTER, dx / pixel.FILTER_REACH, dy / pixel.FILTER_REACH))
        r = math.hypot(dx, dy)
        worst = max(worst, abs(r * a - r * mean_inverse_distance(dx, dy)))
    assert worst < 3e-3, worst


def test_filter_width_scaling():
    """r A(delta) depends on delta / width only, so one table serves every filter width (``filter_scale``):
    Blender's width 3 (a 6 px support; the table is baked for the default 1.5) against quadrature there."""
    k = pixel.filter_scale("BLACKMAN_HARRIS", 3.0)   # Blender's width 3: offsets scaled by 0.5 for the table
    assert k == pytest.approx(0.5)
    for dx, dy in [(0.4, 0.9), (2.0, 1.0)]:
        wide = mean_inverse_distance(dx, dy, width=WIDTH / k)
        assert math.hypot(dx, dy) * wide == pytest.approx(math.hypot(dx * k, dy * k) * mean_inverse_distance(
            dx * k, dy * k), rel=1e-6)
    assert pixel.filter_scale("GAUSSIAN", 0.01) is None and pixel.filter_scale("BOX", 1.0) is None
    assert pixel.filter_scale("EEVEE", 3.0) == pytest.approx(0.5) and pixel.filter_scale("EEVEE", 0.0) is None
    for dx, dy in [(0.4, 0.9), (2.0, 1.0)]:   # EEVEE's radius 3 against its table's 1.5
        wide = eevee_mean_inverse_distance(dx, dy, radius=3.0)
        assert math.hypot(dx, dy) * wide == pytest.approx(math.hypot(dx * k, dy * k) * eevee_mean_inverse_distance(
            dx * k, dy * k), rel=1e-6)


def test_peak_excess_far_from_a_light(table):
    """No excess beyond the table (the glow's mean is its centre value, far from the light), and the
    excess of a pixel next to the light is what the quadrature gives."""
    m = NumpyOps({pixel.FILTER.name: table})
    light = np.array([10.0, 10.0, 0.0])
    far = m.combine(np.array([17.0, 30.0]), np.array([10.0, 2.0]), 0.0)
    assert np.all(pixel.peak_excess(m, far, light) == 0.0)
    near = np.array([10.5, 10.0, 0.0])
    want = 0.5 * mean_inverse_distance(0.5, 0.0) - 1.0
    assert float(pixel.peak_excess(m, near, light)) == pytest.approx(want, rel=1e-3)


def test_picture_position_pinhole():
    """A point's picture position against the pinhole projection x = f X / Z of a camera looking down -Z,
    with a shifted, non-square frame; behind the camera: far outside the picture."""
    m = NumpyOps()
    w, h, sx, sy = 1.0, 0.5625, 0.1, -0.05   # the image plane at unit distance: its size and shift
    corner = np.array([sx - w / 2, sy - h / 2, -1.0])
    across, up = np.array([w, 0.0, 0.0]), np.array([0.0, h, 0.0])
    size = np.array([320.0, 180.0, 0.0])
    rng = np.random.default_rng(1)
    p = rng.uniform([-5, -3, -40], [5, 3, -2], (50, 3))
    got = pixel.picture_position(m, p, corner, across, up, size)
    u = (p[:, 0] / -p[:, 2] - (sx - w / 2)) / w * 320.0
    v = (p[:, 1] / -p[:, 2] - (sy - h / 2)) / h * 180.0
    assert np.allclose(got[:, 0], u, atol=1e-9) and np.allclose(got[:, 1], v, atol=1e-9)
    behind = pixel.picture_position(m, np.array([[0.5, 0.2, 3.0]]), corner, across, up, size)
    assert behind[0, 0] > 1e5 and behind[0, 1] > 1e5
