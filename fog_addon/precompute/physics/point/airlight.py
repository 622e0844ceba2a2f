"""Airlight tables: our normalised tail N(rho, xi) and Sun's F(u, v), numpy only.

Sun, Ramamoorthi, Narasimhan, Nayar 2005, "A Practical Analytic Single
Scattering Model for Real Time Rendering": Eq. 5 (airlight integral), Eq. 10
(F), Eq. 11-12 (airlight from two F lookups).  ``model.py`` explains the change
of variables that replaces F by N; both are baked here so the two can be
compared (tools/figure6.py).
"""
import math

import numpy as np

from ...core import tables
from ...core.ops import NumpyOps
from . import model

_GL8_X, _GL8_W = np.polynomial.legendre.leggauss(8)


def k_inf(u, a, panels=48, g=0.0):
    """Optical tail K(u, a) = int_0^inf exp(-p) w / ((a + p)^2 + u^2) dp (dimensionless).

    u = beta h, a = beta Q (see model.py); w = 1, or for Henyey-Greenstein anisotropy g
    ``model.hg_weight`` at (a + p, u) (Pegoraro et al. Eq. 8).  Composite 8-point
    Gauss-Legendre on geometrically graded panels from min(rho, 1) * 1e-3 to 60
    plus [0, first edge]; relative error below 1e-10 against the closed form
    Im(e^c E1(c)) / u, c = a - iu (checked in the tests with scipy), and against
    scipy quadrature for g != 0.
    """
    u = np.asarray(u, float)
    a = np.asarray(a, float)
    rho = np.hypot(u, a)
    first = np.maximum(np.minimum(rho, 1.0) * 1e-3, 1e-300)[..., None]
    t = np.linspace(0.0, 1.0, panels)
    edges = first * (60.0 / first) ** t
    edges = np.concatenate([np.zeros(edges.shape[:-1] + (1,)), edges], axis=-1)
    lo, hi = edges[..., :-1], edges[..., 1:]
    half = 0.5 * (hi - lo)
    p = half[..., None] * _GL8_X + (0.5 * (hi + lo))[..., None]
    q, uu = a[..., None, None] + p, u[..., None, None]
    f = np.exp(-p) / (q ** 2 + uu ** 2)
    if g:
        f = f * model.hg_weight(NumpyOps(), g, q, uu)
    return np.sum(f * _GL8_W * half[..., None], axis=(-1, -2))


def normalised_tail(rho, xi, g=0.0):
    """N(rho, xi) = K * (rho / h(xi) + rho^2 / w(xi)), K at u = rho cos xi, a = rho sin xi.

    h(xi) = (pi/2 - xi) / cos xi, so rho / h is the reciprocal of K without
    extinction and phase weight (rho -> 0) and rho^2 / w its far-field reciprocal, w the
    Henyey-Greenstein weight at the angle xi (1 for g = 0); N -> 1 at both ends for g = 0,
    and to the mean of w over [xi, pi/2] as rho -> 0 for g != 0.
    """
    rho = np.maximum(np.asarray(rho, float), 1e-12)
    xi = np.asarray(xi, float)
    c = tables.HALF_PI - xi
    h = np.where(c > 1e-6, c / np.maximum(np.sin(c), 1e-300), 1.0)
    u, a = rho * np.cos(xi), rho * np.sin(xi)
    w = model.hg_weight(NumpyOps(), g, a, u) if g else 1.0
    return k_inf(u, a, g=g) * (rho / h + rho * rho / w)


def bake_airlight_table(spec=tables.AIRLIGHT):
    """The N table of ``spec.g`` as float32, layout of tables.py (rows: xi, columns: rho)."""
    x = np.linspace(0.0, 1.0, spec.width)
    y = np.linspace(0.0, 1.0, spec.height)
    rho = tables.airlight_rho(x, spec.g)
    xi = tables.airlight_xi(y, spec.g)
    # a few rows at a time: the quadrature's (rows, columns, panels, nodes) temporaries then stay in the
    # processor's cache (the whole table's would be 200 MB each)
    return np.concatenate([normalised_tail(rho[None, :], xi[i:i + ROWS_AT_ONCE, None], spec.g)
                           for i in range(0, len(xi), ROWS_AT_ONCE)]).astype(np.float32)


ROWS_AT_ONCE = 4   # rows of ``bake_airlight_table`` computed together


def airlight(beta, d_sv, d_vp, gamma, table=None, quadrature=False, g=0.0):
    """Airlight per unit intensity (1/m^2) of our model, in numpy, exactly as the shaders compute it.

    beta (1/m), d_sv, d_vp (m, ``np.inf`` for the background), gamma (rad); arrays broadcast.
    ``quadrature``: the in-shader quadrature of the OSL method (no table) instead
    of the table lookups of the node groups.  ``g``: Henyey-Greenstein anisotropy
    (``table``, if given, baked for it).
    """
    beta, d_sv, d_vp, gamma = np.broadcast_arrays(*(np.asarray(v, float) for v in (beta, d_sv, d_vp, gamma)))
    along = d_sv * np.cos(gamma)
    h = d_sv * np.sin(gamma)
    finite = np.isfinite(d_vp)
    if quadrature:
        return model.airlight_quadrature(NumpyOps(), beta, d_sv, along, h, np.where(finite, d_vp, model.FAR), g)
    spec = tables.anisotropic(tables.AIRLIGHT, g)
    table = bake_airlight_table(spec) if table is None else table
    m = NumpyOps({spec.name: table})
    dvp = np.where(finite, d_vp, 0.0)
    with np.errstate(over="ignore", invalid="ignore"):
        seg = model.airlight_segment(m, beta, d_sv, along, h, dvp, g)
        bg = model.airlight_background(m, beta, d_sv, along, h, g)
    return np.where(finite, seg, bg)


# --- Sun et al.'s original F(u, v) formulation, for comparison ------------------

def sun_f(u, v):
    """F(u, v) = int_0^v exp(-u tan xi) dxi, Sun et al. 2005 Eq. 10, by 64-point Gauss-Legendre."""
    x, w = np.polynomial.legendre.leggauss(64)
    u = np.asarray(u, float)[..., None]
    v = np.asarray(v, float)[..., None]
    xi = 0.5 * v * (x + 1.0)
    return np.sum(np.exp(-u * np.tan(xi)) * w * 0.5 * v, axis=-1)


def bake_sun_f_table(nu, nv, u_max=10.0, compress=True):
    """Sun's F table: nu x nv samples, u in [0, u_max] (``compress``: u = u_max x^2), v in [0, pi/2]."""
    x = np.linspace(0.0, 1.0, nu)
    u = u_max * x ** 2 if compress else u_max * x
    v = np.linspace(0.0, tables.HALF_PI, nv)
    return sun_f(u[None, :], v[:, None]).astype(np.float32)


def airlight_sun(beta, d_sv, d_vp, gamma, f_table, u_max=10.0, compress=True, interp="linear"):
    """Airlight per unit intensity from Sun's Eq. 11 / 12 with a tabulated F (bilinear or nearest).

    Faithful to the paper, including A0's 1/sin(gamma) and the subtraction of
    two lookups; ``u`` beyond the table is clamped to its edge as a texture would.
    """
    beta, d_sv, d_vp, gamma = np.broadcast_arrays(*(np.asarray(v, float) for v in (beta, d_sv, d_vp, gamma)))
    t_sv, t_vp = beta * d_sv, beta * d_vp
    a0 = beta * beta * np.exp(-t_sv * np.cos(gamma)) / (2 * math.pi * t_sv * np.sin(gamma))   # Eq. 7 / I0
    a1 = t_sv * np.sin(gamma)                                                                  # Eq. 8
    with np.errstate(invalid="ignore", divide="ignore"):
        v1 = np.where(np.isfinite(t_vp),
                      math.pi / 4 + 0.5 * np.arctan((t_vp - t_sv * np.cos(gamma)) / a1),
                      tables.HALF_PI)
    nv, nu = f_table.shape
    gx = np.sqrt(np.clip(a1 / u_max, 0, 1)) if compress else np.clip(a1 / u_max, 0, 1)

    def lookup(v):
        fx = gx * (nu - 1)
        fy = np.clip(v / tables.HALF_PI, 0, 1) * (nv - 1)
        if interp == "nearest":
            return f_table[np.rint(fy).astype(int), np.rint(fx).astype(int)]
        m = NumpyOps({"F": f_table})
        return m.table(tables.TableSpec("F", nu, nv), fx / (nu - 1), fy / (nv - 1))

    return a0 * (lookup(v1) - lookup(gamma / 2))                                               # Eq. 11
