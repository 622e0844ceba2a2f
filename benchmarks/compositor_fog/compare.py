"""The compositor's fog light against the materials' (the Fog Light AOV, averaged over each pixel's samples).

    .venv/bin/python benchmarks/compositor_fog/compare.py EXACT.exr
Prints one JSON line: relative RMSE, the share of pixels (above 1e-3 of the peak) more than 1 % off, the
largest relative error, and the same split into pixels wholly on one surface or the sky and mixed pixels
(coverage strictly between 0 and 1, or a normal that varies within the pixel).  With EXACT.exr.json (the
lights' pixels) the 7 x 7 pixels about each light are a group of their own ("peaks"): there the materials'
16 samples a pixel are noise about the pixel's mean (``peaks.py`` measures both against converged means).
"""
import json
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from fog_addon import imageio  # noqa: E402


def layer(layers, name):
    return next(v for k, v in layers.items() if k.endswith(name))


def stats(got, want, mask):
    g, w = got[mask], want[mask]
    peak = want.max()
    lit = w.max(axis=-1) > 1e-3 * peak
    rel = np.abs(g - w).max(axis=-1) / np.maximum(w.max(axis=-1), 1e-3 * peak)
    return {"pixels": int(mask.sum()), "rel_rmse": float(np.sqrt(((g - w) ** 2).sum() / max((w ** 2).sum(), 1e-30))),
            "over_1pc": float((rel[lit] > 0.01).mean()) if lit.any() else 0.0,
            "max_rel": float(rel[lit].max()) if lit.any() else 0.0}


def main(path):
    layers = imageio.read_layers(path)
    want = layer(layers, "Fog Light")[..., :3]
    got = layer(layers, "Composite.Combined")[..., :3]
    cover = layer(layers, "Fog Coverage")[..., 0]
    normal = layer(layers, "Fog Normal")[..., :3]
    nlen = np.linalg.norm(normal, axis=-1) / np.maximum(cover, 1e-6)
    mixed = ((cover > 1e-4) & (cover < 1 - 1e-4)) | ((cover > 0.5) & (nlen < 0.999))
    peaks = np.zeros(cover.shape, bool)
    side = pathlib.Path(path + ".json")
    if side.is_file():
        h = cover.shape[0]
        for x, y, _ in json.loads(side.read_text())["light_pixels"]:
            row = h - 1 - int(y)   # the EXR's rows run from the top
            peaks[max(row - 3, 0):max(row + 4, 0), max(int(x) - 3, 0):max(int(x) + 4, 0)] = True
    out = {"all": stats(got, want, np.ones_like(cover, bool)), "pure": stats(got, want, ~mixed & ~peaks),
           "mixed": stats(got, want, mixed & ~peaks), "peaks": stats(got, want, peaks),
           "all_but_peaks": stats(got, want, ~peaks)}
    print(json.dumps(out))


if __name__ == "__main__":
    main(sys.argv[-1])
