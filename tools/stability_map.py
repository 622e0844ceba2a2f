"""Stability map of every airlight formulation over T_sv, T_vp in [1e-4, 1e3] (and T_vp = inf), gamma in [1e-7, pi - 1e-7].

    .venv/bin/python tools/stability_map.py [--regen] [--isotropic | --anisotropic] [--processes 2]

Formulations (fog_addon/precompute/physics/point/airlight.py, tools/shader_float32.py):
  * ``sun_F64``: Sun et al.'s own F(u, v) table, 64 x 64 (as tools/figure6.py),
    Eq. 11 / 12 with two bilinear lookups (``airlight_sun``), float64;
  * ``table_f64`` / ``table_f32``: our N-table model as the node groups compute
    it (``airlight.airlight``), float64 and every intermediate in float32;
  * ``quad_f64`` / ``quad_f32``: the OSL method's in-shader quadrature
    (``airlight.airlight(..., quadrature=True)``), float64 and float32.

Grid: 25 x 25 log-spaced optical depths T_sv, T_vp from 1e-4 to 1e3 (cell
centres, the extreme corners included) plus a T_vp = inf column (the
background, Sun Eq. 12); in every cell 17 angles gamma = 1e-7, 1e-6, ..., 1e-1,
0.5, pi/2, 2.5, pi - 1e-1, ..., pi - 1e-7 and 4 extinction coefficients
beta = 1e-4, 1e-2, 1, 1e2 per metre: the model is a function of the optical
depths alone only in exact arithmetic; its constants are absolute (distances
clamped at 1 um, rays without a surface 1e15 m long) and float32 rounding
depends on the distances themselves, D = T / beta from 1 um to 10 000 km here.
Inputs are rounded to float32 first (beta, D = fl32(T / beta); gamma stays
exact, the shader's along and h are rounded from it), so both precisions see
the same numbers, and the reference is that of these numbers: its optical
depths are the exact products beta * D.

Reference: scipy adaptive quadrature of Sun Eq. 5
(tools/airlight_reference.py ``eq5_quad``) at beta = 1 and those depths,
scaled exactly, L(beta, D_sv, D_vp, gamma) = beta^2 L(1, beta D_sv, beta D_vp, gamma),
with e^{T_sv} factored out (``scaled=True``) so that values below the float64
range (T_sv > 700) are still known: ln L = 2 ln beta - T_sv + ln S.  It is
cross-checked by an independent quadrature of Sun Eq. 9 in xi written
without cancellation (``eq9_stable``; they agree to 5e-10 everywhere).
Cached in tests/data/stability_reference.npz (tests/test_stability.py reads it);
``--regen`` recomputes it (about a minute on one core).

Error of a sample with model value L_m and true value L, in a format whose
smallest normal number is ``tiny`` (float32: 1.2e-38, what a GPU flushes
denormals to; float64: 2.2e-308):

    err = |L_m - L| / max(L, tiny)

i.e. relative error while L is representable, and absolute error in units of
``tiny`` below (there 0 is the right answer).  Per cell: the maximum over its
4 x 17 samples.  Marked: NaN / Inf output (any sample; magenta, hatched);
catastrophic error, err >= 1: not one correct significant digit, what an
exponentially amplified subtraction of two close lookups gives (white x);
cells whose true values all lie below the format's range (grey, dotted).
The N-table model reads its table at the radius R = sqrt(2 Q d) about the
light clamped at model.MIN_DISTANCE = 1 um (``polar_radius``: rays passing
within 1 um of the light toward it); those samples are left out of its colour
and marked (red o) where they exceed the documented bound, because at
beta = 1e2 they fill every cell a ray passes the light in and would hide the rest.

Outputs: docs/figures/stability_map.png, benchmarks/out/stability_map.csv
(one row per formulation and cell; the near-light samples in columns of their own).
tests/test_stability.py asserts what the map shows for the shipped formulations.

Anisotropic map (issue 9; ``--anisotropic`` alone): Henyey-Greenstein g in ANISO_G = 0, 0.3, 0.7,
0.85, 0.95, on every other depth of the grid above (13 x 13 cells plus T_vp = inf), the same 17
angles and 4 extinction coefficients (12 376 samples a g), float64:
  * ``appD3_F64``: Sun et al. 2005 Appendix D (fog_addon/precompute/phase_series.py): the phase
    function as the degree-3 polynomial in cos(alpha) of HG's Legendre series (Eq. 36), with 64 x 64
    F^k(u, v) tables (Eq. 44) read as ``sun_F64`` reads F, Eq. 43 in the form of Eq. 11 / 12;
  * ``appD3`` / ``appD8``: the same with degree 3 / 8 and F^k integrated exactly (no table, no
    subtraction): the truncation of the phase series alone;
  * ``table_f64`` / ``quad_f64``: ours, ``airlight.airlight`` with the N table baked for g, and
    with ``quadrature=True``, both with that g.
Reference: ``eq5_quad(..., scaled=True, g=g)`` (Eq. 5 times 4 pi p_HG), cross-checked by ``eq9_stable``
with g (agree to 7e-10); g = 0 is read from the isotropic cache, the rest cached in
benchmarks/out/stability_map_anisotropic_reference.npz (about 50 000 values, two minutes on 2 cores;
``--regen`` recomputes it).  Outputs: docs/figures/stability_map_anisotropic.png (T_sv x T_vp cells, as
above), stability_map_anisotropic_gamma.png (max over T_vp and beta per (gamma, T_sv): where in angle a
formulation breaks), stability_map_anisotropic_summary.png (max error against g, with the phase
series' own error at alpha = 0 and pi, the limits App. D reaches), benchmarks/out/
stability_map_anisotropic.csv (per g, formulation and cell, also negative values and samples over 10 %)
and stability_map_anisotropic_summary.csv (per g and formulation).
"""
import argparse
import csv
import math
import multiprocessing as mp
import pathlib
import sys
import time
import warnings

import numpy as np
from scipy import integrate

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))   # a script run by path: the repository root

from tools import airlight_reference as ref  # noqa: E402
from tools import shader_float32 as f32  # noqa: E402
from fog_addon.precompute.physics.point import airlight as al  # noqa: E402
from fog_addon.precompute.physics.point import model  # noqa: E402
from tools.research import phase_series as ps  # noqa: E402
from fog_addon.precompute.core import tables  # noqa: E402
from fog_addon.precompute.model import rungs  # noqa: E402

CACHE = ROOT / "tests" / "data" / "stability_reference.npz"
PNG = ROOT / "docs" / "figures" / "stability_map.png"
CSV = ROOT / "benchmarks" / "out" / "stability_map.csv"

N_T = 25
T_RANGE = (1e-4, 1e3)
T_GRID = np.geomspace(*T_RANGE, N_T)                 # nominal optical depths (cell centres)
T_VP_GRID = np.concatenate([T_GRID, [np.inf]])
GAMMAS = np.array([10.0 ** -k for k in range(7, 0, -1)] + [0.5, 0.5 * math.pi, 2.5]
                  + [math.pi - 10.0 ** -k for k in range(1, 8)])
BETAS = np.asarray([1e-4, 1e-2, 1.0, 1e2], np.float32).astype(float)      # per metre, float32-exact
TINY = {"float64": np.finfo(np.float64).tiny, "float32": float(np.finfo(np.float32).tiny)}
CATASTROPHIC = 1.0
CLAMPS_R = ("table_f64", "table_f32")     # read the N table at R >= model.MIN_DISTANCE (``near_light``)

# name -> (label, format, documented bound or None)
FORMULATIONS = {
    "sun_F64": ("Sun et al. F table 64x64, Eq. 11/12 (float64)", "float64", None),
    "table_f64": ("ours: N table 128x64 (float64)", "float64", 1.6e-4),
    "table_f32": ("ours: N table 128x64, float32 as the shader", "float32", 1.6e-4),
    "quad_f64": ("ours: OSL quadrature (float64)", "float64", 1.1e-6),
    "quad_f32": ("ours: OSL quadrature, float32 as the shader", "float32", 1.1e-6),
}


# --- reference ------------------------------------------------------------------------

def eq9_stable(t_sv, t_vp, gamma, epsrel=1e-12, g=0.0):
    """Cross-check: e^{T_sv} L(beta = 1) from Sun Eq. 9, written without cancellation (D_vp may be inf).

    ``g``: Henyey-Greenstein anisotropy, the integrand times 4 pi p_HG at the scattering angle
    2 xi = gamma + 2 t (Sun Appendix D, Eq. 43; Pegoraro et al. Eq. 8).

    ``airlight_reference.eq9_quad`` integrates exp(-A1 (tan xi - tan(gamma/2)))
    over [gamma/2, v1] with both ends computed separately; near gamma = 0 with
    T_vp < T_sv, and near gamma = pi, the interval is a difference of two close
    angles and loses digits (1.7e-2 at T_sv = 1e3, T_vp = 1e-4, gamma = 1e-7).
    Here the variable is t = xi - gamma/2 on [0, W] with
    W = (atan(z1/A1) - atan(z0/A1)) / 2 = atan2(A1 T_vp, A1^2 + z0 z1) / 2
    (z0 = -T_sv cos gamma, z1 = z0 + T_vp), and
    tan(gamma/2 + t) - tan(gamma/2) = sin t / (cos(gamma/2 + t) cos(gamma/2)),
    cos(gamma/2 + t) = cos(gamma/2) cos t - sin(gamma/2) sin t.  Pieces split
    where A1 (tan xi - tan(gamma/2)) = 2^k.  Agrees with eq5_quad to 5e-10 over the map.
    """
    a1 = t_sv * math.sin(gamma)
    z0 = -t_sv * math.cos(gamma)
    c0, s0 = math.cos(0.5 * gamma), math.sin(0.5 * gamma)
    tv0 = s0 / c0
    if math.isfinite(t_vp):
        width = 0.5 * math.atan2(a1 * t_vp, a1 * a1 + z0 * (z0 + t_vp))
    else:
        width = 0.5 * (math.pi - gamma)                 # v1 = pi/2

    def f(t):
        den = (c0 * math.cos(t) - s0 * math.sin(t)) * c0
        if den <= 0.0:
            return 0.0
        v = math.exp(-a1 * math.sin(t) / den)
        return v * ref.hg_4pi(g, math.cos(gamma + 2.0 * t)) if g else v

    pts = set()
    for k in range(-6, 8):
        s = 2.0 ** k / a1                              # tan(gamma/2 + t) - tan(gamma/2) = s
        t = math.atan(s / (1.0 + tv0 * (tv0 + s)))
        if 0.0 < t < width:
            pts.add(t)
    edges = [0.0] + sorted(pts) + [width]
    v = sum(integrate.quad(f, lo, hi, epsabs=0.0, epsrel=epsrel, limit=400)[0]
            for lo, hi in zip(edges[:-1], edges[1:]) if hi > lo)
    return v / (2.0 * math.pi * a1)


def distances(t_grid=None, t_vp_grid=None):
    """(d_sv[beta, i], d_vp[beta, j]) in m: T / beta rounded to float32, so float32 and float64 get the same inputs."""
    t_grid = T_GRID if t_grid is None else t_grid
    t_vp_grid = T_VP_GRID if t_vp_grid is None else t_vp_grid
    d_sv = np.asarray(t_grid[None, :] / BETAS[:, None], np.float32).astype(float)
    d_vp = np.asarray(t_vp_grid[None, :] / BETAS[:, None], np.float32).astype(float)
    return d_sv, d_vp


def true_depths(t_grid=None, t_vp_grid=None):
    """The optical depths the samples really have, beta * D (exact in float64: products of float32 numbers)."""
    d_sv, d_vp = distances(t_grid, t_vp_grid)
    return BETAS[:, None] * d_sv, BETAS[:, None] * d_vp


def compute_reference(log=print):
    """S[b, i, j, k] = e^{T_sv} L(1, T_sv, T_vp, gamma[k]) at the true depths of beta[b], cell (i, j), by eq5_quad.

    With its estimated error and the relative difference from eq9_stable.
    """
    t_sv, t_vp = true_depths()
    shape = (len(BETAS), len(T_GRID), len(T_VP_GRID), len(GAMMAS))
    s = np.empty(shape)
    est = np.empty(shape)
    check = np.empty(shape)
    t0 = time.time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for idx in np.ndindex(*shape):
            b, i, j, k = idx
            args = (float(t_sv[b, i]), float(t_vp[b, j]), float(GAMMAS[k]))
            s[idx], est[idx] = ref.eq5_quad(1.0, *args, scaled=True)
            check[idx] = eq9_stable(*args)
    log(f"{s.size} reference values in {time.time() - t0:.1f} s")
    return s, est, check


def _same_grid(cached, grid):
    """True if a cached grid is ``grid`` up to float rounding (the grids are computed: their last bits differ
    between numpy builds, which must not recompute, and rewrite, the committed reference)."""
    cached, grid = np.asarray(cached), np.asarray(grid)
    return cached.shape == grid.shape and np.allclose(cached, grid, rtol=1e-12, atol=0.0)


def load_reference(regen=False, log=print):
    """The cached reference (computed and written when missing, stale or ``regen``)."""
    if not regen and CACHE.exists():
        c = dict(np.load(CACHE))
        if (_same_grid(c["t_sv"], T_GRID) and _same_grid(c["t_vp"], T_VP_GRID)
                and _same_grid(c["gamma"], GAMMAS) and _same_grid(c["beta"], BETAS)):
            return c
        log(f"{CACHE} is for another grid: recomputing")
    s, est, check = compute_reference(log)
    CACHE.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(CACHE, beta=BETAS, t_sv=T_GRID, t_vp=T_VP_GRID, gamma=GAMMAS, scaled=s,
                        est_rel=(est / s).astype(np.float32),
                        check_rel=np.abs(check / s - 1.0).astype(np.float32))
    return dict(np.load(CACHE))


def samples(t_grid=None, t_vp_grid=None):
    """(beta, d_sv, d_vp, gamma) of every sample, each of shape (beta, T_sv, T_vp, gamma)."""
    d_sv, d_vp = distances(t_grid, t_vp_grid)
    return tuple(np.broadcast_arrays(BETAS[:, None, None, None], d_sv[:, :, None, None],
                                     d_vp[:, None, :, None], GAMMAS[None, None, None, :]))


def log_truth(c, t_grid=None, t_vp_grid=None):
    """ln L of every sample (shape of ``samples``): 2 ln beta - T_sv + ln S."""
    t_sv, _ = true_depths(t_grid, t_vp_grid)
    return 2.0 * np.log(BETAS)[:, None, None, None] - t_sv[:, :, None, None] + np.log(c["scaled"])


def rel_error(value, ln_truth, tiny):
    """|L_m - L| / max(L, tiny) from L_m and ln L (nan where L_m is not finite)."""
    value = np.asarray(value, float)
    with np.errstate(all="ignore"):
        above = ln_truth >= math.log(tiny)
        rel = np.abs(value * np.exp(-np.where(above, ln_truth, 0.0)) - 1.0)
        absolute = np.abs(value - np.exp(np.minimum(ln_truth, 0.0))) / tiny
        err = np.where(above, rel, absolute)
    return np.where(np.isfinite(value), err, np.nan)


# --- formulations ---------------------------------------------------------------------

def evaluate(name, params, table=None, sun_table=None):
    """The formulation's values at ``params`` (arrays of any shape), float64 array of that shape."""
    shape = np.shape(params[0])
    flat = [np.ravel(p) for p in params]
    with np.errstate(all="ignore"):
        if name == "sun_F64":
            out = al.airlight_sun(*flat, al.bake_sun_f_table(64, 64) if sun_table is None else sun_table)
        elif name == "table_f64":
            out = al.airlight(*flat, table=table)
        elif name == "table_f32":
            out = f32.airlight_float32(*flat, al.bake_airlight_table() if table is None else table)
        elif name == "quad_f64":
            out = al.airlight(*flat, quadrature=True)
        elif name == "quad_f32":
            out = f32.airlight_quadrature_float32(*flat)
        else:
            raise KeyError(name)
    return np.asarray(out, float).reshape(shape)


def run(regen=False, log=print):
    c = load_reference(regen, log)
    log(f"reference: eq5 estimated rel. error max {c['est_rel'].max():.1e}; max rel. diff from Eq. 9 "
        f"(eq9_stable) {c['check_rel'].max():.1e}")
    params = samples()
    ln_l = log_truth(c)
    table = al.bake_airlight_table()
    sun_table = al.bake_sun_f_table(64, 64)
    results = {}
    for name, (label, fmt, bound) in FORMULATIONS.items():
        t0 = time.time()
        val = evaluate(name, params, table, sun_table)
        err = rel_error(val, ln_l, TINY[fmt])
        results[name] = dict(value=val, err=err, seconds=time.time() - t0)
        log(summary(name, err, ln_l, TINY[fmt], params))
    return c, params, ln_l, results


def polar_radius(d_sv, d_vp, gamma):
    """min(R0, R1): the radius R = sqrt(2 Q d) about the light at which the N table is read, at the viewer
    and at the surface (model.py; R ~ h on the way toward the light, ~ 2 d beyond it).  The table
    model clamps it at model.MIN_DISTANCE (1 um): rays that pass within 1 um of the light toward
    it, or end within 0.5 um of it."""
    r0 = 2.0 * d_sv * np.sin(0.5 * gamma)
    h = d_sv * np.sin(gamma)
    with np.errstate(all="ignore"):
        z1 = d_vp - d_sv * np.cos(gamma)
        d_sp = np.hypot(z1, h)
        q1 = np.where(z1 > 0, z1 + d_sp, h * h / (d_sp - z1))
        r1 = np.where(np.isfinite(d_vp), np.sqrt(2.0 * q1 * d_sp), np.inf)
    return np.minimum(r0, r1)


def near_light(params):
    """Samples whose ray the table model clamps at R = 1 um (``polar_radius``)."""
    _, d_sv, d_vp, gamma = params
    return polar_radius(d_sv, d_vp, gamma) < model.MIN_DISTANCE


def _per_cell(x):
    """(beta, T_sv, T_vp, gamma) -> (T_sv, T_vp, beta * gamma)."""
    return np.moveaxis(x, 0, 2).reshape(x.shape[1], x.shape[2], -1)


def cell_stats(err, ln_l, tiny, excluded=None):
    """Per (T_sv, T_vp) cell: max finite error over the samples not ``excluded``, its (beta, gamma) index,
    counts, and the max over the excluded samples."""
    e = _per_cell(err)
    ex = np.zeros(e.shape, bool) if excluded is None else _per_cell(excluded)
    nonfinite = np.isnan(e).sum(-1)
    finite_e = np.where(np.isnan(e), -np.inf, e)
    kept = np.where(ex, -np.inf, finite_e)
    worst = np.argmax(kept, axis=-1)
    mx = np.take_along_axis(kept, worst[..., None], -1)[..., 0]
    ex_max = np.max(np.where(ex, finite_e, -np.inf), axis=-1)
    under = _per_cell(ln_l) < math.log(tiny)
    return dict(max=np.where(np.isfinite(mx), mx, np.nan), worst=worst, nonfinite=nonfinite,
                catastrophic=(np.where(ex, 0.0, finite_e) >= CATASTROPHIC).sum(-1), underflow=under.sum(-1),
                all_underflow=under.all(-1), excluded=ex.sum(-1), excluded_max=np.where(ex.any(-1), ex_max, np.nan))


def stats_of(name, results, params, ln_l):
    fmt = FORMULATIONS[name][1]
    return cell_stats(results[name]["err"], ln_l, TINY[fmt], near_light(params) if name in CLAMPS_R else None)


def summary(name, err, ln_l, tiny, params):
    fin = np.isfinite(err)
    rep = fin & (ln_l >= math.log(tiny))
    out = f"{name:10s} NaN/Inf {int((~fin).sum()):5d}, err >= 1 {int((err >= CATASTROPHIC).sum()):5d} of {err.size}"
    masks = [("", rep)]
    if name in CLAMPS_R:
        nl = near_light(params)
        masks = [("; rays within 1 um of the light", rep & nl), ("; elsewhere", rep & ~nl)]
    for label, m in masks:
        e = np.where(m, err, -1.0)
        i = np.unravel_index(int(np.argmax(e)), e.shape)
        b, s, v, g = (float(p[i]) for p in params)
        out += (f"{label}: max err where representable {e[i]:.3g} at beta={b:.3g} T_sv={b * s:.3g} "
                f"T_vp={b * v:.3g} gamma={g:.3g}")
    return out


def write_csv(results, params, ln_l, path=CSV):
    path.parent.mkdir(parents=True, exist_ok=True)
    nb, ng = len(BETAS), len(GAMMAS)
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["formulation", "format", "T_sv", "T_vp", "max_err", "worst_beta", "worst_gamma",
                    "samples", "nonfinite", "catastrophic", "true_value_underflows",
                    "near_light_samples_left_out", "near_light_max_err"])
        for name in results:
            st = stats_of(name, results, params, ln_l)
            for i, t_sv in enumerate(T_GRID):
                for j, t_vp in enumerate(T_VP_GRID):
                    k = int(st["worst"][i, j])
                    w.writerow([name, FORMULATIONS[name][1], f"{t_sv:.6g}", "inf" if np.isinf(t_vp) else f"{t_vp:.6g}",
                                f"{st['max'][i, j]:.3e}", f"{BETAS[k // ng]:.6g}", f"{GAMMAS[k % ng]:.17g}",
                                nb * ng, int(st["nonfinite"][i, j]), int(st["catastrophic"][i, j]),
                                int(st["underflow"][i, j]), int(st["excluded"][i, j]),
                                f"{st['excluded_max'][i, j]:.3e}"])


def plot(c, results, params, ln_l, path=PNG):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    vmin = VMIN
    fig, axes = plt.subplots(2, 3, figsize=(17, 12.5), dpi=80)
    fig.subplots_adjust(left=0.05, right=0.88, bottom=0.1, top=0.88, wspace=0.28, hspace=0.42)
    im = None
    for ax, name in zip(axes.ravel(), list(FORMULATIONS) + ["reference"]):
        st = None
        if name == "reference":
            val = np.log10(np.maximum(np.max(np.maximum(c["check_rel"], c["est_rel"]), axis=(0, -1)), 1e-17))
            title = ("reference: scipy quadrature of Sun Eq. 5\nvs an independent quadrature of Eq. 9 "
                     f"(max {c['check_rel'].max():.1g})\nand its own error estimate (max {c['est_rel'].max():.1g})")
        else:
            label, fmt, bound = FORMULATIONS[name]
            st = stats_of(name, results, params, ln_l)
            val = np.log10(np.clip(st["max"], 10.0 ** vmin, None))
            err = results[name]["err"]
            fin = np.isfinite(err)
            rep = fin & (ln_l >= math.log(TINY[fmt]))
            keep = rep & ~near_light(params) if name in CLAMPS_R else rep
            title = (f"{label}\nmax {np.max(np.where(keep, err, 0.0)):.2g}"
                     + (" (R >= 1 um)" if name in CLAMPS_R else "")
                     + (f", documented {bound:g}" if bound else ""))
            if name in CLAMPS_R:
                title += f"; R < 1 um: max {np.max(np.where(rep & ~keep, err, 0.0)):.2g}"
            title += (f"\nNaN/Inf: {int((~fin).sum())}, error >= 1: {int((np.where(keep, err, 0) >= 1).sum())} "
                      f"of {fin.size} samples")
        im = _panel(ax, val, st, FORMULATIONS[name][2] if st is not None else None, title, T_GRID)
    cb = fig.colorbar(im, cax=fig.add_axes([0.9, 0.25, 0.015, 0.5]))
    cb.set_label("log10 of the max error per cell, |L - L_ref| / max(L_ref, smallest normal number)")
    fig.legend(handles=_legend_handles(), loc="lower center", ncol=2, fontsize=10, frameon=False,
               bbox_to_anchor=(0.47, 0.0))
    fig.suptitle(f"Airlight stability map: per cell the max error over {len(GAMMAS)} angles gamma in [1e-7, pi - 1e-7]"
                 f" and beta in {{1e-4, 1e-2, 1, 1e2}} /m\nreference: scipy quadrature of Sun Eq. 5 "
                 f"(tools/stability_map.py)", fontsize=13)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, bbox_inches="tight")


VMIN, VMAX = -16.0, 2.0
GAP = 0.45                                                        # the T_vp = inf row sits above a gap


def _legend_handles():
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch
    return [Patch(facecolor="magenta", edgecolor="k", hatch="xxx", label="NaN or Inf output"),
            Line2D([], [], marker="x", color="k", ls="", label="catastrophic: error >= 1 (not one correct digit)"),
            Patch(facecolor="0.85", edgecolor="0.6", hatch="..", label="true values below the format's range"),
            Line2D([], [], marker="o", mfc="none", mec="red", ls="",
                   label="N table: rays within 1 um of the light (R clamped), over the bound; left out of the colour")]


def _panel(ax, val, st, bound, title, t_grid):
    """One heat map: log10 error ``val`` per (T_sv, T_vp) cell of ``t_grid`` (plus the T_vp = inf row), the
    markers of ``cell_stats`` ``st`` (None: colour only) and ``bound`` (documented, for the red circles)."""
    import matplotlib.pyplot as plt
    from matplotlib.patches import Rectangle

    nx, ny = len(t_grid), len(t_grid) + 1
    gap = GAP
    yedges = np.concatenate([np.arange(ny) - 0.5, [ny - 0.5 + gap]])
    yedges[-2] += gap
    decades = range(-4, 4)
    lo, hi = math.log10(t_grid[0]), math.log10(t_grid[-1])
    pos = lambda t: (math.log10(t) - lo) / (hi - lo) * (nx - 1)
    ms = 4.5 if nx >= 20 else 6.0
    im = ax.pcolormesh(np.arange(nx + 1) - 0.5, yedges, np.ma.masked_invalid(val.T), cmap=plt.get_cmap("viridis"),
                       vmin=VMIN, vmax=VMAX, shading="flat")
    ax.axhspan(ny - 1.5, ny - 1.5 + gap, color="white", zorder=2)
    if st is not None:
        for i in range(nx):
            for j in range(ny):
                y0, y1 = yedges[j], (ny - 1.5 if j == ny - 2 else yedges[j + 1])
                if st["nonfinite"][i, j]:
                    ax.add_patch(Rectangle((i - 0.5, y0), 1, y1 - y0, facecolor="magenta", edgecolor="k",
                                           hatch="xxx", lw=0.3, zorder=3))
                elif st["all_underflow"][i, j]:
                    ax.add_patch(Rectangle((i - 0.5, y0), 1, y1 - y0, facecolor="0.85", edgecolor="0.6",
                                           hatch="..", lw=0.0, zorder=3))
                elif st["catastrophic"][i, j]:
                    ax.plot(i, 0.5 * (y0 + y1), marker="x", color="white", ms=ms, mew=1.2, zorder=4)
                if bound and st["excluded_max"][i, j] > bound:
                    ax.plot(i, 0.5 * (y0 + y1), marker="o", mfc="none", mec="red", ms=0.8 * ms, mew=0.9, zorder=5)
    ax.set_xticks([pos(10.0 ** d) for d in decades])
    ax.set_xticklabels([f"1e{d}" for d in decades], fontsize=8)
    ax.set_yticks([pos(10.0 ** d) for d in decades] + [ny - 1 + 0.5 * gap])
    ax.set_yticklabels([f"1e{d}" for d in decades] + ["inf"], fontsize=8)
    ax.set_xlim(-0.5, nx - 0.5)
    ax.set_ylim(-0.5, yedges[-1])
    ax.set_xlabel("T_sv = beta D_sv (viewer - light)", fontsize=9)
    ax.set_ylabel("T_vp = beta D_vp (viewer - surface)", fontsize=9)
    ax.set_title(title, fontsize=9)
    return im

# --- anisotropic map (issue 9): Sun's Appendix D against ours, Henyey-Greenstein g -------------------

ANISO_G = (0.0, 0.3, 0.7, 0.85, 0.95)
ANISO_T_GRID = T_GRID[::2]                           # 13 depths: every other cell of the isotropic map
ANISO_T_VP_GRID = np.concatenate([ANISO_T_GRID, [np.inf]])
_ANISO_VP_INDEX = list(range(0, N_T, 2)) + [N_T]     # where they sit in T_VP_GRID (g = 0 reuses CACHE)
ANISO_CACHE = ROOT / "benchmarks" / "out" / "stability_map_anisotropic_reference.npz"
# the committed copy of that cache, read when benchmarks/out (not tracked) has none
ANISO_CACHE_COMMITTED = ROOT / "docs" / "measurements" / "data" / ANISO_CACHE.name
ANISO_PNG = ROOT / "docs" / "figures" / "stability_map_anisotropic.png"
ANISO_CSV = ROOT / "benchmarks" / "out" / "stability_map_anisotropic.csv"
ANISO_GAMMA_PNG = ROOT / "docs" / "figures" / "stability_map_anisotropic_gamma.png"
ANISO_SUMMARY_PNG = ROOT / "docs" / "figures" / "stability_map_anisotropic_summary.png"
ANISO_SUMMARY_CSV = ROOT / "benchmarks" / "out" / "stability_map_anisotropic_summary.csv"
APPENDIX_D_TABLE = (64, 64)                          # F^k tables as Sun's F (sun_F64)
BREAKS = 0.1                                         # "off by more than 10 %"

# name -> (label, format, documented bound or None)
ANISO_FORMULATIONS = {
    "appD3_F64": ("Sun App. D, n = 3, F^k tables 64x64 (Eq. 43/44)", "float64", None),
    "appD3": ("Sun App. D, n = 3, F^k exact (truncation only)", "float64", None),
    "appD8": ("Sun App. D, n = 8, F^k exact (truncation only)", "float64", None),
    "table_f64": ("ours: N table of g (float64)", "float64", rungs.HG_TABLE_ERROR),
    "quad_f64": ("ours: OSL quadrature with g (float64)", "float64", rungs.HG_QUADRATURE_ERROR),
}


def _aniso_reference_row(row):
    t_sv, t_vp, gamma, g = row
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        v, e = ref.eq5_quad(1.0, t_sv, t_vp, gamma, scaled=True, g=g)
        return v, e, eq9_stable(t_sv, t_vp, gamma, g=g)


def compute_aniso_reference(g_values, processes=2, log=print):
    """S[g, b, i, j, k] = e^{T_sv} L(1, T_sv, T_vp, gamma[k]; g) on the anisotropic grid by eq5_quad(..., g=g),
    with its estimated error and the value of eq9_stable(..., g=g); g = 0 is read from CACHE."""
    t_sv, t_vp = true_depths(ANISO_T_GRID, ANISO_T_VP_GRID)
    shape = (len(BETAS), len(ANISO_T_GRID), len(ANISO_T_VP_GRID), len(GAMMAS))
    rows = [(float(t_sv[b, i]), float(t_vp[b, j]), float(GAMMAS[k]), float(g))
            for g in g_values for b, i, j, k in np.ndindex(*shape)]
    t0 = time.time()
    if processes > 1:
        with mp.get_context("fork").Pool(processes) as pool:
            out = pool.map(_aniso_reference_row, rows, chunksize=256)
    else:
        out = [_aniso_reference_row(r) for r in rows]
    out = np.asarray(out, float).reshape((len(g_values),) + shape + (3,))
    log(f"{len(rows)} anisotropic reference values in {time.time() - t0:.1f} s ({processes} processes)")
    return out[..., 0], out[..., 1], out[..., 2]


def load_aniso_reference(regen=False, processes=2, log=print):
    """dict g -> {"scaled", "est_rel", "check_rel"} on the anisotropic grid (ANISO_CACHE; computed when missing,
    stale or ``regen``, about two minutes on 2 cores); g = 0 from the isotropic CACHE."""
    gs = [g for g in ANISO_G if g]
    c = None
    cached = ANISO_CACHE if ANISO_CACHE.exists() else ANISO_CACHE_COMMITTED
    if not regen and cached.exists():
        c = dict(np.load(cached))
        if not (_same_grid(c["g"], gs) and _same_grid(c["t_sv"], ANISO_T_GRID)
                and _same_grid(c["t_vp"], ANISO_T_VP_GRID) and _same_grid(c["gamma"], GAMMAS)
                and _same_grid(c["beta"], BETAS)):
            log(f"{cached} is for another grid: recomputing")
            c = None
    if c is None:
        s, est, check = compute_aniso_reference(gs, processes, log)
        ANISO_CACHE.parent.mkdir(parents=True, exist_ok=True)
        np.savez_compressed(ANISO_CACHE, g=np.asarray(gs), beta=BETAS, t_sv=ANISO_T_GRID, t_vp=ANISO_T_VP_GRID,
                            gamma=GAMMAS, scaled=s, est_rel=(est / s).astype(np.float32),
                            check_rel=np.abs(check / s - 1.0).astype(np.float32))
        c = dict(np.load(ANISO_CACHE))
    out = {g: dict(scaled=c["scaled"][n], est_rel=c["est_rel"][n], check_rel=c["check_rel"][n])
           for n, g in enumerate(gs)}
    if 0.0 in ANISO_G:
        iso = load_reference(False, log)
        sub = lambda x: x[:, ::2][:, :, _ANISO_VP_INDEX]
        out[0.0] = dict(scaled=sub(iso["scaled"]), est_rel=sub(iso["est_rel"]), check_rel=sub(iso["check_rel"]))
    return out


def evaluate_aniso(name, params, g, table=None, fk_tables=None):
    """Formulation ``name`` of ANISO_FORMULATIONS at anisotropy g (``table``: the N table baked for g)."""
    shape = np.shape(params[0])
    flat = [np.ravel(p) for p in params]
    with np.errstate(all="ignore"):
        if name == "appD3_F64":
            out = ps.airlight_sun_appendix_d(*flat, g, 3, fk_tables)
        elif name == "appD3":
            out = ps.airlight_appendix_d_exact(*flat, g, 3)
        elif name == "appD8":
            out = ps.airlight_appendix_d_exact(*flat, g, 8)
        elif name == "table_f64":
            out = al.airlight(*flat, table=table, g=g)
        elif name == "quad_f64":
            out = al.airlight(*flat, quadrature=True, g=g)
        else:
            raise KeyError(name)
    return np.asarray(out, float).reshape(shape)


def run_aniso(regen=False, processes=2, log=print):
    refs = load_aniso_reference(regen, processes, log)
    params = samples(ANISO_T_GRID, ANISO_T_VP_GRID)
    fk_tables = ps.bake_sun_f_k_tables(8, *APPENDIX_D_TABLE)
    results = {}
    for g in ANISO_G:
        c = refs[g]
        log(f"g = {g}: reference eq5 estimated rel. error max {c['est_rel'].max():.1e}; max rel. diff from "
            f"eq9_stable {c['check_rel'].max():.1e}")
        ln_l = log_truth(c, ANISO_T_GRID, ANISO_T_VP_GRID)
        t0 = time.time()
        table = al.bake_airlight_table(tables.anisotropic(tables.AIRLIGHT, g))
        log(f"g = {g}: N table baked in {time.time() - t0:.1f} s")
        for name, (label, fmt, bound) in ANISO_FORMULATIONS.items():
            t0 = time.time()
            val = evaluate_aniso(name, params, g, table, fk_tables)
            err = rel_error(val, ln_l, TINY[fmt])
            results[g, name] = dict(value=val, err=err, ln_l=ln_l, seconds=time.time() - t0)
            over = (np.nan_to_num(err, nan=np.inf) > BREAKS) & ~(near_light(params) if name in CLAMPS_R else False)
            log(f"g = {g:<5}" + summary(name, err, ln_l, TINY[fmt], params)
                + f"; > {BREAKS:g}{' (R >= 1 um)' if name in CLAMPS_R else ''}: {int(over.sum())}, "
                f"negative: {int((val < 0).sum())}")
    return refs, params, results


def aniso_stats(name, r, params):
    return cell_stats(r["err"], r["ln_l"], TINY[ANISO_FORMULATIONS[name][1]],
                      near_light(params) if name in CLAMPS_R else None)


def write_aniso_csv(results, params, path=ANISO_CSV):
    path.parent.mkdir(parents=True, exist_ok=True)
    nb, ng = len(BETAS), len(GAMMAS)
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["g", "formulation", "format", "T_sv", "T_vp", "max_err", "worst_beta", "worst_gamma",
                    "samples", "nonfinite", "catastrophic", "negative", "over_10_percent", "true_value_underflows",
                    "near_light_samples_left_out", "near_light_max_err"])
        for (g, name), r in results.items():
            st = aniso_stats(name, r, params)
            neg = _per_cell(r["value"] < 0).sum(-1)
            over = _per_cell(np.nan_to_num(r["err"], nan=np.inf) > BREAKS).sum(-1)
            for i, t_sv in enumerate(ANISO_T_GRID):
                for j, t_vp in enumerate(ANISO_T_VP_GRID):
                    k = int(st["worst"][i, j])
                    w.writerow([f"{g:g}", name, ANISO_FORMULATIONS[name][1], f"{t_sv:.6g}",
                                "inf" if np.isinf(t_vp) else f"{t_vp:.6g}", f"{st['max'][i, j]:.3e}",
                                f"{BETAS[k // ng]:.6g}", f"{GAMMAS[k % ng]:.17g}", nb * ng,
                                int(st["nonfinite"][i, j]), int(st["catastrophic"][i, j]), int(neg[i, j]),
                                int(over[i, j]), int(st["underflow"][i, j]), int(st["excluded"][i, j]),
                                f"{st['excluded_max'][i, j]:.3e}"])


def plot_aniso(refs, results, params, path=ANISO_PNG):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(ANISO_FORMULATIONS)
    fig, axes = plt.subplots(len(ANISO_G), len(names), figsize=(4.1 * len(names), 4.3 * len(ANISO_G)), dpi=64)
    fig.subplots_adjust(left=0.04, right=0.9, bottom=0.06, top=0.92, wspace=0.32, hspace=0.62)
    im = None
    for row, g in zip(axes, ANISO_G):
        for ax, name in zip(row, names):
            label, fmt, bound = ANISO_FORMULATIONS[name]
            r = results[g, name]
            st = aniso_stats(name, r, params)
            err = r["err"]
            fin = np.isfinite(err)
            rep = fin & (r["ln_l"] >= math.log(TINY[fmt]))
            keep = rep & ~near_light(params) if name in CLAMPS_R else rep
            title = (f"g = {g:g}\n{label}\nmax {np.max(np.where(keep, err, 0.0)):.2g}"
                     + (" (R >= 1 um)" if name in CLAMPS_R else "")
                     + (f", documented {bound:g}" if bound else "")
                     + f"\n> 10 %: {int((np.where(keep, err, 0) > BREAKS).sum())}, error >= 1: "
                     f"{int((np.where(keep, err, 0) >= 1).sum())} of {err.size}\nnegative: "
                     f"{int((r['value'] < 0).sum())}, NaN/Inf: {int((~fin).sum())}")
            val = np.log10(np.clip(st["max"], 10.0 ** VMIN, None))
            im = _panel(ax, val, st, bound, title, ANISO_T_GRID)
            ax.title.set_fontsize(8.5)
    cb = fig.colorbar(im, cax=fig.add_axes([0.92, 0.3, 0.012, 0.4]))
    cb.set_label("log10 of the max error per cell, |L - L_ref| / max(L_ref, smallest normal number)")
    fig.legend(handles=_legend_handles(), loc="lower center", ncol=2, fontsize=11, frameon=False,
               bbox_to_anchor=(0.47, 0.0))
    est = max(float(c["est_rel"].max()) for c in refs.values())
    chk = max(float(c["check_rel"].max()) for c in refs.values())
    fig.suptitle("Anisotropic airlight (Henyey-Greenstein g) stability map: Sun et al. 2005 Appendix D (phase function "
                 "as a degree-n polynomial in cos alpha, Eq. 36-44) against ours\n"
                 f"per cell the max error over {len(GAMMAS)} angles gamma in [1e-7, pi - 1e-7] and beta in "
                 f"{{1e-4, 1e-2, 1, 1e2}} /m, {len(ANISO_T_GRID)} x {len(ANISO_T_VP_GRID)} cells; reference: scipy "
                 f"quadrature of Eq. 5 times 4 pi p_HG (vs Eq. 9: {chk:.1g}, own estimate {est:.1g}) "
                 "(tools/stability_map.py --anisotropic)", fontsize=14)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, bbox_inches="tight")


def _kept_err(name, r, params):
    """Errors of the samples a formulation is judged on (finite, true value representable, R >= 1 um for
    the N table), -1 elsewhere; NaN/Inf counted as inf."""
    fmt = ANISO_FORMULATIONS[name][1]
    err = np.nan_to_num(r["err"], nan=np.inf)
    keep = r["ln_l"] >= math.log(TINY[fmt])
    if name in CLAMPS_R:
        keep &= ~near_light(params)
    return np.where(keep, err, -1.0)


def phase_truncation_error(g, n):
    """(backward, forward): k_n(cos alpha) / (4 pi p_HG) - 1 at alpha = pi and 0, the limits App. D's airlight
    reaches looking away from the light (gamma -> pi) and toward it through thin fog (gamma, T -> 0)."""
    w = ps.hg_power_coefficients(g, n)
    mu = np.array([-1.0, 1.0])
    return tuple(ps.phase_polynomial(w, mu) / ps.hg_4pi(g, mu) - 1.0)


def aniso_summary_rows(results, params):
    """One row per (g, formulation): max error, samples over BREAKS, negative values, NaN/Inf, and where the
    formulation is over BREAKS: the gamma and T_sv ranges of those samples."""
    rows = []
    t_sv = params[0] * params[1]
    for (g, name), r in results.items():
        e = _kept_err(name, r, params)
        bad = e > BREAKS
        row = dict(g=g, formulation=name, max_err=float(e.max()), samples=int((e >= 0).sum()),
                   over_10_percent=int(bad.sum()), negative=int((r["value"] < 0).sum()),
                   nonfinite=int((~np.isfinite(r["value"])).sum()),
                   gamma_over=(float(params[3][bad].min()), float(params[3][bad].max())) if bad.any() else None,
                   t_sv_over=(float(t_sv[bad].min()), float(t_sv[bad].max())) if bad.any() else None)
        if name.startswith("appD"):
            row["phase_backward"], row["phase_forward"] = phase_truncation_error(g, 8 if name == "appD8" else 3)
        rows.append(row)
    return rows


def write_aniso_summary_csv(rows, path=ANISO_SUMMARY_CSV):
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["g", "formulation", "max_err", "samples", "over_10_percent", "negative", "nonfinite",
                    "gamma_min_over_10_percent", "gamma_max_over_10_percent", "T_sv_min_over_10_percent",
                    "T_sv_max_over_10_percent", "phase_series_error_backward", "phase_series_error_forward"])
        for r in rows:
            go, to = r["gamma_over"] or ("", ""), r["t_sv_over"] or ("", "")
            w.writerow([f"{r['g']:g}", r["formulation"], f"{r['max_err']:.3e}", r["samples"], r["over_10_percent"],
                        r["negative"], r["nonfinite"]] + [f"{x:.6g}" if x != "" else "" for x in go + to]
                       + [f"{r[k]:+.4g}" if k in r else "" for k in ("phase_backward", "phase_forward")])


def plot_aniso_gamma(results, params, path=ANISO_GAMMA_PNG):
    """Per g and formulation: log10 max error over T_vp and beta per (gamma, T_sv): where in angle it breaks."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(ANISO_FORMULATIONS)
    ng, nt = len(GAMMAS), len(ANISO_T_GRID)
    glabels = ["1e-7", "", "1e-5", "", "1e-3", "", "0.1", "0.5", "pi/2", "2.5", "pi-.1", "", "pi-1e-3", "",
               "pi-1e-5", "", "pi-1e-7"]
    fig, axes = plt.subplots(len(ANISO_G), len(names), figsize=(4.1 * len(names), 3.9 * len(ANISO_G)), dpi=64)
    fig.subplots_adjust(left=0.05, right=0.9, bottom=0.05, top=0.92, wspace=0.3, hspace=0.6)
    im = None
    for row, g in zip(axes, ANISO_G):
        for ax, name in zip(row, names):
            e = _kept_err(name, results[g, name], params)
            m = e.max(axis=(0, 2))                                   # (T_sv, gamma)
            val = np.log10(np.clip(np.where(m < 0, np.nan, m), 10.0 ** VMIN, 10.0 ** VMAX))
            im = ax.pcolormesh(np.arange(ng + 1) - 0.5, np.arange(nt + 1) - 0.5, np.ma.masked_invalid(val),
                               cmap=plt.get_cmap("viridis"), vmin=VMIN, vmax=VMAX, shading="flat")
            over = m > BREAKS
            yy, xx = np.nonzero(over)
            ax.plot(xx, yy, ls="", marker="x", color="white", ms=4.0, mew=1.0)
            ax.set_xticks(range(ng))
            ax.set_xticklabels(glabels, rotation=90, fontsize=7)
            ax.set_yticks(range(0, nt, 2))
            ax.set_yticklabels([f"{t:.0e}" for t in ANISO_T_GRID[::2]], fontsize=7)
            ax.set_xlabel("gamma (angle between the view ray and the light)", fontsize=8)
            ax.set_ylabel("T_sv", fontsize=8)
            ax.set_title(f"g = {g:g}\n{ANISO_FORMULATIONS[name][0]}\nmax {e.max():.2g}; > 10 % in "
                         f"{int(over.sum())} of {over.size} (gamma, T_sv) cells", fontsize=8.5)
    cb = fig.colorbar(im, cax=fig.add_axes([0.92, 0.3, 0.012, 0.4]))
    cb.set_label("log10 of the max error over T_vp (and inf) and beta, per (gamma, T_sv); x: over 10 %")
    fig.suptitle("Anisotropic airlight by angle: Sun et al. 2005 Appendix D (degree-n polynomial phase function) "
                 "against ours\nmax error over T_vp in [1e-4, 1e3] and inf and beta in {1e-4, 1e-2, 1, 1e2} /m "
                 "(N table: rays within 1 um of the light left out) (tools/stability_map.py --anisotropic)",
                 fontsize=14)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, bbox_inches="tight")


def plot_aniso_summary(rows, path=ANISO_SUMMARY_PNG):
    """Max error over the domain against g, each formulation, with App. D's phase-series limits as curves."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(9, 6.5), dpi=80)
    CLIP = 5e2
    styles = {"appD3_F64": ("tab:red", "s"), "appD3": ("tab:orange", "o"), "appD8": ("tab:purple", "D"),
              "table_f64": ("tab:green", "^"), "quad_f64": ("tab:blue", "v")}
    for name, (label, _, bound) in ANISO_FORMULATIONS.items():
        rr = [r for r in rows if r["formulation"] == name]
        col, mk = styles[name]
        ys = [min(max(r["max_err"], 1e-16), CLIP) for r in rr]
        clipped = any(r["max_err"] > CLIP for r in rr)
        ax.plot([r["g"] for r in rr], ys, color=col, marker=mk,
                label=label + (f" (clipped at {CLIP:g}: {max(r['max_err'] for r in rr):.1g})" if clipped else ""))
        if bound:
            ax.axhline(bound, color=col, ls=":", lw=1)
    gg = np.linspace(0.0, 0.95, 96)
    for n, col in ((3, "tab:orange"), (8, "tab:purple")):
        back = np.array([abs(phase_truncation_error(g, n)[0]) for g in gg])
        fwd = np.array([abs(phase_truncation_error(g, n)[1]) for g in gg])
        ax.plot(gg, np.maximum(back, 1e-16), color=col, ls="--", lw=1,
                label=f"|k_{n}(-1) / 4 pi p_HG(-1) - 1|: degree-{n} series at alpha = pi")
        ax.plot(gg, np.maximum(fwd, 1e-16), color=col, ls="-.", lw=1,
                label=f"|k_{n}(+1) / 4 pi p_HG(+1) - 1|: at alpha = 0")
    ax.axhline(BREAKS, color="k", lw=0.8)
    ax.text(0.01, BREAKS * 1.3, "10 %", fontsize=9)
    ax.set_yscale("log")
    ax.set_ylim(1e-10, 2e3)
    ax.set_xlabel("Henyey-Greenstein g")
    ax.set_ylabel("max relative error over the map's domain")
    ax.set_title("Where Sun's Appendix D stops working as g grows (F^k table version: already broken at g = 0,\n"
                 "behind the light, as Sun's F; ours: N table (R >= 1 um) and quadrature; dotted: documented bounds)",
                 fontsize=10)
    ax.legend(fontsize=7.5, loc="lower right")
    ax.grid(True, which="major", alpha=0.3)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, bbox_inches="tight")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--regen", action="store_true", help="recompute the cached reference values")
    ap.add_argument("--anisotropic", action="store_true",
                    help="only the anisotropic map (Sun's Appendix D against ours for g in ANISO_G)")
    ap.add_argument("--isotropic", action="store_true", help="only the isotropic map")
    ap.add_argument("--processes", type=int, default=2, help="for the anisotropic reference (default 2)")
    a = ap.parse_args(argv)
    if not a.anisotropic:
        c, params, ln_l, results = run(a.regen)
        write_csv(results, params, ln_l)
        plot(c, results, params, ln_l)
        print("wrote", PNG, CSV)
    if not a.isotropic:
        refs, params, results = run_aniso(a.regen, a.processes)
        write_aniso_csv(results, params)
        plot_aniso(refs, results, params)
        rows = aniso_summary_rows(results, params)
        for r in rows:
            print(f"g = {r['g']:<5} {r['formulation']:10s} max {r['max_err']:.3g}, > 10 %: {r['over_10_percent']:5d} "
                  f"of {r['samples']}, negative {r['negative']}, NaN/Inf {r['nonfinite']}"
                  + (f", over 10 % at gamma in [{r['gamma_over'][0]:.3g}, {r['gamma_over'][1]:.3g}], "
                     f"T_sv in [{r['t_sv_over'][0]:.3g}, {r['t_sv_over'][1]:.3g}]" if r["gamma_over"] else "")
                  + (f"; phase series at alpha = pi {r['phase_backward']:+.3g}, at 0 {r['phase_forward']:+.3g}"
                     if "phase_backward" in r else ""))
        write_aniso_summary_csv(rows)
        plot_aniso_gamma(results, params)
        plot_aniso_summary(rows)
        print("wrote", ANISO_PNG, ANISO_GAMMA_PNG, ANISO_SUMMARY_PNG, ANISO_CSV, ANISO_SUMMARY_CSV, ANISO_CACHE)


if __name__ == "__main__":
    main()
