"""Independent reference values of a Blender AREA light's airlight (issue 28, item 3).

A flat emitter of uniform radiance L on the rectangle [-a, a] x [-b, b] in the light's plane z = 0,
shining into z < 0, lights the fog point x with (Sun et al. 2005 Eq. 3 summed over the emitter)

    S(x) = int_A L cos(theta_e) e^{-beta |x - y|} p(cos theta_s) / |x - y|^2 dA(y),

theta_e the angle between the emitter's normal (-Z) and x - y, theta_s the scattering angle between the
light's direction x - y and the direction to the camera (-u), p Henyey-Greenstein's phase function (1 /
(4 pi) for g = 0).  The airlight per unit normal intensity I_n = L A is

    L_a / I_n = int_0^{D_vp} beta e^{-beta t} S(o + t u) / (L A) dt.

Nothing here uses fog_addon.  The inner integral is composite Gauss-Legendre over the emitter, panels graded
towards the foot of x on the emitter's plane (the integrand's peak when x is near it); the outer is scipy's
adaptive quadrature (QUADPACK) split at the ray's crossing of the emitter's plane, its closest points to the
emitter's centre and to the emitter's rectangle, and extinction scales.  A ray to the sky (d_vp = inf) stops
at 60 / beta past its last piece in front of the emitter.

    .venv/bin/python tools/area_reference.py --n 600 --out tests/data/area_reference.npz
"""
import argparse
import math
import multiprocessing as mp
import pathlib
import time

import numpy as np
from scipy import integrate

ROOT = pathlib.Path(__file__).resolve().parents[1]
CACHE = ROOT / "tests" / "data" / "area_reference.npz"
SEED = 20261127
GS = (0.0, 0.5, 0.7, 0.9)
_X, _W = np.polynomial.legendre.leggauss(12)


def _graded_nodes(lo, hi, foot, scale):
    """Gauss-Legendre nodes and weights on [lo, hi], panels graded geometrically towards ``foot`` (clamped into
    [lo, hi]) from ``scale`` (the distance to the emitter's plane) upwards."""
    foot = min(max(foot, lo), hi)
    edges = {lo, hi, foot}
    for side in (lo, hi):
        span = abs(side - foot)
        if span <= 0.0:
            continue
        k = max(1e-3 * span, min(scale, span) * 0.25)
        while k < span:
            edges.add(foot + math.copysign(k, side - foot))
            k *= 2.0
    e = np.array(sorted(edges))
    e = e[np.concatenate([[True], np.diff(e) > 1e-15])]
    a, b = e[:-1, None], e[1:, None]
    return (0.5 * (b - a) * _X + 0.5 * (a + b)).ravel(), (0.5 * (b - a) * _W).ravel()


def inscatter(x, u, a, b, beta, g):
    """S(x) / L (sr): the emitter's light scattered at the fog point x (light space) towards -u."""
    if x[2] >= 0.0:
        return 0.0
    depth = -x[2]
    xs, wx = _graded_nodes(-a, a, x[0], depth)
    ys, wy = _graded_nodes(-b, b, x[1], depth)
    dx = x[0] - xs[:, None]
    dy = x[1] - ys[None, :]
    r2 = dx * dx + dy * dy + depth * depth
    r = np.sqrt(r2)
    cos_e = depth / r
    cos_s = -(dx * u[0] + dy * u[1] + x[2] * u[2]) / r
    p = (1.0 - g * g) / (1.0 + g * g - 2.0 * g * cos_s) ** 1.5 / (4.0 * math.pi)
    return float(np.sum(wx[:, None] * wy[None, :] * cos_e * np.exp(-beta * r) * p / r2))


def reference(o, u, d_vp, a, b, beta, g):
    """L_a / I_n (1/m^2) of the ray o + t u (light space, |u| = 1) up to d_vp (inf: the sky)."""
    if abs(u[2]) > 1e-300:
        cross = -o[2] / u[2]
        lo, hi = (0.0, cross) if u[2] > 0.0 else (max(cross, 0.0), math.inf)
        if o[2] >= 0.0 and u[2] > 0.0:
            return 0.0
    else:
        if o[2] >= 0.0:
            return 0.0
        lo, hi = 0.0, math.inf
    hi = min(hi, d_vp, lo + 60.0 / beta + abs(lo) + 50.0)
    if hi <= lo:
        return 0.0
    t_c = -float(np.dot(o, u))
    foot = np.clip(o + t_c * u, [-a, -b, -np.inf], [a, b, np.inf])
    t_r = float(np.dot(foot - o, u))
    points = sorted({min(max(t, lo), hi) for t in (t_c, t_r, t_c - 1.0, t_c + 1.0, t_r - 0.3, t_r + 0.3,
                                                     *(lo + k / beta for k in (1.0, 4.0, 16.0)))} - {lo, hi})

    def f(t):
        return beta * math.exp(-beta * t) * inscatter(o + t * u, u, a, b, beta, g)

    total, edges = 0.0, [lo, *points, hi]
    for p0, p1 in zip(edges[:-1], edges[1:]):
        total += integrate.quad(f, p0, p1, limit=200, epsabs=0.0, epsrel=1e-9)[0]
    return total / (4.0 * a * b)


def sample_parameters(n, seed=SEED):
    """(n, 13) rows: beta, g, a, b, d_vp (inf for the sky), origin (3), direction (3), and 2 spare zeros.
    Cameras within 8 m of the emitter, rays aimed at points within 2 m of it (most pass its near field)."""
    rng = np.random.default_rng(seed)
    rows = []
    while len(rows) < n:
        beta = float(10.0 ** rng.uniform(-2.0, math.log10(0.5)))
        g = float(GS[len(rows) % len(GS)])
        a = float(10.0 ** rng.uniform(-1.3, 0.3))
        b = a * float(rng.uniform(0.25, 1.0))
        o = rng.uniform(-8.0, 8.0, 3)
        o[2] = rng.uniform(-8.0, 1.0)
        target = np.array([rng.uniform(-2, 2), rng.uniform(-2, 2), rng.uniform(-3.0, 0.5)])
        u = target - o
        norm = np.linalg.norm(u)
        if norm < 1e-3:
            continue
        u /= norm
        d_vp = math.inf if rng.uniform() < 0.5 else float(rng.uniform(0.5, 20.0))
        rows.append([beta, g, a, b, d_vp, *o, *u, 0.0, 0.0])
    return np.array(rows)


def _one(row):
    beta, g, a, b, d_vp, ox, oy, oz, ux, uy, uz = row[:11]
    return reference(np.array([ox, oy, oz]), np.array([ux, uy, uz]), d_vp, a, b, beta, g)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=600)
    ap.add_argument("--processes", type=int, default=2)
    ap.add_argument("--out", default=str(CACHE))
    args = ap.parse_args()
    params = sample_parameters(args.n)
    start = time.time()
    with mp.Pool(args.processes) as pool:
        values = np.array(pool.map(_one, params, chunksize=8))
    np.savez_compressed(args.out, params=params, values=values, seed=SEED)
    print(f"{len(values)} samples in {time.time() - start:.0f} s -> {args.out}")


if __name__ == "__main__":
    main()
