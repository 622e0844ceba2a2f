"""Figure 6 of Sun et al. 2005 (airlight error vs table resolution), for Sun's F table and our N table.

    .venv/bin/python tools/figure6.py [--resolutions 16 32 64 128 256 512] [--no-timing]

Samples: the 44 000 cached reference samples of tests/data/airlight_reference.npz
(40 000 surface rays, 4 000 background rays; tools/airlight_reference.py).  Reference: scipy adaptive quadrature of Eq. 5.

Methods, at n x n texels for n in --resolutions:
  * Sun's F(u, v) table (Eq. 10, u in [0, 10] with u = 10 x^2, v in [0, pi/2]),
    Eq. 11/12 with bilinear and with nearest-neighbour lookups
    (airlight.bake_sun_f_table / airlight_sun);
  * our N(rho, xi) table (airlight.bake_airlight_table / airlight); the shipped
    128 x 64 table is added as its own row.

Metrics, per sample i with model value L_i and reference R_i:
  * Sun's normalised error  e_i = |L_i - R_i| / H_i,  H_i = (1 / 2 pi) * integral of
    L_a over the hemisphere of view directions facing the light (gamma < pi/2),
    same beta, D_sv, D_vp for every direction, i.e. the mean airlight per
    steradian (airlight_reference.hemisphere_mean).  Reported as mean and std
    over the samples, as the paper's error bars.
  * our strict relative error  r_i = |L_i / R_i - 1|: median, p99 and max.

Subsets (column ``subset``): ``all``; ``table_domain`` (A1 = T_sv sin gamma <= 10,
inside Sun's table); ``front_table_domain`` (also gamma < pi/2, where Sun's A0
does not carry the exponentially large e^{-T_sv cos gamma}).

Outputs: benchmarks/out/figure6.csv, benchmarks/out/figure6_timing.csv,
docs/figures/figure6.png.
"""
import argparse
import csv
import math
import pathlib
import sys
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))   # a script run by path: the repository root

from tools import airlight_reference as ref  # noqa: E402
from fog_addon.precompute.physics.point import airlight as al  # noqa: E402
from fog_addon.precompute.core import tables  # noqa: E402

OUT = ROOT / "benchmarks" / "out"
PNG = ROOT / "docs" / "figures" / "figure6.png"
U_MAX = 10.0


def ours(params, width, height):
    table = al.bake_airlight_table(tables.TableSpec(tables.AIRLIGHT.name, width, height))
    return al.airlight(*params, table=table)


def sun(params, n, interp):
    f = al.bake_sun_f_table(n, n, u_max=U_MAX)
    with np.errstate(all="ignore"):
        return al.airlight_sun(*params, f, u_max=U_MAX, interp=interp)


def metrics(value, reference, hemisphere):
    with np.errstate(all="ignore"):
        rel = np.abs(value / reference - 1.0)
        norm = np.abs(value - reference) / hemisphere
    bad = ~np.isfinite(rel)
    rel = np.where(bad, np.inf, rel)
    norm = np.where(~np.isfinite(norm), np.inf, norm)
    return dict(norm_mean=float(np.mean(norm)), norm_std=float(np.std(norm)), norm_max=float(np.max(norm)),
                rel_median=float(np.median(rel)), rel_p99=float(np.percentile(rel, 99)),
                rel_max=float(np.max(rel)), nonfinite=int(bad.sum()))


def run(resolutions, log=print):
    c = ref.load_cache(log=log)
    b, s, v, g = (c[k] for k in ("beta", "d_sv", "d_vp", "gamma"))
    r, hemi = c["reference"], c["hemisphere"]
    a1 = b * s * np.sin(g)
    subsets = {"all": np.ones(len(r), bool), "table_domain": a1 <= U_MAX,
               "front_table_domain": (a1 <= U_MAX) & (g < 0.5 * math.pi)}
    params = (b, s, v, g)
    rows = []
    runs = [("sun_F", "bilinear", n, n, lambda n=n: sun(params, n, "linear")) for n in resolutions]
    runs += [("sun_F", "nearest", n, n, lambda n=n: sun(params, n, "nearest")) for n in resolutions]
    runs += [("ours_N", "bilinear", n, n, lambda n=n: ours(params, n, n)) for n in resolutions]
    runs += [("ours_N", "bilinear", tables.AIRLIGHT.width, tables.AIRLIGHT.height,
              lambda: ours(params, tables.AIRLIGHT.width, tables.AIRLIGHT.height))]
    for method, interp, w, h, fn in runs:
        val = fn()
        for name, m in subsets.items():
            row = dict(method=method, interp=interp, width=w, height=h, subset=name, samples=int(m.sum()))
            row.update(metrics(val[m], r[m], hemi[m]))
            rows.append(row)
        a = rows[-3]
        log(f"{method:7s} {interp:8s} {w:4d}x{h:<4d} norm {a['norm_mean']:.3g}+-{a['norm_std']:.3g}  "
            f"rel median {a['rel_median']:.3g} p99 {a['rel_p99']:.3g} max {a['rel_max']:.3g}")
    return rows


def timing(n=1_000_000, seed=5, repeats=3):
    b, s, v, g = ref.sample_parameters(n, seed)
    v = np.where(np.arange(n) % 10 == 0, np.inf, v)      # 10 % background rays
    table = al.bake_airlight_table()
    f64 = al.bake_sun_f_table(64, 64)
    cases = [("ours_N 128x64 bilinear", lambda: al.airlight(b, s, v, g, table=table)),
             ("sun_F 64x64 bilinear", lambda: al.airlight_sun(b, s, v, g, f64, interp="linear")),
             ("sun_F 64x64 nearest", lambda: al.airlight_sun(b, s, v, g, f64, interp="nearest"))]
    rows = []
    with np.errstate(all="ignore"):
        for name, fn in cases:
            fn()
            best = min(_timed(fn) for _ in range(repeats))
            rows.append(dict(method=name, samples=n, seconds=best, ns_per_eval=best / n * 1e9))
    m = 200
    t0 = time.perf_counter()
    for i in range(m):
        ref._work((b[i], s[i], v[i], g[i]))
    t = (time.perf_counter() - t0) / m
    rows.append(dict(method="reference scipy quad of Eq. 5 (per sample, not vectorised)", samples=m,
                     seconds=t * m, ns_per_eval=t * 1e9))
    return rows


def _timed(fn):
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def write_csv(path, rows):
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


def plot(rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(9, 5), dpi=100)
    styles = {("sun_F", "bilinear"): ("tab:red", "Sun F, bilinear"),
              ("sun_F", "nearest"): ("tab:green", "Sun F, nearest"),
              ("ours_N", "bilinear"): ("tab:blue", "ours N, bilinear")}
    for (method, interp), (col, label) in styles.items():
        for subset, ls, suffix in (("all", "-", ""), ("front_table_domain", ":", " (A1<=10, gamma<pi/2)")):
            if method == "ours_N" and subset != "all":
                continue
            rs = [x for x in rows if x["method"] == method and x["interp"] == interp and x["subset"] == subset
                  and x["width"] == x["height"]]
            n = np.array([x["width"] for x in rs])
            mean = np.array([x["norm_mean"] for x in rs])
            std = np.array([x["norm_std"] for x in rs])
            ax0.errorbar(n * (1.03 if ls == ":" else 1.0), mean, yerr=[np.minimum(std, mean * 0.999), std],
                         color=col, ls=ls, marker="o", ms=3, capsize=2, label=label + suffix)
            med = np.array([x["rel_median"] for x in rs])
            mx = np.array([x["rel_max"] for x in rs])
            p99 = np.array([x["rel_p99"] for x in rs])
            ax1.plot(n, med, color=col, ls=ls, marker="o", ms=3, label=label + suffix + " median")
            ax1.plot(n, p99, color=col, ls=ls, marker="^", ms=3, alpha=0.6)
            ax1.plot(n, mx, color=col, ls=ls, marker="v", ms=3, alpha=0.35)
    ship = [x for x in rows if x["method"] == "ours_N" and x["width"] != x["height"] and x["subset"] == "all"]
    for x in ship:
        ax1.plot([math.sqrt(x["width"] * x["height"])] * 3, [x["rel_median"], x["rel_p99"], x["rel_max"]], "k*",
                 ms=8, label=f"ours shipped {x['width']}x{x['height']} (median, p99, max)")
    ax1.axhline(5e-3, color="k", lw=0.8, ls="--", label="0.5 % requirement")
    for ax in (ax0, ax1):
        ax.set_xscale("log", base=2)
        ax.set_yscale("log")
        ax.set_xlabel("table resolution n (n x n texels)")
        ax.grid(True, which="both", alpha=0.3)
    ax0.set_ylabel("|L - L_ref| / hemisphere mean airlight")
    ax0.set_title("Sun's metric: mean +- std", fontsize=10)
    ax1.set_ylabel("|L / L_ref - 1|")
    ax1.set_title("strict per sample: median (o), p99 (^), max (v)", fontsize=10)
    ax0.legend(fontsize=7)
    ax1.legend(fontsize=6, loc="upper right")
    fig.suptitle("Airlight error vs table resolution (43 999 samples, ref. = quadrature of Eq. 5)", fontsize=11)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--resolutions", type=int, nargs="+", default=[16, 32, 64, 128, 256, 512])
    ap.add_argument("--no-timing", action="store_true")
    a = ap.parse_args(argv)
    rows = run(a.resolutions)
    write_csv(OUT / "figure6.csv", rows)
    plot(rows, PNG)
    print("wrote", OUT / "figure6.csv", PNG)
    if not a.no_timing:
        t = timing()
        write_csv(OUT / "figure6_timing.csv", t)
        for x in t:
            print(f"{x['method']:60s} {x['ns_per_eval']:10.1f} ns/eval")


if __name__ == "__main__":
    main()
