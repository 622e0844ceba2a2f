"""Image comparison metrics and diff images (numpy only).

Definitions (``a`` = test, ``b`` = reference, RGB, all pixels):

* ``rel_rmse``   = ||a - b||_2 / ||b||_2 over all pixels and channels;
* per-pixel relative error e_p = |a_p - b_p| / max(|b_p|, floor), with |.| the
  Euclidean norm over the RGB channels of pixel p and ``floor`` =
  ``FLOOR_FRACTION`` x the mean of |b_p| (keeps black pixels from dominating);
  ``median_rel`` and ``p95_rel`` are its median and 95th percentile;
* ``mean_ratio`` = sum(a) / sum(b) (overall brightness ratio);
* ``max_rel`` = max e_p.
"""
import math

import numpy as np

FLOOR_FRACTION = 1e-3


def _rgb(x):
    a = np.asarray(x, dtype=np.float64)
    if a.ndim == 2:
        a = a[..., None]
    if a.shape[-1] == 1:
        a = np.repeat(a, 3, axis=-1)
    return a[..., :3]


def per_pixel_relative_error(a, b):
    a, b = _rgb(a), _rgb(b)
    nb = np.linalg.norm(b, axis=-1)
    floor = FLOOR_FRACTION * float(nb.mean()) if nb.size else 0.0
    floor = max(floor, 1e-30)
    return np.linalg.norm(a - b, axis=-1) / np.maximum(nb, floor)


def metrics(a, b, mask=None):
    """Dict of rel_rmse, median_rel, p95_rel, max_rel, mean_ratio, n_pixels, n_nonfinite."""
    a, b = _rgb(a), _rgb(b)
    if a.shape != b.shape:
        raise ValueError(f"image sizes differ: test {a.shape[:2]} vs reference {b.shape[:2]}")
    if mask is not None:
        mask = np.asarray(mask, dtype=bool)
        a, b = a[mask], b[mask]
    bad = ~(np.isfinite(a).all(axis=-1) & np.isfinite(b).all(axis=-1))
    n_bad = int(bad.sum())
    nb = float(np.linalg.norm(b))
    rel_rmse = float(np.linalg.norm(a - b) / nb) if nb > 0 else (0.0 if not np.any(a) else math.inf)
    e = per_pixel_relative_error(a, b)
    sb = float(b.sum())
    return {
        "rel_rmse": rel_rmse if n_bad == 0 else math.nan,
        "median_rel": float(np.median(e)),
        "p95_rel": float(np.percentile(e, 95)),
        "max_rel": float(np.max(e)),
        "mean_ratio": float(a.sum() / sb) if sb != 0 else math.nan,
        "n_pixels": int(e.size),
        "n_nonfinite": n_bad,
    }


def format_metrics(m):
    s = (f"relative RMSE {m['rel_rmse']:.6f}\n"
         f"median per-pixel relative error {m['median_rel']:.6f}\n"
         f"p95 per-pixel relative error {m['p95_rel']:.6f}\n"
         f"max per-pixel relative error {m['max_rel']:.6f}\n"
         f"mean ratio (test/reference) {m['mean_ratio']:.6f}\n"
         f"pixels {m['n_pixels']}")
    if m.get("n_nonfinite"):
        s += f"\nNON-FINITE pixels {m['n_nonfinite']}"
    return s


def _display(x, scale):
    """Simple display mapping for diff images: linear / scale, sRGB-ish gamma."""
    return np.clip(x / scale, 0.0, 1.0) ** (1.0 / 2.2)


def diff_image(a, b, max_rel=0.1):
    """Side by side: test | reference | per-pixel relative error (0 -> black,
    ``max_rel`` -> white; red where test > reference, blue where test < reference)."""
    a, b = _rgb(a), _rgb(b)
    scale = float(np.percentile(b, 99.5)) or 1.0
    e = np.clip(per_pixel_relative_error(a, b) / max_rel, 0.0, 1.0)
    sign = np.sign(a.sum(-1) - b.sum(-1))
    err = np.stack([e * (sign >= 0) + 0.25 * e * (sign < 0),
                    0.25 * e,
                    e * (sign < 0) + 0.25 * e * (sign >= 0)], axis=-1)
    sep = np.ones((a.shape[0], 2, 3))
    return np.concatenate([_display(a, scale), sep, _display(b, scale), sep, err], axis=1).astype(np.float32)


def write_diff(a, b, path, max_rel=0.1):
    from . import imageio
    imageio.write_png(path, diff_image(a, b, max_rel=max_rel))
    return path


def compare_files(test, ref, diff=None, max_rel=0.1):
    from . import imageio
    a = imageio.read_rgb(test)
    b = imageio.read_rgb(ref)
    m = metrics(a, b)
    if diff:
        write_diff(a, b, diff, max_rel=max_rel)
    return m
