"""Issue 8's overhead protocol for the compositor's fog light: render CPU time with fog over without.

    .venv/bin/python benchmarks/compositor_fog/overhead.py [N ...]     (default 1 4 16 64 256)

Each N runs ``build.py N ratio`` in a process of its own (the many-lights scene, Cycles on the CPU,
320x180, 16 spp, best of REPS=3 renders without fog, then with it, in that process).  Writes
benchmarks/out/compositor_fog_overhead.csv (with CF_MOMENTS=1: ..._moments.csv, the fog light at two
depths per pixel; CF_SPOTS=1 and CF_ANISOTROPY=g add _spots and _g<g>) and
docs/figures/compositor_fog_overhead.png from the variants in VARIANTS that exist.
"""
import json
import os
import pathlib
import subprocess
import sys

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))

import csv_rows  # noqa: E402

GOALS = {1: 1.5, 16: 2.0, 64: 3.0}   # issue 8 section 3
OUT = ROOT / "benchmarks" / "out"
VARIANTS = {"": "one depth per pixel (the samples' mean position)", "_moments": "two depths per pixel (moments)",
            "_spots_g0.7": "spot lights, g = 0.7 (one depth per pixel)"}


def measure(n):
    env = dict(os.environ, REPS=os.environ.get("REPS", "3"))
    proc = subprocess.run([sys.executable, str(HERE / "build.py"), str(n), "ratio",
                           str(OUT / f"compositor_fog_{n}.exr")],
                          capture_output=True, text=True, env=env, timeout=3600)
    rows = [json.loads(line) for line in proc.stdout.splitlines() if line.startswith("{")]
    if not rows:
        raise RuntimeError(f"{n} lights: no result\n{proc.stdout[-2000:]}\n{proc.stderr[-2000:]}")
    (OUT / f"compositor_fog_{n}.exr").unlink(missing_ok=True)
    return rows[0]


def chart(path):
    import csv
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 3.6))
    for suffix, label in VARIANTS.items():
        data = OUT / f"compositor_fog_overhead{suffix}.csv"
        if data.is_file():
            rows = list(csv.DictReader(open(data)))
            ax.plot([int(r["n"]) for r in rows], [float(r["ratio_cpu"]) for r in rows], "o-", label=label)
    ax.plot(list(GOALS), list(GOALS.values()), "k_", markersize=18, mew=2, label="issue 8's goals")
    ax.set_xscale("log", base=2)
    ax.set_xlabel("lights")
    ax.set_ylabel("render CPU time, fog / no fog")
    ax.set_title("Cycles CPU, 320x180, 16 spp (many-lights scene)")
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)


def main(counts):
    rows = []
    for n in counts:
        rows.append(measure(n))
        print(json.dumps(rows[-1]), flush=True)
    suffix = ("_moments" if os.environ.get("CF_MOMENTS") == "1" else "") + (
        "_spots" if os.environ.get("CF_SPOTS") == "1" else "") + (
        f"_g{float(os.environ['CF_ANISOTROPY']):g}" if os.environ.get("CF_ANISOTROPY") else "")
    csv_rows.write(OUT / f"compositor_fog_overhead{suffix}.csv", rows,
                   ["n", "cpu_nofog", "cpu", "ratio_cpu", "wall_nofog", "wall", "ratio_wall", "setup"], digits=4)
    chart(ROOT / "docs" / "figures" / "compositor_fog_overhead.png")


if __name__ == "__main__":
    main([int(a) for a in sys.argv[1:]] or [1, 4, 16, 64, 256])
