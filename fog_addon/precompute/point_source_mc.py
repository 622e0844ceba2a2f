"""Monte Carlo radiance around an isotropic point source in an infinite homogeneous medium, by scattering
order, numpy only: what ``apsf.multiple_scattering_table`` bakes, and the reference of the seed's own check.

The problem of Narasimhan, Ramamoorthi and Nayar (``002``, §2, Fig. 1a): a source of radiant intensity I0 = 1
(power 4 pi) at the origin, extinction 1 (distances are optical thicknesses T), single-scattering albedo W0,
Henyey-Greenstein phase function of parameter q.  Photons are followed by free flights of unit mean length
and scattering events (weight x W0, a new direction drawn from p_HG), and the radiance I(T, mu) on the sphere
of radius T is estimated by the crossing estimator: every crossing of the sphere by a flight adds the photon's
weight / |mu| to the bin of mu = cos(angle between the flight and the outward radial direction).  The
crossings are tallied as expected values: every crossing of the flight's whole line ahead, at distance s,
counts with the probability e^{-s} that the photon gets there, whatever free path it then draws (the same
mean, a smaller variance):

    I(T, mu) = (4 pi / N) sum w / |mu| / (4 pi T^2 * 2 pi d mu).

Each crossing is tallied by the number of scatterings before it (its order), so the single-scattering part
(order 1) can be checked against the closed forms and the multiple part (order >= 2) read apart.  The
unscattered light (order 0) crosses at mu = 1 only: it is the source's direct light, not the glow.  A viewer at
distance T from the source sees, at an angle theta from the source's direction, I(T, cos theta).

Photons whose weight falls below ``roulette`` play Russian roulette (survive with probability 1/10 at ten times
the weight): unbiased.  A photon farther than ``r_max`` from the source is dropped (biased low by what
returns from there: choose r_max a few diffusion lengths past the largest T).
"""
import math

import numpy as np

EXPECT_LENGTH = 40.0   # optical lengths along a flight over which its crossings are tallied (e^-40: nothing after)
DEFAULT_EDGES_DEG = np.concatenate([[0.0], np.geomspace(0.25, 180.0, 48)])   # theta bin edges (deg)


def sample_hg(rng, q, n):
    """cos of n scattering angles drawn from Henyey-Greenstein of parameter q."""
    u = rng.random(n)
    if abs(q) < 1e-6:
        return 2.0 * u - 1.0
    s = (1.0 - q * q) / (1.0 - q + 2.0 * q * u)
    return np.clip((1.0 + q * q - s * s) / (2.0 * q), -1.0, 1.0)


def turn(directions, cos_t, phi):
    """Unit directions turned by polar angle acos(cos_t) and azimuth phi about themselves."""
    x, y, z = directions.T
    sin_t = np.sqrt(np.maximum(0.0, 1.0 - cos_t * cos_t))
    cp, sp = np.cos(phi), np.sin(phi)
    polar = np.abs(z) > 0.99999
    den = np.sqrt(np.maximum(1.0 - z * z, 1e-30))
    nx = sin_t * (x * z * cp - y * sp) / den + x * cos_t
    ny = sin_t * (y * z * cp + x * sp) / den + y * cos_t
    nz = -sin_t * cp * den + z * cos_t
    px, py, pz = sin_t * cp, sin_t * sp, np.sign(z) * cos_t
    out = np.stack([np.where(polar, px, nx), np.where(polar, py, ny), np.where(polar, pz, nz)], axis=1)
    return out / np.linalg.norm(out, axis=1, keepdims=True)


def _batches(rng, photons, batch):
    """Photons leaving the source in batches of at most ``batch``: (positions at the origin, isotropic unit
    directions)."""
    done = 0
    while done < photons:
        n = min(batch, photons - done)
        done += n
        u = rng.normal(size=(n, 3))
        yield np.zeros((n, 3)), u / np.linalg.norm(u, axis=1, keepdims=True)


def _tally_crossings(tally, radii, edges_rad, b, c, w, kind, kinds, nb):
    """Add the expected-value crossings of flights (b = p.d, c = p.p at their starts, weights w, each of a
    ``kind`` in range(kinds)) with every sphere of ``radii`` to ``tally`` (flat: radius, kind, theta bin).  A
    line p + s d meets the sphere T at s = -b -+ sqrt(b^2 - c + T^2), where mu = x.d / T = -+ sqrt(...) / T."""
    root = np.sqrt(np.maximum(b[:, None] * b[:, None] - c[:, None] + radii[None, :] ** 2, 0.0))
    meets = (b[:, None] * b[:, None] - c[:, None] + radii[None, :] ** 2) > 0.0
    for sign in (-1.0, 1.0):
        s = -b[:, None] + sign * root
        mu = sign * root / radii[None, :]
        hit = meets & (s > 0.0) & (s < EXPECT_LENGTH)
        if not hit.any():
            continue
        i_photon, i_radius = np.nonzero(hit)
        mu_h = np.clip(mu[hit], -1.0, 1.0)
        k = np.clip(np.searchsorted(edges_rad, np.arccos(mu_h)) - 1, 0, nb - 1)
        val = w[i_photon] * np.exp(-s[hit]) / np.maximum(np.abs(mu_h), 1e-3)
        index = (i_radius * kinds + kind[i_photon]) * nb + k
        tally += np.bincount(index, weights=val, minlength=len(tally))


def radiance(radii, q, albedo, photons=200_000, edges_deg=DEFAULT_EDGES_DEG, max_order=None, r_max=None,
             roulette=1e-2, seed=0, batch=100_000):
    """{T: (I_single, I_multiple)} for each T in ``radii``, each an array over the theta bins ``edges_deg``
    (I per unit source intensity, extinction 1), plus "theta" (the bins' centres in deg) and "edges".
    ``max_order``: stop photons after that many scatterings (None: until roulette or r_max)."""
    radii = np.asarray(radii, float)
    r_max = float(r_max if r_max is not None else radii.max() + 40.0)
    nb = len(edges_deg) - 1
    theta_of_bin = np.radians(np.asarray(edges_deg, float))
    tally = np.zeros(len(radii) * 2 * nb)
    rng = np.random.default_rng(seed)
    for p, d in _batches(rng, photons, batch):
        n = len(p)
        w = np.ones(n)
        order = np.zeros(n, dtype=np.int64)
        while len(w):
            step = -np.log(1.0 - rng.random(len(w)))
            b = np.einsum("ij,ij->i", p, d)
            c = np.einsum("ij,ij->i", p, p)
            scattered = order > 0
            if scattered.any():
                _tally_crossings(tally, radii, theta_of_bin, b[scattered], c[scattered], w[scattered],
                                 (order[scattered] > 1).astype(np.int64), 2, nb)
            p = p + step[:, None] * d
            w = w * albedo
            order = order + 1
            d = turn(d, sample_hg(rng, q, len(w)), rng.uniform(0.0, 2.0 * math.pi, len(w)))
            low = w < roulette
            if low.any():
                live = rng.random(len(w)) < 0.1
                w = np.where(low, np.where(live, w * 10.0, 0.0), w)
            keep = (w > 0.0) & (np.einsum("ij,ij->i", p, p) < r_max * r_max)
            if max_order is not None:
                keep &= order < max_order
            p, d, w, order = p[keep], d[keep], w[keep], order[keep]
    solid = 2.0 * math.pi * (np.cos(np.radians(edges_deg[:-1])) - np.cos(np.radians(edges_deg[1:])))
    out = {"theta": 0.5 * (edges_deg[:-1] + edges_deg[1:]), "edges": np.asarray(edges_deg, float)}
    for i, T in enumerate(radii):
        scale = 4.0 * math.pi / photons / (4.0 * math.pi * T * T) / solid
        t = tally.reshape(len(radii), 2, nb)
        out[float(T)] = (t[i, 0] * scale, t[i, 1] * scale)
    return out


def radiance_by_order(radii, q, max_order, photons=100_000, edges_deg=DEFAULT_EDGES_DEG, r_max=None, seed=0,
                      batch=50_000):
    """I_k(T, theta) / I0 of each scattering order k = 1 .. ``max_order`` without absorption: an array
    (len(radii), max_order, bins), extinction 1.  Any albedo's field then follows without another run:
    a photon scattered k times carries W0^k, so I(W0) = sum_k W0^k I_k (the orders above ``max_order``
    left out: W0^max_order of the light).  Photons farther than ``r_max`` from the source are dropped."""
    radii = np.asarray(radii, float)
    r_max = float(r_max if r_max is not None else radii.max() + 40.0)
    nb = len(edges_deg) - 1
    theta_of_bin = np.radians(np.asarray(edges_deg, float))
    tally = np.zeros(len(radii) * max_order * nb)
    rng = np.random.default_rng(seed)
    for p, d in _batches(rng, photons, batch):
        order = 0
        while len(p) and order <= max_order:
            if order > 0:
                b = np.einsum("ij,ij->i", p, d)
                c = np.einsum("ij,ij->i", p, p)
                _tally_crossings(tally, radii, theta_of_bin, b, c, np.ones(len(p)),
                                 np.full(len(p), order - 1, dtype=np.int64), max_order, nb)
            step = -np.log(1.0 - rng.random(len(p)))
            p = p + step[:, None] * d
            d = turn(d, sample_hg(rng, q, len(p)), rng.uniform(0.0, 2.0 * math.pi, len(p)))
            order += 1
            keep = np.einsum("ij,ij->i", p, p) < r_max * r_max
            p, d = p[keep], d[keep]
    solid = 2.0 * math.pi * (np.cos(np.radians(edges_deg[:-1])) - np.cos(np.radians(edges_deg[1:])))
    scale = 1.0 / photons / (radii[:, None, None] ** 2) / solid[None, None, :]
    return tally.reshape(len(radii), max_order, nb) * scale
