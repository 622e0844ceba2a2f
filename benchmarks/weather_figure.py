"""Figure (issue 28, like Narasimhan et al. Fig. 11-12): a fog-free render with its distance pass, the same with
``weather`` (visibility 39 m and 13 m), and Cycles' path-traced fog of the scene (64 volume bounces), tone-mapped
alike.  Writes docs/figures/2026-11-27-weather.png.  Run: .venv/bin/python benchmarks/weather_figure.py
Smoke mode (``FOG_BENCH_SMOKE=1``, benchmarks/smoke.py): the same, the figure in the smoke folder."""
import pathlib
import sys

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]
import smoke  # noqa: E402
from fog_addon import imageio, weather  # noqa: E402

REF = ROOT / "tests" / "references" / "glowing_sphere_d15_R0.15_L100_120x120"


def tone(img, exposure):
    x = np.clip(img * exposure, 0.0, None)
    return np.clip(x / (1.0 + x), 0.0, 1.0) ** (1.0 / 2.2)


def main():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    clear = imageio.read_rgb(f"{REF}_clear.exr")
    distance = weather.read_depth(f"{REF}_clear_distance.exr")
    panels = [("fog-free render (Cycles)", clear)]
    for vis in (39.12, 13.04):
        panels.append((f"weather, visibility {vis:g} m (T {3.912 / vis * 15:.1f})",
                       weather.add_weather(clear, distance, vis, anisotropy=0.85, sky=(0, 0, 0), fov_deg=12.0,
                                           albedo=0.9)))
    ref = pathlib.Path(f"{REF}_beta0.1_g0.85_a0.9_vb64_1024spp_x2.exr")
    if ref.is_file():
        panels.append(("Cycles path traced, 64 bounces (T 1.5)", imageio.read_rgb(ref)))
    fig, axes = plt.subplots(1, len(panels), figsize=(3.2 * len(panels), 3.5))
    for ax, (title, img) in zip(axes, panels):
        ax.imshow(tone(img, 2.0))
        ax.set_title(title, fontsize=8)
        ax.axis("off")
    fig.tight_layout()
    path = smoke.out(ROOT / "docs" / "figures" / "2026-11-27-weather.png")
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=100)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
