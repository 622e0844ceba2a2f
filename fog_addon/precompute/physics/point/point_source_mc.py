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


def _tally_crossings(tally, radii, edges_rad, b, c, w, kind, kinds, nb, share=1.0, rng=None, share_below=np.inf):
    """Add the expected-value crossings of flights (b = p.d, c = p.p at their starts, weights w, each of a
    ``kind`` in range(kinds)) with every sphere of ``radii`` to ``tally`` (flat: radius, kind, theta bin).  A
    line p + s d meets the sphere T at s = -b -+ sqrt(b^2 - c + T^2), where mu = x.d / T = -+ sqrt(...) / T.
    Only the spheres a flight can cross ahead of it are visited (``_candidates``): those farther out than the
    line's closest approach to the source and, for a flight moving away from it, than its start; the entering
    crossing (-) only where the flight starts outside the sphere.  The bins by mu against the cosines of the
    ``edges_rad`` (theta ascending).  ``share`` < 1: each (flight, sphere) pair of a sphere smaller than
    ``share_below`` is tallied with that probability (``rng``), at 1 / share the weight (unbiased: a flight's
    crossings of neighbouring spheres say much the same)."""
    ip, ir = _candidates(radii, b, c)
    scale = None
    if share < 1.0:
        small = radii[ir] < share_below
        pick = ~small | (rng.random(len(ip)) < share)
        ip, ir = ip[pick], ir[pick]
        scale = np.where(small[pick], 1.0 / share, 1.0)
    if not len(ip):
        return
    cos_edges = np.cos(edges_rad)[::-1]        # ascending
    for lo in range(0, len(ip), CHUNK):
        hi = lo + CHUNK
        _tally_pairs(tally, radii, cos_edges, b, c, w, kind, kinds, nb, ip[lo:hi], ir[lo:hi],
                     None if scale is None else scale[lo:hi])


CHUNK = 65_536   # (flight, sphere) pairs tallied at once: their temporaries stay in the processor's cache


def _tally_pairs(tally, radii, cos_edges, b, c, w, kind, kinds, nb, ip, ir, scale):
    """``_tally_crossings`` of the (flight ``ip``, sphere ``ir``) pairs, each of weight ``scale`` (None: 1)."""
    bb, cc, rr = b[ip], c[ip], radii[ir]
    rr2 = rr ** 2
    disc = bb * bb - cc + rr2
    root = np.sqrt(np.maximum(disc, 0.0))
    meets = disc > 0.0
    outside = rr2 < cc
    for sign in (-1.0, 1.0):
        if sign < 0.0:
            sub = np.nonzero(outside & meets)[0]
            s = -bb[sub] - root[sub]
            hit = (s > 0.0) & (s < EXPECT_LENGTH)
        else:
            sub = None
            s = -bb + root
            hit = meets & (s > 0.0) & (s < EXPECT_LENGTH)
        if not hit.any():
            continue
        at = np.nonzero(hit)[0] if sub is None else sub[hit]
        s_h = s[hit]
        i_photon, i_radius = ip[at], ir[at]
        mu_h = np.clip(sign * root[at] / rr[at], -1.0, 1.0)
        k = np.clip(nb - np.searchsorted(cos_edges, mu_h, side="right"), 0, nb - 1)
        val = w[i_photon] * np.exp(-s_h) / np.maximum(np.abs(mu_h), 1e-3)
        if scale is not None:
            val = val * scale[at]
        index = (i_radius * kinds + kind[i_photon]) * nb + k
        tally += np.bincount(index, weights=val, minlength=len(tally))


def _candidates(radii, b, c):
    """(photon, radius) index pairs, photon-major and in the order of ``radii`` within a photon, of the spheres
    each flight may cross ahead of it: T^2 > c - b^2 (its line comes nearer the source than T) and, if b >= 0
    (moving away), T^2 > c (the sphere is about it).  A slightly generous bound: ``_tally_crossings`` tests
    each pair exactly."""
    order = np.argsort(radii, kind="stable")
    sorted_sq = np.asarray(radii, float)[order] ** 2
    bound = np.where(b >= 0.0, c, np.maximum(c - b * b, 0.0)) * (1.0 - 1e-9)
    start = np.searchsorted(sorted_sq, bound, side="right")
    counts = len(radii) - start
    total = int(counts.sum())
    if not total:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    ip = np.repeat(np.arange(len(b)), counts)
    offsets = np.cumsum(counts) - counts
    slot = start[ip] + (np.arange(total) - offsets[ip])
    ir = order[slot]
    if not np.all(np.diff(order) > 0):   # radii not ascending: keep each photon's pairs in their given order
        key = ip * len(radii) + ir
        keep = np.argsort(key, kind="stable")
        ip, ir = ip[keep], ir[keep]
    return ip, ir


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
                      batch=50_000, window=None, progress=None):
    """I_k(T, theta) / I0 of each scattering order k = 1 .. ``max_order`` without absorption: an array
    (len(radii), max_order, bins), extinction 1.  Any albedo's field then follows without another run:
    a photon scattered k times carries W0^k, so I(W0) = sum_k W0^k I_k (the orders above ``max_order``
    left out: W0^max_order of the light).  Photons farther than ``r_max`` from the source are dropped.

    ``window`` = (from_order, r_near, m, share): a weight window in the distance from the source for the orders
    from ``from_order`` on: a photon that goes farther than 2 r_near plays Russian roulette (surviving with 1/m
    at m times the weight), one that comes back within r_near is split into m copies of 1/m the weight
    (unbiased; far out, where the spheres are large and crossed by many, one photon in m is followed); and a
    flight's crossings of the spheres within r_near are tallied each with probability ``share``
    (``_tally_crossings``).  ``progress(done, total)``: called every order of every batch (``done`` of
    ``photons * max_order`` photon-orders); it may raise an exception (``table_cache.BakeCancelled``) to stop."""
    radii = np.asarray(radii, float)
    r_max = float(r_max if r_max is not None else radii.max() + 40.0)
    nb = len(edges_deg) - 1
    theta_of_bin = np.radians(np.asarray(edges_deg, float))
    tally = np.zeros((len(radii), max_order, nb))
    own = np.zeros(len(radii) * nb)           # one order's tally
    zero_kind = np.zeros(batch, dtype=np.int64)
    rng = np.random.default_rng(seed)
    from_order, r_near, m, share = window if window is not None else (max_order + 1, 0.0, 1, 1.0)
    done = 0
    for p, d in _batches(rng, photons, batch):
        n_batch = len(p)
        w = np.ones(n_batch)
        thin = np.zeros(n_batch, dtype=bool)
        order = 0
        while len(p) and order <= max_order:
            if order > 0:
                b = np.einsum("ij,ij->i", p, d)
                c = np.einsum("ij,ij->i", p, p)
                own[:] = 0.0
                kind = zero_kind[:len(p)] if len(p) <= batch else np.zeros(len(p), dtype=np.int64)
                _tally_crossings(own, radii, theta_of_bin, b, c, w, kind, 1, nb,
                                 share if order >= from_order else 1.0, rng, r_near)
                tally[:, order - 1, :] += own.reshape(len(radii), nb)
            if order == max_order:
                break
            step = -np.log(1.0 - rng.random(len(p)))
            p = p + step[:, None] * d
            d = turn(d, sample_hg(rng, q, len(p)), rng.uniform(0.0, 2.0 * math.pi, len(p)))
            order += 1
            r2 = np.einsum("ij,ij->i", p, p)
            if progress is not None:
                progress(done + order * n_batch, photons * max_order)
            if m > 1 and order >= from_order:
                going = ~thin & (r2 > 4.0 * r_near * r_near)
                if going.any():
                    live = rng.random(len(p)) < 1.0 / m
                    w = np.where(going, np.where(live, w * m, 0.0), w)
                    thin |= going
                back = thin & (r2 < r_near * r_near) & (w > 0.0)
                if back.any():
                    w[back] /= m
                    thin &= ~back
                    copies = np.repeat(np.arange(len(p)), np.where(back, m, 1))
                    p, d, w, thin, r2 = p[copies], d[copies], w[copies], thin[copies], r2[copies]
            keep = (r2 < r_max * r_max) & (w > 0.0)
            if not keep.all():
                p, d, w, thin = p[keep], d[keep], w[keep], thin[keep]
        done += n_batch * max_order
    if progress is not None:
        progress(photons * max_order, photons * max_order)
    solid = 2.0 * math.pi * (np.cos(np.radians(edges_deg[:-1])) - np.cos(np.radians(edges_deg[1:])))
    scale = 1.0 / photons / (radii[:, None, None] ** 2) / solid[None, None, :]
    return tally * scale
