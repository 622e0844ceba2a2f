"""Sun et al. 2005, Appendix D: airlight for a general phase function as a polynomial in cos(alpha), numpy only.

Sun, Ramamoorthi, Narasimhan, Nayar 2005, "A Practical Analytic Single
Scattering Model for Real Time Rendering", Appendix D:

* Eq. 36: k(alpha) = sum_{k=0}^{n} W_k cos^k(alpha), "n <= 3 typically suffices";
* Eq. 37-42: each power gives an integral like Eq. 5; alpha is the scattering
  angle at the ray point (cos alpha = -(x - D_sv cos gamma) / d, light going
  from the source to the point and then back to the viewer: alpha -> 0 is
  forward scattering), and with z = A1 tan(eta), eta = 2 xi - pi/2 one gets
  cos(alpha) = -sin(eta) = cos(2 xi): the (-1)^k of Eq. 38-42 is absorbed and
* Eq. 43: L_a = A0 sum_k W_k int_{gamma/2}^{v1} cos^k(2 xi) exp(-A1 tan xi) dxi,
  A0 = beta^2 e^{-T_sv cos gamma} / (2 pi T_sv sin gamma) (Eq. 7, per unit
  intensity I0), A1 = T_sv sin gamma (Eq. 8), v1 of Eq. 9 (pi/2 for D_vp = inf);
* Eq. 44: F^k(u, v) = int_0^v cos^k(2 xi) exp(-u tan xi) dxi, tabulated like F
  (Eq. 10), so that L_a = A0 sum_k W_k [F^k(A1, v1) - F^k(A1, gamma/2)] (Eq. 11 / 12).

Normalisation: here W_k are the coefficients of 4 pi p(alpha), so that W = (1,)
is Sun's isotropic model (p = 1 / 4 pi) and ``airlight_sun_appendix_d`` at
g = 0 is ``airlight.airlight_sun`` exactly (same table layout).

The phase function is Henyey-Greenstein; its Legendre series
4 pi p_HG(cos alpha) = sum_l (2l + 1) g^l P_l(cos alpha) is exact, and its
truncation at l = n, converted to powers of cos(alpha), is the degree-n
polynomial of Eq. 36 (the least-squares one over the sphere).  It converges
like g^n: the forward peak 4 pi p(0) = (1 + g) / (1 - g)^2 (82 at g = 0.85)
against sum_{l<=n} (2l + 1) g^l (11.5 at n = 3), and the truncated series is
negative backwards for large g (-2.3 at alpha = pi, g = 0.85, n = 3).  That is
where Appendix D stops working as g grows (tools/stability_map.py, anisotropic map).

Units: beta in 1/m, distances in m (``np.inf`` for the background), angles in
radians, airlight per unit intensity in 1/m^2, as in airlight.py.
"""
import math

import numpy as np
from numpy.polynomial import legendre

from fog_addon.precompute.core import tables

_GL8_X, _GL8_W = legendre.leggauss(8)


# --- Eq. 36: the phase function as a polynomial in cos(alpha) -----------------------

def hg_legendre_coefficients(g, n):
    """c_l = (2l + 1) g^l, l = 0..n: 4 pi p_HG(mu) = sum_l c_l P_l(mu) (dimensionless, exact as n -> inf)."""
    l = np.arange(int(n) + 1, dtype=float)
    return (2.0 * l + 1.0) * float(g) ** l


def hg_power_coefficients(g, n):
    """W_k, k = 0..n, of Sun Eq. 36 for 4 pi p_HG: the Legendre series truncated at l = n in powers of cos(alpha).

    ``numpy.polynomial.legendre.leg2poly``; W = (1, 0, ...) at g = 0.  Evaluate with ``phase_polynomial``.
    """
    w = legendre.leg2poly(hg_legendre_coefficients(g, n))
    return np.concatenate([w, np.zeros(int(n) + 1 - len(w))])        # leg2poly trims trailing zeros


def phase_polynomial(w, mu):
    """4 pi k(alpha) = sum_k W_k mu^k at mu = cos(alpha) (Sun Eq. 36, Horner)."""
    mu = np.asarray(mu, float)
    out = np.zeros_like(mu)
    for c in w[::-1]:
        out = out * mu + c
    return out


def hg_4pi(g, mu):
    """4 pi p_HG(mu), mu = cos(alpha) (1 for g = 0)."""
    return (1.0 - g * g) / (1.0 + g * g - 2.0 * g * np.asarray(mu, float)) ** 1.5


# --- Eq. 44: F^k(u, v) ------------------------------------------------------------------

def sun_f_k(k, u, v):
    """F^k(u, v) = int_0^v cos^k(2 xi) exp(-u tan xi) dxi, Sun Eq. 44, by 64-point Gauss-Legendre (as ``airlight.sun_f``).

    Dimensionless; u >= 0, v in [0, pi/2]; F^0 = F of Eq. 10.
    """
    x, w = legendre.leggauss(64)
    u = np.asarray(u, float)[..., None]
    v = np.asarray(v, float)[..., None]
    xi = 0.5 * v * (x + 1.0)
    return np.sum(np.cos(2.0 * xi) ** k * np.exp(-u * np.tan(xi)) * w * 0.5 * v, axis=-1)


def bake_sun_f_k_tables(n, nu, nv, u_max=10.0, compress=True):
    """F^k tables, k = 0..n, stacked: float32 array (n + 1, nv, nu), each the layout of ``airlight.bake_sun_f_table``.

    Columns u in [0, u_max] (``compress``: u = u_max x^2), rows v in [0, pi/2].
    """
    x = np.linspace(0.0, 1.0, nu)
    u = u_max * x ** 2 if compress else u_max * x
    v = np.linspace(0.0, tables.HALF_PI, nv)
    return np.stack([sun_f_k(k, u[None, :], v[:, None]) for k in range(int(n) + 1)]).astype(np.float32)


def _bilinear(table, fx, fy):
    """Bilinear lookup at grid coordinates fx in [0, nu - 1], fy in [0, nv - 1] (as NumpyOps.table)."""
    nv, nu = table.shape
    fx = np.clip(fx, 0.0, nu - 1)
    fy = np.clip(fy, 0.0, nv - 1)
    i = np.minimum(np.floor(fx), nu - 2).astype(int)
    j = np.minimum(np.floor(fy), nv - 2).astype(int)
    tx, ty = fx - i, fy - j
    t = table.astype(float)
    a = t[j, i] + tx * (t[j, i + 1] - t[j, i])
    b = t[j + 1, i] + tx * (t[j + 1, i + 1] - t[j + 1, i])
    return a + ty * (b - a)


# --- Eq. 37-43: the airlight -------------------------------------------------------------

def _geometry(beta, d_sv, d_vp, gamma):
    beta, d_sv, d_vp, gamma = np.broadcast_arrays(*(np.asarray(v, float) for v in (beta, d_sv, d_vp, gamma)))
    t_sv, t_vp = beta * d_sv, beta * d_vp
    a1 = t_sv * np.sin(gamma)                                                        # Eq. 8
    return beta, t_sv, t_vp, gamma, a1


def airlight_sun_appendix_d(beta, d_sv, d_vp, gamma, g, n=3, f_tables=None, u_max=10.0, compress=True):
    """Airlight per unit intensity (1/m^2) for Henyey-Greenstein g by Sun's Appendix D with degree n (Eq. 36-44).

    L_a = A0 sum_{k<=n} W_k [F^k(A1, v1) - F^k(A1, gamma/2)] (Eq. 43 with Eq. 44, the form of Eq. 11 / 12),
    W_k = ``hg_power_coefficients(g, n)``.  ``f_tables``: ``bake_sun_f_k_tables`` of at least n + 1 levels,
    read bilinearly as ``airlight.airlight_sun`` reads F (u beyond the table clamped to its edge);
    None bakes the 64 x 64 ones.  Faithful to the paper, including A0's 1 / sin(gamma) and the
    subtraction of two lookups.  At g = 0 it is ``airlight.airlight_sun`` with the same table.
    """
    beta, t_sv, t_vp, gamma, a1 = _geometry(beta, d_sv, d_vp, gamma)
    w = hg_power_coefficients(g, n)
    if f_tables is None:
        f_tables = bake_sun_f_k_tables(n, 64, 64, u_max, compress)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        a0 = beta * beta * np.exp(-t_sv * np.cos(gamma)) / (2 * math.pi * t_sv * np.sin(gamma))   # Eq. 7 / I0
        v1 = np.where(np.isfinite(t_vp),
                      math.pi / 4 + 0.5 * np.arctan((t_vp - t_sv * np.cos(gamma)) / a1), tables.HALF_PI)
        _, nv, nu = f_tables.shape
        gx = np.sqrt(np.clip(a1 / u_max, 0, 1)) if compress else np.clip(a1 / u_max, 0, 1)
        fx = gx * (nu - 1)
        fy1 = np.clip(v1 / tables.HALF_PI, 0, 1) * (nv - 1)
        fy0 = np.clip(0.5 * gamma / tables.HALF_PI, 0, 1) * (nv - 1)
        total = np.zeros_like(a0)
        for k, wk in enumerate(w):
            if wk:
                total = total + wk * (_bilinear(f_tables[k], fx, fy1) - _bilinear(f_tables[k], fx, fy0))
        return a0 * total                                                                  # Eq. 43


def airlight_appendix_d_exact(beta, d_sv, d_vp, gamma, g, n=3, panels=64):
    """Eq. 43 with the degree-n phase polynomial integrated directly, without F^k tables (1/m^2).

    The truncation of Eq. 36 alone: L_a = beta^2 / (2 pi A1) e^{-T_sv} int_0^W k_n(cos(gamma + 2t))
    exp(-A1 (tan(gamma/2 + t) - tan(gamma/2))) dt, t = xi - gamma/2 (A0 e^{-A1 tan(gamma/2)} = beta^2
    e^{-T_sv} / (2 pi A1)), with tan(gamma/2 + t) - tan(gamma/2) = sin t / (cos(gamma/2 + t) cos(gamma/2))
    and W = atan2(A1 T_vp, A1^2 + z0 z1) / 2 (z0 = -T_sv cos gamma, z1 = z0 + T_vp; (pi - gamma) / 2
    for D_vp = inf), as tools/stability_map.py ``eq9_stable``: no cancellation.  Composite 8-point
    Gauss-Legendre on ``panels`` panels graded geometrically toward both ends (to 1e-12 W): the
    e^{-A1 tan} decay at t = 0 and, for small A1, its boundary layer at xi = pi/2.
    As n grows it converges to Sun Eq. 5 with 4 pi p_HG where the Legendre series does (|g| < 1).
    ``n=None``: the exact HG phase function instead of the polynomial.
    """
    beta, t_sv, t_vp, gamma, a1 = _geometry(beta, d_sv, d_vp, gamma)
    w = None if n is None else hg_power_coefficients(g, n)
    z0 = -t_sv * np.cos(gamma)
    c0, s0 = np.cos(0.5 * gamma), np.sin(0.5 * gamma)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        width = np.where(np.isfinite(t_vp),
                         0.5 * np.arctan2(a1 * np.where(np.isfinite(t_vp), t_vp, 0.0),
                                          a1 * a1 + z0 * (z0 + np.where(np.isfinite(t_vp), t_vp, 0.0))),
                         0.5 * (math.pi - gamma))
        width = np.maximum(width, 0.0)
        e = np.concatenate([[0.0], 0.5 * np.geomspace(1e-12, 1.0, panels // 2)])
        e = np.concatenate([e, 1.0 - e[-2::-1]])                  # graded at both ends
        lo, hi = e[:-1], e[1:]
        half = 0.5 * (hi - lo)
        s = (half[:, None] * _GL8_X + (0.5 * (hi + lo))[:, None]).ravel()      # nodes in [0, 1]
        wt = (half[:, None] * _GL8_W).ravel()
        t = width[..., None] * s
        den = (c0[..., None] * np.cos(t) - s0[..., None] * np.sin(t)) * c0[..., None]
        expo = np.where(den > 0, -a1[..., None] * np.sin(t) / np.where(den > 0, den, 1.0), -np.inf)
        mu = np.cos(gamma[..., None] + 2.0 * t)
        phase = hg_4pi(g, mu) if w is None else phase_polynomial(w, mu)
        integral = np.sum(phase * np.exp(expo) * wt, axis=-1) * width
        return np.where(a1 > 0, beta * beta / (2.0 * math.pi * a1) * np.exp(-t_sv) * integral, np.nan)
