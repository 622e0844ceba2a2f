"""The seed's own check (issue 28): Narasimhan et al.'s APSF series (Eq. 27, ``precompute/apsf.py``) against
our Monte Carlo transport around a point source (``precompute/physics/point/point_source_mc.py``), and how much of the
glow is multiply scattered, over the issue's range (T 1.5-8, q 0.5-0.9, albedo 0.8-0.99).

    .venv/bin/python benchmarks/apsf_check.py [--photons 200000]

Writes benchmarks/out/apsf_check.csv (per case and annulus: the Monte Carlo's single and multiple scattering,
the series, their ratios) and apsf_check.png (profiles).  Figures and their reading:
docs/measurements/2026-11-27-apsf.md.  Smoke mode (``FOG_BENCH_SMOKE=1``, benchmarks/smoke.py): one case, 2 000 photons.
"""
import argparse
import csv
import pathlib
import sys
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
import smoke  # noqa: E402
from tools.research import apsf  # noqa: E402
from fog_addon.precompute.physics.point import point_source_mc as mc  # noqa: E402

OUT = smoke.out(ROOT / "benchmarks" / "out")
CASES = smoke.pick([(0.5, 0.8), (0.5, 0.99), (0.9, 0.8), (0.9, 0.99)], [(0.9, 0.8)])   # (q, albedo)
RADII = [1.5, 2.0, 4.0, 8.0]
ANNULI = [(0.25, 1.0), (1.0, 3.0), (3.0, 10.0), (10.0, 30.0), (30.0, 90.0), (90.0, 180.0)]   # deg


def annulus_mean(values, edges, lo, hi):
    solid = np.cos(np.radians(edges[:-1])) - np.cos(np.radians(edges[1:]))
    k = (edges[:-1] >= lo - 1e-9) & (edges[1:] <= hi + 1e-9)
    return float(np.sum(values[k] * solid[k]) / np.sum(solid[k]))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--photons", type=int, default=smoke.pick(200_000, 2_000))
    args = ap.parse_args()
    OUT.mkdir(parents=True, exist_ok=True)
    edges = np.unique(np.concatenate([[0.0], np.geomspace(0.25, 180.0, 61), [1.0, 3.0, 10.0, 30.0, 90.0]]))
    rows, profiles = [], {}
    for q, w0 in CASES:
        t = time.perf_counter()
        r = mc.radiance(RADII, q, w0, photons=args.photons, edges_deg=edges, seed=11)
        secs = time.perf_counter() - t
        print(f"q {q} W0 {w0}: {secs:.1f} s", flush=True)
        theta = r["theta"]
        for T in RADII:
            single, multiple = r[T]
            series = apsf.apsf_series(T, np.cos(np.radians(theta)), q, w0, terms=400)
            profiles[(q, w0, T)] = (theta, single, multiple, series)
            for lo, hi in ANNULI:
                s1, sm, ap_ = (annulus_mean(x, edges, lo, hi) for x in (single, multiple, series))
                rows.append(dict(q=q, albedo=w0, T=T, theta_lo=lo, theta_hi=hi, mc_single=s1, mc_multiple=sm,
                                 apsf=ap_, multiple_over_single=sm / s1 if s1 else float("nan"),
                                 mc_total_over_apsf=(s1 + sm) / ap_ if ap_ else float("nan"),
                                 mc_multiple_over_apsf=sm / ap_ if ap_ else float("nan"),
                                 photons=args.photons, mc_seconds=secs))
    with open(OUT / "apsf_check.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    chart(profiles, OUT / "apsf_check.png")
    print("wrote", OUT / "apsf_check.csv")


def chart(profiles, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(len(CASES), len(RADII), figsize=(16, 13), sharex=True, squeeze=False)
    for i, (q, w0) in enumerate(CASES):
        for j, T in enumerate(RADII):
            ax = axes[i][j]
            theta, single, multiple, series = profiles[(q, w0, T)]
            ax.loglog(theta, single, label="Monte Carlo, single", color="C0")
            ax.loglog(theta, multiple, label="Monte Carlo, multiple (order >= 2)", color="C1")
            ax.loglog(theta, single + multiple, label="Monte Carlo, all orders", color="k", lw=1)
            ax.loglog(theta, np.where(series > 0, series, np.nan), "--", label="APSF series (Eq. 27)", color="C3")
            ax.set_title(f"q {q}, W0 {w0}, T {T}", fontsize=9)
            if i == len(CASES) - 1:
                ax.set_xlabel("angle from the source (deg)")
            if j == 0:
                ax.set_ylabel("I / I0 (sigma = 1)")
    axes[0][0].legend(fontsize=7)
    fig.suptitle("Glow around a point source: Narasimhan et al.'s series against Monte Carlo transport")
    fig.tight_layout()
    fig.savefig(path, dpi=90)


if __name__ == "__main__":
    main()
