"""Figure (issue 29): the city of ``fog_scenes/daylight.py`` in a 100 m fog layer under a sun at 40 degrees and a
light-blue sky, from inside the layer and from above it: fog-free (Cycles), the Analytic Fog (Cycles, Compositor
method, 64 spp), Cycles' own path-traced fog in a mesh box (the cached references, 2 x 1024 spp), tone-mapped alike.
Writes docs/figures/2026-11-27-daylight.png.  Renders what it lacks (about 20 s a picture) into --work.
Run: .venv/bin/python benchmarks/daylight_figure.py [--work DIR]
Smoke mode (``FOG_BENCH_SMOKE=1``, benchmarks/smoke.py): the camera in the layer only, ours at 4 spp, the figure and the
renders in the smoke folder."""
import argparse
import pathlib
import sys

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT)]
import smoke  # noqa: E402
from fog_addon import compare, imageio  # noqa: E402
from fog_scenes import daylight as dl  # noqa: E402
from fog_scenes import render_harness as h  # noqa: E402

CASES = smoke.pick(("hard_g0_inside", "hard_g0_above"), ("hard_g0_inside",))
OUT = smoke.out(ROOT / "docs" / "figures" / "2026-11-27-daylight.png")
SAMPLES = smoke.pick(64, 4)   # ours


def tone(img, exposure):
    x = np.clip(img * exposure, 0.0, None)
    return np.clip(x / (1.0 + x), 0.0, 1.0) ** (1.0 / 2.2)


def ours(case, work):
    """The analytic fog's render of ``case`` (rendered if missing)."""
    out = work / f"{case}.exr"
    if not out.is_file():
        blend = dl.build_scene(work / f"{dl.as_case(case).camera}.blend", case, with_fog=False)
        log = []
        h.render_test("daylight", dl.layer(case)["beta0"], out, engine="cycles", method="compositor",
                      resolution=dl.RESOLUTION, blend=str(blend), samples=SAMPLES, extra=dl.fog_flags(case), log=log)
        smoke.echo(*log)
    return imageio.read_rgb(out)[..., :3]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--work", default=str(smoke.out(ROOT / "benchmarks" / "out" / "daylight_figure")))
    a = ap.parse_args(argv)
    work = pathlib.Path(a.work)
    work.mkdir(parents=True, exist_ok=True)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(len(CASES), 3, figsize=(10.5, 2.2 * len(CASES)), squeeze=False)
    for row, case in zip(axes, CASES):
        ref = imageio.read_rgb(dl.render_reference(case, samples=1024, seeds=2))[..., :3]
        clear = imageio.read_rgb(dl.render_clear(case, samples=1024, seeds=2))[..., :3]
        mine = ours(case, work)
        err = compare.metrics(mine, ref)["rel_rmse"]
        where = "camera in the layer" if case.endswith("inside") else "camera above the layer"
        for ax, (title, img) in zip(row, [(f"no fog ({where})", clear),
                                          (f"Analytic Fog, Cycles ({err:.1%} from path traced)", mine),
                                          ("Cycles path traced (fog in a mesh box)", ref)]):
            ax.imshow(tone(img, 3.0), interpolation="nearest")
            ax.set_title(title, fontsize=8)
            ax.axis("off")
    fig.tight_layout()
    OUT.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(OUT, dpi=110)
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
