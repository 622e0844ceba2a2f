"""The photon walk that bakes a spot's (or an area light's) multiple-scattering table, numpy only.

The table (``spot_multiple.py``) holds J, the order >= 1 radiance scattered towards each outgoing direction, on a grid
of cells: the optical distance T from the lamp (ROWS, geometric), the angle psi from the axis (PSI_NODES bands), and
the outgoing direction's angle theta from the radial direction e_r (THETA_NODES) and azimuth phi about it (PHI_NODES).
``collide`` fills it by Monte Carlo: photons leave the lamp with Blender's spot falloff (``_emit``); every collision
of an already scattered photon adds w p(w_in . w_out) / V to its (T, psi) cell at each tabulated outgoing direction
(a collision estimator, exact in the directions: no angular binning).  The first collision is drawn log-uniformly in
distance, weighted, so that the cells near the lamp, where the beam is brightest, hold many collisions.

* **A bounded bake** (``collide``; docs/measurements/2026-11-29-bake-time.md).  In fog of albedo 1 (a white
  fog's) nothing absorbs a photon: its walk ends only R_MAX from the lamp, R_MAX^2 (1 - g) / 2 collisions on
  average (1 800 at g 0), and the bake took 12 minutes.  Three things bound it, none biased beyond the
  table's own noise: the orders from EXACT_ORDERS on, whose light is spread over directions, are tallied by
  their moments to Legendre degree MOMENT_DEGREE (``moment_matrices``: 15 numbers a collision instead of 192
  phase functions); a weight window in the distance from the lamp (``weight_window``: Russian roulette far
  out, splitting back near the lamp, unbiased) follows one photon in m where the walks spend most of their
  collisions; a walk ends after MAX_WALK mean exit times (0.1 % of the collisions).  Every table then bakes in
  4-6 s on 2 cores (``walk_counts`` gives the work, ``spot_multiple.estimate_seconds`` how long before it starts;
  ``progress`` reports it and may stop it).

Units: extinction 1, per unit on-axis intensity; distances optical.
"""
import functools
import math

import numpy as np

from ..point import point_source_mc

T_MIN = 0.005          # the first row's optical distance from the lamp (below: J T held, J ~ 1/T)
T_MAX = 40.0           # the last row's (beyond: held; e^-40 of the light)
ROWS = 28              # rows in T, geometric
PSI_NODES = 37         # bands in psi, 0 .. 180 deg every 5 deg (the cone edge is sharp near the lamp)
THETA_NODES = 32       # columns in theta = pi u^2 (u uniform: dense towards e_r, where J peaks)
PHI_NODES = 4          # channels: phi = 0, 60, 120, 180 deg
PHOTONS = 100_000      # a bake's photons (docs/measurements/2026-11-29-bake-time.md)
SEED = 20261128
BATCH = 10_000         # photons walking at once (``collide``)
EXACT_ORDERS = 12      # orders below this tallied exactly at every direction; from it on by moments
MOMENT_DEGREE = 4      # the moments' Legendre degree (``moment_matrices``)
NEAR_STEPS = 25.0      # a walk's collisions within the weight window's r_near (``weight_window``)
FAR_STEPS = 30.0       # and beyond it, about, once thinned
PROGRESS_STEPS = 64    # ``collide`` reports its progress every this many steps (and as photons start)
MERGE_T = 1.0          # the later orders' moments pooled over the rows nearer than this (``_merge_near_rows``)
MAX_WALK = 4.0         # a walk ends after this many times ``exit_steps`` collisions (0.1 % of the collisions)
FIRST_RANGE = (1e-3, 30.0)   # the first collision's distance, drawn log-uniformly in it
R_MAX = T_MAX + 20.0   # photons farther than this are dropped
ROULETTE = 1e-3


def row_distances():
    """The rows' optical distances T (ROWS, geometric from T_MIN to T_MAX)."""
    return np.geomspace(T_MIN, T_MAX, ROWS)


def psi_angles():
    """The bands' angles from the axis (rad), PSI_NODES from 0 to pi."""
    return np.linspace(0.0, math.pi, PSI_NODES)


def theta_angles():
    """The columns' angles of the outgoing direction from e_r (rad): pi u^2."""
    return math.pi * np.linspace(0.0, 1.0, THETA_NODES) ** 2


def phi_angles():
    """The channels' azimuths of the outgoing direction about e_r from the axis' plane (rad)."""
    return np.linspace(0.0, math.pi, PHI_NODES)


def _falloff(c, cos_half, blend):
    """Blender's spot factor at cosine c to the axis (``spot.spot_falloff`` on numpy arrays)."""
    if blend <= 0.0:
        return (c > cos_half).astype(np.float64)
    x = np.clip((c - cos_half) / ((1.0 - cos_half) * blend), 0.0, 1.0)
    return np.where(c > cos_half, x * x * (3.0 - 2.0 * x), 0.0)


def cone_power(cos_half, blend):
    """int f dOmega over the sphere (sr) of Blender's spot factor: 2 pi (1 - cos_half)(1 - blend / 2), the
    smoothstep's mean over its ramp being 1/2; ``blend`` None: Lambert's, pi."""
    if blend is None:
        return math.pi
    return 2.0 * math.pi * (1.0 - cos_half) * (1.0 - 0.5 * blend)


def _emit(rng, n, cos_half, blend):
    """n unit directions about +z distributed as the spot factor (rejection in the cosine)."""
    if blend is None:   # Lambert: c = sqrt(u) has density 2c on [0, 1]
        c = np.sqrt(rng.random(n))
        phi = rng.uniform(0.0, 2.0 * math.pi, n)
        s = np.sqrt(np.maximum(1.0 - c * c, 0.0))
        return np.stack([s * np.cos(phi), s * np.sin(phi), c], axis=1)
    out, have = [], 0
    while have < n:
        c = rng.uniform(cos_half, 1.0, 2 * n)
        c = c[rng.random(2 * n) < _falloff(c, cos_half, blend)]
        out.append(c)
        have += len(c)
    c = np.concatenate(out)[:n]
    phi = rng.uniform(0.0, 2.0 * math.pi, n)
    s = np.sqrt(np.maximum(1.0 - c * c, 0.0))
    return np.stack([s * np.cos(phi), s * np.sin(phi), c], axis=1)


def _hg(g, c):
    """Henyey-Greenstein phase function per steradian."""
    return (1.0 - g * g) / (4.0 * math.pi * (1.0 + g * g - 2.0 * g * c) ** 1.5)


def _edges(nodes, log):
    """Cell edges about ``nodes``: midpoints (geometric if ``log``), the ends half a step out."""
    x = np.log(nodes) if log else nodes
    mid = 0.5 * (x[1:] + x[:-1])
    e = np.concatenate([[x[0] - (mid[0] - x[0])], mid, [x[-1] + (x[-1] - mid[-1])]])
    return np.exp(e) if log else e


def _out_directions():
    """(THETA_NODES * PHI_NODES, 3) outgoing directions in the local frame (e_r, e_psi, e_phi)."""
    th, ph = np.meshgrid(theta_angles(), phi_angles(), indexing="ij")
    th, ph = th.ravel(), ph.ravel()
    return np.stack([np.cos(th), np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph)], axis=1)


def _moment_powers():
    """(p, q) of the monomials a^p b^q (p + q <= MOMENT_DEGREE) that ``collide`` tallies for the orders from
    EXACT_ORDERS on: a, b the incoming direction's components along e_r and e_psi."""
    return [(p, k - p) for k in range(MOMENT_DEGREE + 1) for p in range(k, -1, -1)]


def _monomials(a, b):
    """(n, len(_moment_powers())) the monomials a^p b^q of each (a, b)."""
    pa, pb = [np.ones_like(a), a], [np.ones_like(b), b]
    for _ in range(MOMENT_DEGREE - 1):
        pa.append(pa[-1] * a)
        pb.append(pb[-1] * b)
    powers = _moment_powers()
    out = np.empty((len(a), len(powers)))
    for k, (i, j) in enumerate(powers):
        np.multiply(pa[i], pb[j], out=out[:, k])
    return out


def _legendre_series(coefficients, x):
    """sum_l coefficients[l] P_l(x) (numpy's Legendre series)."""
    return np.polynomial.legendre.legval(x, coefficients)


def _clamped_cosine_coefficients(degree):
    """The Legendre coefficients f_l (l <= degree) of max(0, -x) on [-1, 1]: (2l + 1) / 2 int max(0, -x) P_l dx
    (Gauss-Legendre on [-1, 0], where it is a polynomial: exact)."""
    x, w = np.polynomial.legendre.leggauss(degree + 2)
    x, w = 0.5 * (x - 1.0), 0.5 * w
    return np.array([(2 * l + 1) / 2.0 * np.sum(w * (-x) * np.polynomial.legendre.legval(x, np.eye(l + 1)[l]))
                     for l in range(degree + 1)])


@functools.lru_cache(maxsize=None)
def moment_matrices(g):
    """(A_J, A_E), each (len(_moment_powers()), THETA_NODES * PHI_NODES): the order's tally of the monomials
    S_pq = sum w a^p b^q of a cell, times A_J, is sum w p_HG truncated to the Legendre degrees <= MOMENT_DEGREE
    (p_HG = sum_l (2l + 1) g^l P_l / 4 pi) at each outgoing direction, mirror-symmetric in phi (``collide``);
    times A_E, sum w max(0, -w_in . n) so truncated.  Mirrored in phi, the series is even in the component c
    along e_phi, and c^2 = 1 - a^2 - b^2 on the sphere: a polynomial in (a, b) of degree <= MOMENT_DEGREE, fitted
    here by least squares on directions spread over the sphere (exact: the fit's residual is checked)."""
    out = _out_directions()
    mirror = out * np.array([1.0, 1.0, -1.0])
    rng = np.random.default_rng(1)
    d = rng.normal(size=(600, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    phase = (2 * np.arange(MOMENT_DEGREE + 1) + 1) * float(g) ** np.arange(MOMENT_DEGREE + 1) / (4.0 * math.pi)
    facing = _clamped_cosine_coefficients(MOMENT_DEGREE)
    basis = _monomials(d[:, 0], d[:, 1])
    result = []
    for coefficients in (phase, facing):
        target = 0.5 * (_legendre_series(coefficients, d @ out.T) + _legendre_series(coefficients, d @ mirror.T))
        a = np.linalg.lstsq(basis, target, rcond=None)[0]
        assert np.abs(basis @ a - target).max() <= 1e-8 * max(1.0, np.abs(target).max())
        result.append(a)
    return tuple(result)


def _split_out():
    """(the outgoing directions' order with those in the axis' plane first (phi 0 or pi, or theta 0: each its own
    mirror), how many of them there are)."""
    flat = np.abs(_out_directions()[:, 2]) < 1e-9
    return np.concatenate([np.nonzero(flat)[0], np.nonzero(~flat)[0]]), int(flat.sum())


def _hg_power(dot, g):
    """(1 + g^2 - 2 g dot)^-1.5 in place of ``dot`` (float32): the Henyey-Greenstein phase function over its
    constant (1 - g^2) / 4 pi."""
    dot *= -2.0 * g
    dot += 1.0 + g * g
    root = np.sqrt(dot)
    dot *= root
    np.reciprocal(dot, out=dot)
    return dot


def exit_steps(g):
    """The mean number of collisions before a walk without absorption leaves R_MAX: a diffusion's exit time from
    a ball, R_MAX^2 (1 - g) / 2 (steps of mean square 2 / (1 - g); measured 1840 at g 0, 310 at g 0.85)."""
    return R_MAX * R_MAX * (1.0 - float(g)) / 2.0


def steps_within(radius, g):
    """The mean number of collisions a walk without absorption from the lamp makes within ``radius`` of it
    before it leaves R_MAX: the diffusion's Green function in the ball, (1 - g) (1.5 R^2 - R^3 / R_MAX)."""
    radius = min(float(radius), R_MAX)
    return (1.0 - float(g)) * (1.5 * radius * radius - radius ** 3 / R_MAX)


def weight_steps(albedo):
    """The collisions after which a photon's weight W0^k falls below ROULETTE (with roulette's tail: a tenth
    more); infinite without absorption."""
    return math.inf if albedo >= 1.0 else 1.1 * math.log(1.0 / ROULETTE) / -math.log(float(albedo))


def expected_steps(g, albedo):
    """The mean number of collisions of a photon's walk (``collide`` without its weight window): it ends when its
    weight falls below ROULETTE (``weight_steps``) or when it leaves R_MAX (``exit_steps``, taken as
    exponentially distributed: E[min(weight's, exit)] = mu (1 - e^{-n / mu}))."""
    exit_mean = exit_steps(g)
    return exit_mean * (1.0 - math.exp(-weight_steps(albedo) / exit_mean))


def weight_window(g, albedo):
    """(r_near, m) of ``collide``'s weight window: a photon past EXACT_ORDERS that goes farther than 2 r_near from
    the lamp plays Russian roulette, surviving with 1/m at m times the weight; one that comes back within r_near
    is split into m copies of 1/m the weight (unbiased both).  r_near holds NEAR_STEPS of a walk's collisions
    (``steps_within``); m brings those beyond to about FAR_STEPS.  Where the field is sharp (near the lamp and
    its beam) every photon is followed; far out, where the cells are large and the light spread over them (and
    where an albedo near 1 lets a walk run for R_MAX^2 (1 - g) / 2 collisions), one in m."""
    lo, hi = 0.0, R_MAX
    for _ in range(50):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if steps_within(mid, g) < NEAR_STEPS else (lo, mid)
    r_near = min(max(lo, 1.0), 0.5 * T_MAX)
    total = expected_steps(g, albedo)
    beyond = total - min(total, steps_within(r_near, g))
    return r_near, max(1, int(math.ceil(beyond / FAR_STEPS)))


LAST_WALK = {}   # the last ``collide``'s counts: exact tallies, photon steps, loop iterations (``walk_counts``)


def collide(g, albedo, cos_half, blend, photons=PHOTONS, seed=SEED, batch=BATCH, progress=None,
            exact_orders=EXACT_ORDERS, window=None):
    """(J, collisions, E) per cell: J (ROWS, PSI_NODES, THETA_NODES, PHI_NODES) per unit on-axis intensity at
    extinction 1, the axis +z (module docstring); E the same shape: the irradiance from orders >= 2 of a surface
    facing each tabulated direction, per unit albedo (the shading multiplies by it).

    Photons stream through a pool of ``batch``: when half of it has finished, new photons fill it.  Orders 1 ..
    ``exact_orders`` - 1 are tallied exactly at every outgoing direction (``_tally_exact``); later orders, whose
    light is spread over directions, by their moments (``moment_matrices``), under a weight window in the distance
    from the lamp (``window`` = (r_near, m), default ``weight_window``).  A walk ends when its weight falls below
    ROULETTE (roulette), beyond R_MAX or after MAX_WALK times ``exit_steps`` collisions.  ``progress(done,
    total)``: called as photons finish (``done`` of ``photons``), every PROGRESS_STEPS steps; it may raise
    ``table_cache.BakeCancelled`` to stop the bake."""
    t_edges, p_edges = _edges(row_distances(), True), _edges(psi_angles(), False)
    p_edges[0], p_edges[-1] = 0.0, math.pi
    cos_edges = np.cos(p_edges)[::-1].copy()                  # increasing: psi bands from the far end
    n_cells = ROWS * PSI_NODES
    perm, n_flat = _split_out()
    out = _out_directions()[perm].astype(np.float32)           # (K, 3), those in the axis' plane first
    radial = np.ascontiguousarray(out[:, :2].T)                # (2, K): a, b -> a out_r + b out_psi
    across = out[n_flat:, 2]
    a_j, a_e = moment_matrices(float(g))
    n_moments = a_j.shape[0]
    tally = np.zeros((n_cells, len(out)))
    flux = np.zeros((n_cells, len(out)))      # the irradiance of surfaces facing each direction, orders >= 2
    moments = np.zeros(n_cells * n_moments)   # the later orders' (``_monomials``)
    count = np.zeros(n_cells)
    rng = np.random.default_rng(seed)
    r_near, m = weight_window(g, albedo) if window is None else window
    r_far = 2.0 * r_near
    max_walk = int(MAX_WALK * exit_steps(g))
    lo, hi = FIRST_RANGE
    log_range = math.log(hi / lo)
    p, d, w = np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0)
    order = np.zeros(0, dtype=np.int32)
    thin = np.zeros(0, dtype=bool)            # rouletted beyond r_far (carrying m times the weight)
    launched, steps, n_exact, n_steps = 0, 0, 0, 0
    while True:
        fresh = 0
        if len(w) <= batch // 2 and launched < photons:
            fresh = min(batch - len(w), photons - launched)
            launched += fresh
            p = np.concatenate([p, np.zeros((fresh, 3))])
            d = np.concatenate([d, _emit(rng, fresh, cos_half, blend)])
            w = np.concatenate([w, np.ones(fresh)])
            order = np.concatenate([order, np.zeros(fresh, dtype=np.int32)])
            thin = np.concatenate([thin, np.zeros(fresh, dtype=bool)])
        if progress is not None and (fresh or steps % PROGRESS_STEPS == 0):
            progress(launched - len(w), photons)
        if not len(w):
            break
        steps += 1
        n_steps += len(w)
        u = rng.random(len(w))
        s = -np.log1p(-u)
        if fresh:   # the new photons (the last ``fresh``): the first collision log-uniform in distance, weighted
            s0 = lo * (hi / lo) ** u[-fresh:]
            s[-fresh:] = s0
            w[-fresh:] *= np.exp(-s0) * s0 * log_range
        p += s[:, None] * d
        r = np.sqrt(np.einsum("ij,ij->i", p, p))
        inside = (r > t_edges[0]) & (r < t_edges[-1])
        if fresh:
            inside[-fresh:] = False                             # order 0: the lamp's own light, not tallied
        idx = np.nonzero(inside)[0]
        if len(idx):
            rr = r[idx]
            cz = np.clip(p[idx, 2] / rr, -1.0, 1.0)
            dd = d[idx]
            a = np.einsum("ij,ij->i", dd, p[idx]) / rr
            sin_psi = np.sqrt(np.maximum(1.0 - cz * cz, 0.0))
            b = np.where(sin_psi > 1e-9, (a * cz - dd[:, 2]) / np.maximum(sin_psi, 1e-12), dd[:, 0])
            cell = ((np.searchsorted(t_edges, rr) - 1) * PSI_NODES
                    + np.clip(PSI_NODES - np.searchsorted(cos_edges, cz), 0, PSI_NODES - 1))
            count += np.bincount(cell, minlength=n_cells)
            ww, kk = w[idx], order[idx]
            exact = kk < exact_orders
            if exact.any():
                n_exact += int(exact.sum())
                _tally_exact(tally, flux, cell[exact], a[exact], b[exact], ww[exact], kk[exact] >= 2, g, albedo,
                             radial, n_flat, across)
            late = ~exact
            if late.any():
                mono = _monomials(a[late], b[late])
                mono *= ww[late][:, None]
                index = cell[late][:, None] * n_moments + np.arange(n_moments)
                moments += np.bincount(index.ravel(), weights=mono.ravel(), minlength=len(moments))
        w *= albedo
        order += 1
        d = point_source_mc.turn(d, point_source_mc.sample_hg(rng, g, len(w)),
                                 rng.uniform(0.0, 2.0 * math.pi, len(w)))
        low = w < ROULETTE
        if low.any():
            live = rng.random(len(w)) < 0.1
            w = np.where(low, np.where(live, w * 10.0, 0.0), w)
        if m > 1:
            late = order >= exact_orders
            going = late & ~thin & (r > r_far)
            if going.any():
                live = rng.random(len(w)) < 1.0 / m
                w = np.where(going, np.where(live, w * m, 0.0), w)
                thin |= going
            back = thin & (r < r_near) & (w > 0.0)
            if back.any():
                w[back] /= m
                thin &= ~back
                copies = np.repeat(np.arange(len(w)), np.where(back, m, 1))
                p, d, w, order, thin, r = p[copies], d[copies], w[copies], order[copies], thin[copies], r[copies]
        keep = (w > 0.0) & (r < R_MAX) & (order < max_walk)
        if not keep.all():
            p, d, w, order, thin = p[keep], d[keep], w[keep], order[keep], thin[keep]
    LAST_WALK.update(exact=n_exact, steps=n_steps, iterations=steps)
    volume = ((t_edges[1:, None] ** 3 - t_edges[:-1, None] ** 3) / 3.0 * 2.0 * math.pi
              * (np.cos(p_edges[None, :-1]) - np.cos(p_edges[None, 1:])))
    moments = _merge_near_rows(moments.reshape(ROWS, PSI_NODES, n_moments), volume).reshape(n_cells, n_moments)
    unperm = np.argsort(perm)
    tally = tally[:, unperm] * ((1.0 - g * g) / (4.0 * math.pi)) + moments @ a_j
    flux = flux[:, unperm] + (moments @ a_e) / albedo
    shape = (ROWS, PSI_NODES, THETA_NODES, PHI_NODES)
    scale = (cone_power(cos_half, blend) / photons) / volume[..., None]
    return (tally.reshape(ROWS, PSI_NODES, -1) * scale).reshape(shape), count.reshape(ROWS, PSI_NODES), (
        flux.reshape(ROWS, PSI_NODES, -1) * scale).reshape(shape)


def _merge_near_rows(moments, volume, merge_t=None):
    """The moments (ROWS, PSI_NODES, M) of the later orders with the rows nearer the lamp than MERGE_T pooled
    in each band: each such row takes the band's pooled sums times its share of their volume.  The light of
    the later orders has forgotten the lamp (its photons are a dozen free paths from it): flat over the first
    rows, whose cells are small and would each hold a handful of the few photons that come back."""
    merge_t = MERGE_T if merge_t is None else merge_t
    near = row_distances() < merge_t
    if near.sum() < 2:
        return moments
    out = moments.copy()
    pooled = moments[near].sum(axis=0)                          # (PSI_NODES, M)
    share = volume[near] / volume[near].sum(axis=0)             # (rows, PSI_NODES)
    out[near] = share[..., None] * pooled[None]
    return out


def _tally_exact(tally, flux, cell, a, b, w, surfaces, g, albedo, radial, n_flat, across, chunk=4096):
    """Add the collisions' sum w (1 + g^2 - 2 g w_in . w_out)^-1.5 to ``tally`` (per cell, at every outgoing
    direction of ``radial``'s columns, mirrored in phi: the mean of the direction and its mirror) and, for those of
    ``surfaces`` (order >= 2), w / W0 max(0, -w_in . n) to ``flux``: (a, b, c) the incoming direction in the cell's
    frame, |c| = sqrt(1 - a^2 - b^2) (the mirror takes both signs); the first ``n_flat`` directions are their own
    mirrors, the others' components along e_phi are ``across``.  float32, in chunks, the collisions sorted by cell
    (one ``reduceat`` a cell)."""
    order = np.argsort(cell, kind="stable")
    cell, surfaces = cell[order], surfaces[order]
    ab = np.stack([a[order], b[order]], axis=1).astype(np.float32)
    c = np.sqrt(np.maximum(1.0 - a[order] ** 2 - b[order] ** 2, 0.0)).astype(np.float32)
    w = w[order].astype(np.float32)
    wf = w * (surfaces / albedo).astype(np.float32)
    k = radial.shape[1]
    for lo in range(0, len(cell), chunk):
        sl = slice(lo, lo + chunk)
        dot = ab[sl] @ radial                                   # (n, K): the in-plane part of w_in . w_out
        side = c[sl, None] * across                             # the part along e_phi (its sign: the mirror)
        plus = dot[:, n_flat:] + side
        minus = dot[:, n_flat:] - side
        face = np.empty((len(dot), k), np.float32)
        np.maximum(-dot[:, :n_flat], 0.0, out=face[:, :n_flat])
        np.maximum(-plus, 0.0, out=face[:, n_flat:])
        face[:, n_flat:] += np.maximum(-minus, 0.0)
        face[:, n_flat:] *= 0.5
        value = dot
        _hg_power(value[:, :n_flat], g)
        _hg_power(plus, g)
        _hg_power(minus, g)
        np.add(plus, minus, out=value[:, n_flat:])
        value[:, n_flat:] *= 0.5
        value *= w[sl, None]
        face *= wf[sl, None]
        cells, starts = np.unique(cell[sl], return_index=True)
        tally[cells] += np.add.reduceat(value, starts, axis=0)
        flux[cells] += np.add.reduceat(face, starts, axis=0)


def walk_counts(g, albedo, photons=PHOTONS, batch=BATCH):
    """The expected work of ``collide`` (the keys of LAST_WALK): exact tallies (orders 1 .. EXACT_ORDERS - 1 of
    each photon's walk, ``expected_steps`` long), photon steps (those orders, then ``weight_window``'s NEAR_STEPS
    near the lamp and the rest over m) and loop iterations (the steps over the pool's mean of 3/4 ``batch``, then
    the longest walk's tail: 3 times the mean one, or 1.5 ``weight_steps`` where absorption ends the walks)."""
    total = expected_steps(g, albedo)
    r_near, m = weight_window(g, albedo)
    early = min(total, EXACT_ORDERS)
    near = min(total - early, steps_within(r_near, g))
    per_photon = early + near + (total - early - near) / m
    steps = photons * per_photon
    return {"exact": photons * max(early - 1.0, 0.0), "steps": steps,
            "iterations": steps / (0.75 * batch) + min(MAX_WALK * exit_steps(g), 3.0 * total,
                                                        1.5 * weight_steps(albedo))}
