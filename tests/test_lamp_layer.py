"""A lamp's glow in a fog layer ends at the layer's top (``sunlight.lamp_glow_span``, ``lamp_glow_top``): the span of
a camera ray the homogeneous kernels take, and the glow over it against scipy quadrature of Sun et al. 2005 Eq. 5
with the fog cut at the top (numpy; the end-to-end render: test_lamp_layer_render.py)."""
import math

import numpy as np
import pytest
from scipy import integrate

from fog_addon.precompute.physics.daylight import daylight, sunlight
from tools.research import segments
from fog_addon.precompute.core.ops import NumpyOps

FAR = daylight.UNBOUNDED


def _span(origin, direction, top=10.0):
    m = NumpyOps()
    d = np.asarray(direction, float)
    return sunlight.lamp_glow_span(m, top, np.asarray(origin, float), d / np.linalg.norm(d))


@pytest.mark.parametrize("origin,direction,want", [
    ((0, 0, 2), (0, 1, 1), (0.0, 8.0 * math.sqrt(2.0))),     # inside, going up: leaves at the top
    ((0, 0, 2), (0, 1, -1), (0.0, FAR)),                     # inside, going down: never leaves
    ((0, 0, 2), (0, 1, 0), (0.0, FAR)),                      # inside, level
    ((0, 0, 30), (0, 1, -1), (20.0 * math.sqrt(2.0), FAR)),  # above, going down: enters at the top
    ((0, 0, 30), (0, 1, 1), (FAR, FAR)),                     # above, going up: never meets it
    ((0, 0, 30), (0, 1, 0), (FAR, FAR)),                     # above, level
])
def test_span(origin, direction, want):
    t0, t1 = _span(origin, direction)
    assert float(t0) == pytest.approx(want[0], rel=1e-12) and float(t1) == pytest.approx(want[1], rel=1e-12)


def test_falloff_top_is_one_falloff_length_up():
    assert sunlight.lamp_glow_top(6.0, 4.0, -1.5) == pytest.approx(-1.5 + 6.0 + sunlight.LAMP_FALLOFF_CUT * 4.0)
    assert sunlight.LAMP_FALLOFF_CUT == 1.0   # the one-node Gauss-Laguerre mixture of hard tops (its docstring)


def _cut_glow(origin, d, lamp, beta, top, g, length):
    """Sun et al. 2005 Eq. 5 per unit intensity with the fog cut above ``top`` (no scattering and no extinction
    there), by scipy."""
    def f(t):
        p = origin + t * d
        r = lamp - p
        dist = np.linalg.norm(r)
        c = np.dot(-r / dist, -d)
        phase = (1 - g * g) / (4 * math.pi * (1 + g * g - 2 * g * c) ** 1.5)
        inside = max(0.0, min(1.0, 1e6 * (top - p[2])))
        return inside * beta * phase * math.exp(-beta * dist) / dist ** 2
    # extinction along the ray only inside the layer: e^{-beta * (length of [0, t] below the top)}
    def f_ext(t):
        below = integrate.quad(lambda s: 1.0 if origin[2] + s * d[2] < top else 0.0, 0.0, t, limit=50)[0] if t else 0
        return f(t) * math.exp(-beta * below)
    t_lamp = max(float(np.dot(lamp - origin, d)), 0.0)
    return integrate.quad(f_ext, 0.0, min(length, 400.0), limit=400, points=[min(t_lamp, length)])[0]


@pytest.mark.parametrize("origin,elevation", [((0.0, 0.0, 1.6), 5.0), ((0.0, 0.0, 1.6), 12.0),
                                              ((0.0, 0.0, 1.6), -2.0), ((0.0, 0.0, 25.0), -20.0)])
@pytest.mark.parametrize("g", [0.0, 0.7])
def test_glow_over_the_span_against_quadrature(origin, elevation, g):
    """The kernels' glow (table-free, ``model.airlight_quadrature``) from where the ray enters the layer over the
    span, against quadrature of the cut integrand: within 0.5 %."""
    m = NumpyOps()
    origin = np.array(origin)
    e = math.radians(elevation)
    d = np.array([0.0, math.cos(e), math.sin(e)])
    lamp = np.array([0.0, 30.0, 5.0])
    beta, top = 0.05, 10.0
    t0, t1 = (float(v) for v in sunlight.lamp_glow_span(m, top, origin, d))
    ground = origin[2] / -d[2] if d[2] < 0 else FAR
    end = min(t1, ground)
    seg = segments.Segment(origin + t0 * d, d, end - t0)
    got = float(segments.glow(m, beta, seg, lamp, g=g, quadrature=True))
    ratio = got / _cut_glow(origin + t0 * d, d, lamp, beta, top, g, end - t0)
    print(f"\norigin z {origin[2]}, elevation {elevation}, g {g}: span ({t0:.3g}, {end:.3g}), ours / quadrature {ratio:.5f}")
    assert ratio == pytest.approx(1.0, abs=5e-3)
