"""Independent reference values of the airlight integral (Sun et al. 2005, Eq. 5).

    L_a / I0 = beta / (4 pi) * int_0^{D_vp} exp(-beta (d(x) + x)) / d(x)^2 dx,
    d(x)^2 = D_sv^2 + x^2 - 2 x D_sv cos(gamma) = (x - D_sv cos gamma)^2 + (D_sv sin gamma)^2.

Nothing here uses fog_addon: the primary reference is scipy's adaptive
quadrature (QUADPACK QAGS / QAGI) of Eq. 5 in x, split at the point closest to
the light (x_c = D_sv cos gamma) and at x_c +- h * 4^k (h = D_sv sin gamma, the
half width of the 1 / d^2 peak), and at x = 2^k / beta (the e^{-beta x} decay).
Each piece is integrated to epsrel 1e-11.

The reference is itself checked by a second, different quadrature:
``eq9_quad`` integrates Sun's Eq. 9 in the angle xi (integrand
exp(-T_sv cos gamma - A1 tan xi), smooth and bounded), also with scipy quad.

Also here: ``sample_parameters`` (the test sample design), ``hemisphere_mean``
(the normaliser of Sun's Figure 6 metric) and a CLI that writes the cache
tests/data/airlight_reference.npz using all CPU cores:

    .venv/bin/python tools/airlight_reference.py [--n 40000] [--out PATH]

and, with ``--hg``, the Henyey-Greenstein cache tests/data/airlight_reference_hg.npz
(``build_hg_cache``: 16 values of g x 2 500 samples for the tables and the
quadrature, plus 2 000 samples at g = -0.95, -0.9 for the quadrature only):

    .venv/bin/python tools/airlight_reference.py --hg [--processes 2] [--out PATH]
"""
import argparse
import math
import multiprocessing as mp
import pathlib
import sys
import time
import warnings

import numpy as np
from scipy import integrate

ROOT = pathlib.Path(__file__).resolve().parents[1]
CACHE = ROOT / "tests" / "data" / "airlight_reference.npz"
CACHE_SEED = 20050731          # seed of the cached 40 000 samples
N_CACHE = 40000
N_BACKGROUND = 4000            # extra D_vp = inf samples in the cache
EPSREL = 1e-11

# Parameter ranges of the requirement (issue): optical thicknesses and beta log-uniform.
T_SV = (0.01, 20.0)
T_VP = (0.01, 50.0)
BETA = (1e-3, 1.0)


def sample_parameters(n, seed, background=False):
    """n random (beta, d_sv, d_vp, gamma): log-uniform T_sv, T_vp, beta; gamma uniform in (0, pi).

    background=True gives d_vp = inf.  Distances are D = T / beta.
    """
    rng = np.random.default_rng(seed)
    lu = lambda lo, hi: np.exp(rng.uniform(math.log(lo), math.log(hi), n))
    beta = lu(*BETA)
    t_sv = lu(*T_SV)
    t_vp = lu(*T_VP)
    gamma = rng.uniform(0.0, math.pi, n)
    gamma = np.clip(gamma, 1e-6, math.pi - 1e-6)
    d_vp = np.full(n, np.inf) if background else t_vp / beta
    # rounded to float32 so that the cache stores them exactly in half the space
    return tuple(np.asarray(v, np.float32).astype(float) for v in (beta, t_sv / beta, d_vp, gamma))


def hg_4pi(g, cos_theta):
    """4 pi times the Henyey-Greenstein phase function at scattering angle theta (1 when g = 0)."""
    return (1.0 - g * g) / (1.0 + g * g - 2.0 * g * cos_theta) ** 1.5


def _integrand(x, beta, d_sv, along, h, offset=0.0, g=0.0):
    z = x - along
    d2 = z * z + h * h
    d = math.sqrt(d2)
    # the scattering angle at x: light going from the light to x, then from x back to the viewer
    phase = hg_4pi(g, -z / d) if g else 1.0
    return phase * math.exp(-beta * (d + x - offset)) / d2


def eq5_quad(beta, d_sv, d_vp, gamma, epsrel=EPSREL, scaled=False, g=0.0):
    """Airlight per unit intensity (1/m^2) by adaptive quadrature of Eq. 5 in x; d_vp may be inf.

    ``g``: Henyey-Greenstein anisotropy; the integrand is then multiplied by 4 pi p(theta) (Sun's
    Eq. 5 with a general phase function, Sun Appendix D; Pegoraro et al. Eq. 4).

    Returns (value, estimated absolute error).  ``scaled``: both times
    e^{beta D_sv} (the integrand's exponent taken relative to beta D_sv, which
    it never falls below: d(x) + x >= D_sv), so optical depths beyond the
    float64 range (T_sv > 700) stay representable (tools/stability_map.py).
    """
    beta, d_sv, d_vp, gamma = float(beta), float(d_sv), float(d_vp), float(gamma)
    along = d_sv * math.cos(gamma)
    h = d_sv * math.sin(gamma)
    if d_vp <= 0.0:
        return 0.0, 0.0
    pts = {0.0}
    # peak of 1/d^2 at x = along, width h
    if h > 0.0:
        w = h
        while w < 1e9 * max(d_sv, 1.0):
            for p in (along - w, along + w):
                pts.add(p)
            w *= 4.0
    pts.add(along)
    # near-light scale when h is tiny: graded points on both sides at multiples of max(h, 1e-9 d_sv)
    hh = max(h, 1e-12 * d_sv)
    s = hh
    while s < 4.0 * d_sv:
        pts.add(along - s)
        pts.add(along + s)
        s *= 8.0
    # extinction scale
    if beta > 0.0:
        s = 1.0 / beta / 64.0
        while s < 2000.0 / beta:
            pts.add(s)
            pts.add(along + s)
            s *= 2.0
    far = d_vp if math.isfinite(d_vp) else None
    pts = sorted(p for p in pts if p >= 0.0 and (far is None or p < far))
    if far is not None:
        pts.append(far)
    total, err = 0.0, 0.0
    args = (beta, d_sv, along, h, d_sv if scaled else 0.0, float(g))
    for a, b in zip(pts[:-1], pts[1:]):
        if b <= a:
            continue
        v, e = integrate.quad(_integrand, a, b, args=args, epsabs=0.0, epsrel=epsrel, limit=200)
        total += v
        err += e
    if far is None:
        v, e = integrate.quad(_integrand, pts[-1], np.inf, args=args, epsabs=0.0, epsrel=epsrel, limit=200)
        total += v
        err += e
    c = beta / (4.0 * math.pi)
    return c * total, c * err


def eq9_quad(beta, d_sv, d_vp, gamma, epsrel=1e-12, g=0.0):
    """Second reference: Sun's Eq. 9 integrated in xi with scipy quad (needs 0 < gamma < pi, beta > 0).

    L_a / I0 = beta / (2 pi h) int_{gamma/2}^{v1} exp(-T_sv cos gamma - A1 tan xi) dxi,
    v1 = pi/4 + atan((T_vp - T_sv cos gamma) / A1) / 2 (pi/2 for d_vp = inf).
    ``g``: the integrand times 4 pi p_HG at the scattering angle 2 xi (Pegoraro et al. Eq. 8).
    """
    beta, d_sv, d_vp, gamma = float(beta), float(d_sv), float(d_vp), float(gamma)
    t_sv = beta * d_sv
    a1 = t_sv * math.sin(gamma)
    h = d_sv * math.sin(gamma)
    c0 = t_sv * math.cos(gamma)
    v0 = 0.5 * gamma
    v1 = 0.5 * math.pi if not math.isfinite(d_vp) else \
        0.25 * math.pi + 0.5 * math.atan2(beta * d_vp - c0, a1)
    # exponent written relative to its value at xi = gamma/2 (= -T_sv) to keep it O(1)
    t0 = math.tan(v0)
    f = lambda xi: (math.exp(-a1 * (math.tan(xi) - t0)) * (hg_4pi(g, math.cos(2.0 * xi)) if g else 1.0)
                    if xi < 0.5 * math.pi else 0.0)
    pts = [v0 + (v1 - v0) * k for k in (0.25, 0.5, 0.75)]
    v, _ = integrate.quad(f, v0, v1, epsabs=0.0, epsrel=epsrel, limit=400, points=pts)
    return beta / (2.0 * math.pi * h) * math.exp(-t_sv) * v


def hemisphere_mean(beta, d_sv, d_vp, n=64):
    """Mean airlight per unit intensity over the hemisphere of view directions facing the light (1/m^2/sr... per sr).

    H(beta, D_sv, D_vp) = (1 / 2 pi) int_{gamma < pi/2} L_a(gamma) dOmega = int_0^{pi/2} L_a(gamma) sin(gamma) dgamma,
    D_vp the same for every direction.  This is the normaliser of the Figure 6
    ("fractional error, normalizing by the total airlight over the hemisphere"),
    made per steradian so that the ratio is a fraction.  L_a sin(gamma) is
    bounded (L_a ~ 1 / gamma near the light), so n-point Gauss-Legendre in gamma
    with L_a from Eq. 9 by 96-point Gauss-Legendre in xi is accurate to ~1e-4,
    plenty for a normaliser.  Vectorised over the first three arguments.
    """
    beta, d_sv, d_vp = (np.asarray(v, float)[..., None] for v in (beta, d_sv, d_vp))
    xg, wg = np.polynomial.legendre.leggauss(n)
    gam = 0.25 * math.pi * (xg + 1.0)
    wgam = 0.25 * math.pi * wg
    t_sv = beta * d_sv
    a1 = t_sv * np.sin(gam)
    c0 = t_sv * np.cos(gam)
    v0 = 0.5 * gam
    with np.errstate(invalid="ignore"):
        v1 = np.where(np.isfinite(d_vp), 0.25 * math.pi + 0.5 * np.arctan2(beta * np.where(np.isfinite(d_vp), d_vp, 0) - c0, a1),
                      0.5 * math.pi)
    xq, wq = np.polynomial.legendre.leggauss(96)
    half = 0.5 * (v1 - v0)
    xi = v0[..., None] + half[..., None] * (xq + 1.0)
    with np.errstate(over="ignore"):
        integ = np.exp(-a1[..., None] * (np.tan(xi) - np.tan(v0)[..., None]))
    inner = np.sum(integ * wq, axis=-1) * half
    la = beta / (2 * math.pi * d_sv * np.sin(gam)) * np.exp(-t_sv) * inner
    return np.sum(la * np.sin(gam) * wgam, axis=-1)


def _quiet(fn, row):
    # QUADPACK warns about round-off when epsrel 1e-11 is below what a piece can reach;
    # the returned error estimate (checked by the caller) is what matters.
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", integrate.IntegrationWarning)
        return fn(*row)


def _work(row):
    return _quiet(lambda *r: eq5_quad(*r[:4], g=r[4]), row)


def _work_check(row):
    v, e = _work(row)
    return v, e, _quiet(lambda *r: eq9_quad(*r[:4], g=r[4]), row)


def reference_values(beta, d_sv, d_vp, gamma, processes=None, check=False, g=0.0):
    """eq5_quad over arrays (``g`` too), in parallel.  check=True also returns eq9_quad values."""
    rows = list(zip(*(np.broadcast_arrays(*(np.asarray(v, float) for v in (beta, d_sv, d_vp, gamma, g))))))
    rows = [tuple(float(x) for x in r) for r in rows]
    fn = _work_check if check else _work
    processes = processes or mp.cpu_count()
    if processes > 1 and len(rows) > 50:
        with mp.get_context("fork").Pool(processes) as pool:
            out = pool.map(fn, rows, chunksize=64)
    else:
        out = [fn(r) for r in rows]
    out = np.array(out, float).reshape(len(rows), -1)
    return out[:, 0], out[:, 1], (out[:, 2] if check else None)


def build_cache(path=CACHE, n=N_CACHE, n_bg=N_BACKGROUND, seed=CACHE_SEED, processes=None, log=print):
    t0 = time.time()
    fin = sample_parameters(n, seed)
    bg = sample_parameters(n_bg, seed + 1, background=True)
    params = [np.concatenate([a, b]) for a, b in zip(fin, bg)]
    ref, est, ref9 = reference_values(*params, processes=processes, check=True)
    hemi = hemisphere_mean(*params[:3])
    disagreement = np.abs(ref9 - ref) / ref
    log(f"{len(ref)} references in {time.time() - t0:.1f} s; Eq.5 vs Eq.9 quadrature: "
        f"max rel diff {disagreement.max():.2e}, max est. rel err {np.max(est / ref):.2e}")
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    f32 = lambda v: np.asarray(v, np.float32)
    np.savez_compressed(path, beta=f32(params[0]), d_sv=f32(params[1]), d_vp=f32(params[2]), gamma=f32(params[3]),
                        reference=ref, eq9_rel_diff=f32(disagreement), hemisphere=f32(hemi),
                        seed=seed, n_finite=n)
    return _as_float64(np.load(path))


# --- Henyey-Greenstein cache (issue 9): 40 000 samples over g in [-0.8, 0.95] + 2 000 strong back-scatter ---------

HG_CACHE = ROOT / "tests" / "data" / "airlight_reference_hg.npz"
HG_CACHE_SEED = 20050809       # seed of the Henyey-Greenstein cache; group k uses HG_CACHE_SEED + 2k (+1 background)
# 16 values over [-0.8, 0.95] (-0.8 = rungs.MIN_TABLE_ANISOTROPY, 0.95 = tables.MAX_ANISOTROPY), denser where the
# forward peak sharpens; the node tables serve all of them.
HG_TABLE_GS = (-0.8, -0.65, -0.5, -0.35, -0.2, -0.1, 0.0, 0.15, 0.3, 0.45, 0.6, 0.7, 0.8, 0.85, 0.9, 0.95)
HG_QUADRATURE_ONLY_GS = (-0.95, -0.9)   # below MIN_TABLE_ANISOTROPY: the OSL method's quadrature only
HG_PER_G = 2500                 # samples per g of HG_TABLE_GS, HG_BACKGROUND_PER_G of them background (d_vp = inf)
HG_BACKGROUND_PER_G = 250
HG_EXTRA_PER_G = 1000           # samples per g of HG_QUADRATURE_ONLY_GS, HG_EXTRA_BACKGROUND_PER_G background
HG_EXTRA_BACKGROUND_PER_G = 100


def hg_cache_parameters(seed=HG_CACHE_SEED, table_gs=HG_TABLE_GS, per_g=HG_PER_G, bg_per_g=HG_BACKGROUND_PER_G,
                        extra_gs=HG_QUADRATURE_ONLY_GS, extra_per_g=HG_EXTRA_PER_G,
                        extra_bg_per_g=HG_EXTRA_BACKGROUND_PER_G):
    """(beta, d_sv, d_vp, gamma, g) of the Henyey-Greenstein cache, grouped by g in the order table_gs + extra_gs.

    Each group: per_g - bg_per_g surface rays, then bg_per_g background rays (d_vp = inf), from
    ``sample_parameters`` (same ranges as the isotropic cache) with its own seeds, so no two groups share
    a geometry.  The first len(table_gs) * per_g samples are those the node tables serve.
    """
    groups = [(g, per_g, bg_per_g) for g in table_gs] + [(g, extra_per_g, extra_bg_per_g) for g in extra_gs]
    cols = [[] for _ in range(5)]
    for k, (g, n, n_bg) in enumerate(groups):
        fin = sample_parameters(n - n_bg, seed + 2 * k)
        bg = sample_parameters(n_bg, seed + 2 * k + 1, background=True)
        for c, a, b in zip(cols, fin, bg):
            c.append(np.concatenate([a, b]))
        cols[4].append(np.full(n, float(g)))
    return tuple(np.concatenate(c) for c in cols)


def build_hg_cache(path=HG_CACHE, seed=HG_CACHE_SEED, table_gs=HG_TABLE_GS, per_g=HG_PER_G,
                   bg_per_g=HG_BACKGROUND_PER_G, extra_gs=HG_QUADRATURE_ONLY_GS, extra_per_g=HG_EXTRA_PER_G,
                   extra_bg_per_g=HG_EXTRA_BACKGROUND_PER_G, processes=None, log=print):
    """Reference airlight with the Henyey-Greenstein phase function (Eq. 5 in x, checked by Eq. 9 in xi).

    Stores float32 inputs (beta, d_sv, d_vp, gamma; exactly what was integrated), g per sample in float64
    (the exact value of its group), the float64 reference, the Eq. 5 vs Eq. 9 relative disagreement and
    the quadrature's estimated relative error (float32), and ``n_table``: the first n_table samples have
    g in table_gs (tables and quadrature), the rest g in extra_gs (quadrature only).
    """
    t0 = time.time()
    beta, d_sv, d_vp, gamma, g = hg_cache_parameters(seed, table_gs, per_g, bg_per_g, extra_gs, extra_per_g,
                                                     extra_bg_per_g)
    ref, est, ref9 = reference_values(beta, d_sv, d_vp, gamma, processes=processes, check=True, g=g)
    disagreement = np.abs(ref9 - ref) / ref
    log(f"{len(ref)} Henyey-Greenstein references ({len(table_gs)} + {len(extra_gs)} values of g) in "
        f"{time.time() - t0:.1f} s; Eq.5 vs Eq.9 quadrature: max rel diff {disagreement.max():.2e}, "
        f"max est. rel err {np.max(est / ref):.2e}")
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    f32 = lambda v: np.asarray(v, np.float32)
    np.savez_compressed(path, beta=f32(beta), d_sv=f32(d_sv), d_vp=f32(d_vp), gamma=f32(gamma), g=g,
                        reference=ref, eq9_rel_diff=f32(disagreement), est_rel_err=f32(est / ref),
                        table_gs=np.array(table_gs, float), extra_gs=np.array(extra_gs, float),
                        per_g=per_g, background_per_g=bg_per_g, extra_per_g=extra_per_g,
                        extra_background_per_g=extra_bg_per_g, n_table=len(table_gs) * per_g, seed=seed)
    return _as_float64(np.load(path))


def load_hg_cache(path=HG_CACHE, regen=False, processes=None, log=print):
    path = pathlib.Path(path)
    if regen or not path.exists():
        return build_hg_cache(path, processes=processes, log=log)
    return _as_float64(np.load(path))


def _as_float64(npz):
    return {k: (np.asarray(v, float) if np.asarray(v).dtype == np.float32 else np.asarray(v)) for k, v in npz.items()}


def load_cache(path=CACHE, regen=False, log=print):
    path = pathlib.Path(path)
    if regen or not path.exists():
        return build_cache(path, log=log)
    return _as_float64(np.load(path))


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=N_CACHE)
    ap.add_argument("--n-background", type=int, default=N_BACKGROUND)
    ap.add_argument("--out", default=None, help=f"default {CACHE}, with --hg {HG_CACHE}")
    ap.add_argument("--hg", action="store_true",
                    help="build the Henyey-Greenstein cache (build_hg_cache) instead of the isotropic one")
    ap.add_argument("--processes", type=int, default=None, help="worker processes (default: all CPU cores)")
    a = ap.parse_args()
    if a.hg:
        a.out = a.out or str(HG_CACHE)
        build_hg_cache(a.out, processes=a.processes)
    else:
        a.out = a.out or str(CACHE)
        build_cache(a.out, a.n, a.n_background, processes=a.processes)
    print("wrote", a.out, f"{pathlib.Path(a.out).stat().st_size / 1e6:.2f} MB")
    sys.exit(0)
