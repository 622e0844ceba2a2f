"""The atmospheric point spread function (APSF): multiple scattering around an isotropic point source in an
infinite homogeneous medium, after Narasimhan, Ramamoorthi and Nayar, "Analytic Rendering of Multiple
Scattering in Participating Media" (``002``), numpy only.

The light field of a point source of radiant intensity I0 depends on the optical distance T = sigma R and on
mu, the cosine of the angle between the light's direction and the outward radial one.  A viewer at distance R
from the source sees, at the angle theta from the source's direction, I(T, cos theta): the APSF is the glow's
profile directly, with no integral along the ray.

Their solution (§2, Eq. 24-27) with the Henyey-Greenstein phase function of parameter q and albedo W0:

    W_k = W0 (2k + 1) q^k                                  (Eq. 12, scaled by W0 as §2.2.1 says),
    alpha_m = m + 1,  beta_m = (2m + 1) / m (1 - W_{m-1} / (2m - 1)) = (2m + 1) / m (1 - W0 q^{m-1})   (Eq. 25),
    g_m(T) = I0 e^{-beta_m T - alpha_m log T},  g_0 = 0                                              (Eq. 24),
    I(T, mu) = sum_{m>=0} (g_m(T) + g_{m+1}(T)) L_m(mu)                                             (Eq. 27).

It converges for T > 1 only (§2.1: each g_{m+1} / g_m ~ q / T for large m), and peaked profiles (small T, q near
1) need many terms and ring when cut (Fig. 2).  ``apsf_series`` is the series as printed, for the seed's own
check (docs/measurements/2026-11-27-apsf.md); the renderer's glow comes from transport instead
(``multiple.py``).

Units: T dimensionless (optical thickness), I per unit source intensity I0 in units of sigma^2 (radiance
I0 sigma^2 / sr at extinction sigma: multiply by sigma^2 for 1/m^2).
"""
import numpy as np
from numpy.polynomial import legendre

def legendre_table(mu, count):
    """L_0 .. L_{count-1} at ``mu``, shape (count,) + mu.shape (numpy's Legendre-Vandermonde matrix)."""
    return np.moveaxis(legendre.legvander(np.asarray(mu, float), count - 1), -1, 0)


def apsf_exponents(q, albedo, count):
    """(alpha_m, beta_m) for m = 0 .. count-1 (Eq. 25; m = 0 unused: g_0 = 0)."""
    m = np.arange(count, dtype=float)
    alpha = m + 1.0
    with np.errstate(divide="ignore", invalid="ignore"):
        beta = (2.0 * m + 1.0) / m * (1.0 - float(albedo) * float(q) ** np.maximum(m - 1.0, 0.0))
    beta[0] = np.inf
    return alpha, beta


def apsf_g(T, q, albedo, count):
    """g_m(T) / I0 for m = 0 .. count (Eq. 24; g_0 = 0): shape (count + 1,) + T.shape."""
    T = np.asarray(T, float)
    alpha, beta = apsf_exponents(q, albedo, count + 1)
    g = np.exp(-beta[:, None] * T.reshape(1, -1) - alpha[:, None] * np.log(T.reshape(1, -1)))
    g[0] = 0.0
    return g.reshape((count + 1,) + T.shape)


def apsf_series(T, mu, q, albedo=1.0, terms=200):
    """I(T, mu) / I0 by Eq. 27 cut after ``terms`` terms, for T > 1 (``T`` broadcast against ``mu``)."""
    T, mu = np.broadcast_arrays(np.asarray(T, float), np.asarray(mu, float))
    if np.any(T <= 1.0):
        raise ValueError("the APSF series converges for T > 1 only (Narasimhan et al. §2.1)")
    g = apsf_g(T, q, albedo, terms)
    L = legendre_table(mu, terms)
    return np.sum((g[:-1] + g[1:]) * L, axis=0)
