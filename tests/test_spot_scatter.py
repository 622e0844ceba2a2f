"""The fog light a spot scatters onto a surface (issue 9 §1): ``spot.scatter`` against quadrature.

The reference is Sun et al. 2005 Eq. 15 for a spot: the spot's airlight (``spot.airlight_spot``, itself
within 0.25 % of scipy quadrature of Eq. 5 in tests/test_spot.py) along every direction of the hemisphere
above a Lambertian point, times cos / pi, by composite Gauss-Legendre about the direction to the light
(panels graded towards it, the horizon cut exactly in azimuth).  The same quadrature of the point light's
airlight reproduces ``surface.surface_scatter`` (checked first).  Errors are relative to the point light's
fog light at the point: outside a cone the spot's is a small share of it.
"""
import functools
import math

import numpy as np
import pytest

from fog_addon.precompute import airlight, model, rungs, spot, surface, tables
from fog_addon.precompute.ops import NumpyOps


@functools.lru_cache(maxsize=None)
def _ops(g):
    a, s, f = (tables.anisotropic(t, g) for t in (tables.AIRLIGHT, tables.SURFACE, tables.SPOT_FRACTION))
    return NumpyOps({a.name: airlight.bake_airlight_table(a), s.name: surface.surface_table(g),
                     f.name: spot.bake_scatter_fraction(f)})


def _panels(edges, order):
    x, w = np.polynomial.legendre.leggauss(order)
    lo, hi = edges[:-1, None], edges[1:, None]
    return (0.5 * (hi - lo) * x + 0.5 * (hi + lo)).ravel(), (0.5 * (hi - lo) * w).ravel()


def _hemisphere(p, light, normal):
    """Directions w (K, 3) and weights (sin g dg dphi (n.w) / pi) of the hemisphere above ``normal``,
    polar angle g measured from the direction to the light."""
    a = (light - p) / np.linalg.norm(light - p)
    ct = float(normal @ a)
    e1 = normal - ct * a
    e1 = e1 / np.linalg.norm(e1) if np.linalg.norm(e1) > 1e-9 else np.cross(a, (1.0, 0.0, 0.0))
    e2 = np.cross(a, e1)
    edges = np.unique(np.concatenate([1e-6 * 1e5 ** np.linspace(0, 1, 17), np.linspace(0.1, math.pi, 64)]))
    gam, wg = _panels(np.concatenate([[0.0], edges]), 8)
    st = math.sqrt(max(0.0, 1.0 - ct * ct))
    A, B = ct * np.cos(gam), st * np.sin(gam)
    phimax = np.arccos(np.clip(np.where(B > 1e-300, -A / np.maximum(B, 1e-300), np.where(A > 0, -2.0, 2.0)), -1, 1))
    xu, wu = _panels(np.linspace(-1.0, 1.0, 17), 8)
    phi = phimax[:, None] * xu[None, :]
    cosn = np.maximum(A[:, None] + B[:, None] * np.cos(phi), 0.0)
    wt = (wg * np.sin(gam) * phimax)[:, None] * wu[None, :] * cosn / math.pi
    cg, sg = np.cos(gam)[:, None], np.sin(gam)[:, None]
    w = (cg[..., None] * a + (sg * np.cos(phi))[..., None] * e1 + (sg * np.sin(phi))[..., None] * e2)
    return w.reshape(-1, 3), wt.ravel()


def _case(rng, where):
    """A Lambertian point 0.5-30 m from a spot (10-120 degrees, blend 0-1), inside, at the edge of or
    outside its cone, the normal random and facing the light."""
    beta = math.exp(rng.uniform(math.log(0.01), math.log(0.5)))
    dist = math.exp(rng.uniform(math.log(0.5), math.log(30.0)))
    half = math.radians(rng.uniform(10.0, 120.0)) / 2
    blend = rng.uniform()
    lo, hi = {"inside": (0.0, 0.7 * half), "edge": (0.7 * half, 1.3 * half), "outside": (1.3 * half, math.pi)}[where]
    psi, az = rng.uniform(lo, hi), rng.uniform(0, 2 * math.pi)
    p = dist * np.array([math.sin(psi) * math.cos(az), math.sin(psi) * math.sin(az), -math.cos(psi)])
    n = rng.normal(size=3)
    n /= np.linalg.norm(n)
    if n @ -p < 0:
        n = -n
    return beta, p, n, math.cos(half), blend


@pytest.mark.parametrize("g", [0.0, 0.85])
def test_spot_scatter_against_hemisphere_quadrature(g):
    """12 points a g (4 inside, 4 at the edge, 4 outside): ``spot.scatter`` (the point light's scatter table
    times the baked share F of the cone) within SPOT_SCATTER_ERROR of the point light's fog light, and
    closer on the whole than the cone's factor at the point times the point light's (the first model).
    Measured on 150 random points (helper script, this stop): error at most 0.36 (g = 0) and 0.40
    (g = 0.85), 95 % within 0.25 and 0.15; the factor alone: 0.95 and 0.78."""
    m, light, rows = _ops(g), np.zeros(3), tuple(np.eye(3))
    rng = np.random.default_rng(11 + int(10 * g))
    ours, plain = [], []
    # the quadrature reproduces the point light's scatter first
    beta, p, n, _, _ = _case(rng, "inside")
    w, wt = _hemisphere(p, light, n)
    d_sv, along, h = model.ray_light_geometry(m, p[None, :], w, light[None, :])
    with np.errstate(all="ignore"):
        quad = float(np.sum(model.airlight_quadrature(m, beta, d_sv, along, h, model.FAR, g=g) * wt))
    d_sp = float(np.linalg.norm(p))
    table = float(surface.surface_scatter(m, np.asarray(beta), np.asarray(d_sp), np.asarray(n @ -p / d_sp), 0.0, g))
    assert abs(table / quad - 1) < 1e-2, (table, quad)
    for where in ("inside", "edge", "outside") * 4:
        beta, p, n, cos_half, blend = _case(rng, where)
        w, wt = _hemisphere(p, light, n)
        with np.errstate(all="ignore"):
            exact = float(np.sum(spot.airlight_spot(m, beta, np.broadcast_to(p, w.shape), w, np.zeros_like(w), rows,
                                                    cos_half, blend, model.FAR, g) * wt))
        d_sp = float(np.linalg.norm(p))
        point = float(surface.surface_scatter(m, np.asarray(beta), np.asarray(d_sp), np.asarray(n @ -p / d_sp), 0.0, g))
        c = spot.axis_cosine(m, rows, p, light)
        got = float(spot.scatter(m, np.asarray(beta), np.asarray(d_sp), np.asarray(n @ -p / d_sp), 0.0, c, cos_half,
                                 blend, point=functools.partial(surface.surface_scatter, g=g), g=g))
        ours.append(abs(got - exact) / point)
        plain.append(abs(float(spot.falloff_at(m, rows, p, light, cos_half, blend)) * point - exact) / point)
    print(f"g={g}: max {max(ours):.3f} median {np.median(ours):.3f}; cone factor alone: max {max(plain):.3f} "
          f"median {np.median(plain):.3f}")
    assert max(ours) <= rungs.SPOT_SCATTER_ERROR
    assert np.median(ours) < 0.5 * np.median(plain)
