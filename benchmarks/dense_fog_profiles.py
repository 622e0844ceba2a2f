"""Chart: the glow profiles of a lamp in dense fog (T 1.5, 4.5, 8): Cycles with 64 volume bounces and with single
scattering (fog_scenes/dense.py references) against ours with Dense Fog on and off; writes
docs/figures/2026-11-27-dense-fog-ours.png.  Run: .venv/bin/python benchmarks/dense_fog_profiles.py
Smoke mode (``FOG_BENCH_SMOKE=1``, benchmarks/smoke.py): the first panel only, outputs in the smoke folder."""
import sys; import pathlib; ROOT = pathlib.Path(__file__).resolve().parents[1]; sys.path[:0] = [str(ROOT), str(ROOT / "tests")]
import numpy as np
import smoke
import matplotlib; matplotlib.use("Agg"); import matplotlib.pyplot as plt; import matplotlib.ticker
from fog_scenes import dense as dn
from fog_addon import imageio
CASES = smoke.pick(((15.0, 0.1, 2), (15.0, 0.3, 4), (20.0, 0.4, 4)), ((15.0, 0.1, 2),))   # (distance m, density, seeds)
OUT = smoke.out(ROOT / "benchmarks" / "out")
OUT.mkdir(parents=True, exist_ok=True)
FIGURE = smoke.out(ROOT / "docs/figures/2026-11-27-dense-fog-ours.png")
FIGURE.parent.mkdir(parents=True, exist_ok=True)
LOG = []   # the renders' output, shown in smoke mode
edges = np.geomspace(1.5, 55, 16)
fig, axes = plt.subplots(1, len(CASES), figsize=(14 * len(CASES) / 3, 4.2), squeeze=False)
axes = axes[0]
c = dn.lamp_image_centre()
for ax, (dist, dens, seeds) in zip(axes, CASES):
    ms = imageio.read_rgb(dn.render_ms_reference(dist, dens, 0.85, 0.9, volume_bounces=64, samples=2048, seeds=seeds))
    ss = imageio.read_rgb(dn.render_ms_reference(dist, dens, 0.85, 0.9, volume_bounces=0, samples=4096, seeds=2))
    on = imageio.read_rgb(dn.render_ours(dist, dens, 0.85, 0.9, str(OUT / f"dense_on_{dens}.exr"),
                                         multiple_scattering="on", log=LOG))
    off = imageio.read_rgb(dn.render_ours(dist, dens, 0.85, 0.9, str(OUT / f"dense_off_{dens}.exr"),
                                          multiple_scattering="off", log=LOG))
    mid = np.sqrt(edges[1:] * edges[:-1]) * 0.1
    for img, lab, st in ((ms, "Cycles, 64 volume bounces", "k-"), (ss, "Cycles, single scattering", "k--"),
                         (on, "ours, Dense Fog on", "C1o"), (off, "ours, Dense Fog off", "C0s")):
        ax.loglog(mid, dn.ring_means(img, c, edges_px=tuple(edges)), st, label=lab, ms=4)
    ax.set_title(f"T = {dist * dens:g} ({dist:g} m, density {dens:g}/m), g 0.85, albedo 0.9", fontsize=9)
    ax.set_xlabel("angle from the lamp (deg)")
    ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    ax.set_xticks([0.2, 0.5, 1, 2, 5]); ax.set_xticklabels(["0.2", "0.5", "1", "2", "5"])
axes[0].set_ylabel("annulus mean luminance")
axes[0].legend(fontsize=8)
fig.tight_layout(); fig.savefig(str(FIGURE), dpi=90)
smoke.echo(*LOG)
print("ok")
