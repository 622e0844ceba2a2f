"""The daylight kernels' errors against the cached quadrature (tests/data/daylight_reference.npz), float64 and
float32, and the node/panel ladders of the two quadratures (sky directions, haze panels); with --figure, the
error distributions as docs/figures/2026-11-27-daylight-kernels.png.

    .venv/bin/python benchmarks/daylight_check.py [--figure]

Numbers go to docs/measurements/2026-11-27-daylight-kernels.md.  Smoke mode (``FOG_BENCH_SMOKE=1``,
benchmarks/smoke.py): the same, the figure drawn into the smoke folder.
"""
import argparse
import pathlib
import sys

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import smoke                                       # noqa: E402

from fog_addon.precompute.core import medium   # noqa: E402
from fog_addon.precompute.physics.daylight import aerial, daylight as dl   # noqa: E402
from tests import test_daylight as t               # noqa: E402
from tools.shader_float32 import Float32Ops        # noqa: E402


def stats(err):
    return f"max {err.max():.3g}, p99 {np.percentile(err, 99):.3g}, median {np.median(err):.3g}"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--figure", action="store_true", default=smoke.ON)
    a = ap.parse_args()
    c = dict(np.load(t.CACHE))
    out = {}
    sun, sref = c["sun"], c["sun_ref"]
    ok = sref > t.FLOOR
    out["sun"] = t._rel(t.k_sun(sun)[ok], sref[ok])
    print(f"sun_airlight float64, {ok.sum()} samples (+{(sref == 0).sum()} exact zeros): {stats(out['sun'])}")
    with np.errstate(all="ignore"):
        s32 = t.k_sun(sun, Float32Ops({}))
    out["sun32"] = t._rel(s32[ok], sref[ok])
    print(f"sun_airlight float32: {stats(out['sun32'])}; finite {np.all(np.isfinite(s32))}")
    sky, kref = c["sky"], c["sky_ref"]
    ok = kref > t.FLOOR
    for n in (4, 6, 8, 10, 12, 16):
        e = t._rel(t.k_sky(sky, nodes=n)[ok], kref[ok])
        print(f"sky_airlight, {n:2d} directions, {ok.sum()} samples: {stats(e)}")
        if n == dl.SKY_NODES:
            out["sky"] = e
    haze, href = c["haze"], c["haze_ref"]
    for n in (4, 6, 8, 12, 16):
        e = t._rel(t.k_haze(haze, panels=n), href)
        print(f"haze_airlight, {n:2d} panels, {len(href)} samples: {stats(e)}")
        if n == aerial.HAZE_PANELS:
            out["haze"] = e
    with np.errstate(all="ignore"):
        h32 = t.k_haze(haze, Float32Ops({}))
    print(f"haze_airlight float32: {stats(t._rel(h32, href))}; finite {np.all(np.isfinite(h32))}")
    for d in (5e3, 1e4, 2e4, 5e4, 1e5):
        print(f"flat Earth at {d / 1e3:5.0f} km: Rayleigh {aerial.flat_earth_error(d, medium.RAYLEIGH_HEIGHT):.3g}, "
              f"Mie {aerial.flat_earth_error(d, aerial.MIE_HEIGHT):.3g}")
    if a.figure:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(7, 4))
        bins = np.geomspace(1e-17, 1e-1, 81)
        for key, label in (("sun", "sun, closed form (f64)"), ("sun32", "sun, closed form (f32)"),
                           ("sky", f"sky, {dl.SKY_NODES} directions"), ("haze", f"haze, {aerial.HAZE_PANELS} panels")):
            ax.hist(np.maximum(out[key], 1e-17), bins=bins, histtype="step", label=label, density=False)
        ax.axvline(5e-3, color="k", ls="--", lw=0.8)
        ax.text(5.5e-3, ax.get_ylim()[1] * 0.9, "0.5 %", fontsize=8)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("relative error against scipy quadrature")
        ax.set_ylabel("samples")
        ax.set_title("Daylight kernels against quadrature (tests/data/daylight_reference.npz)")
        ax.legend(fontsize=8)
        fig.tight_layout()
        path = smoke.out(ROOT / "docs" / "figures" / "2026-11-27-daylight-kernels.png")
        path.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path, dpi=110)
        print("wrote", path)


if __name__ == "__main__":
    main()
