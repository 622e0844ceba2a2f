"""Full fog (glow + scattered light) lean prototype at 320x180 on many_lights, vs predict.light_fog:
glow branch-masked (glowfast.glow), scatter only on surface pixels, grouped by material so the Phong level is
a Python float (diffuse: level 0, one table lookup), chunked, float32/float64.

    .venv/bin/python benchmarks/screen_cache_bake/fulllean.py N
"""
import json
import os
import sys
import time

import hits  # noqa: E402  (first: it puts the repository and tests/scenes on sys.path)

import bpy  # noqa: E402,F401
import numpy as np  # noqa: E402

import many_lights  # noqa: E402
from fog_addon import measure  # noqa: E402
from fog_addon.ops import apply, view  # noqa: E402
from fog_addon.precompute import bakers, model, predict, shading, surface  # noqa: E402
from fog_addon.precompute.ops import NumpyOps  # noqa: E402
from glowfast import glow  # noqa: E402

from hits import H, REPS, W, fog_scene, timed  # noqa: E402,F401


def scatter(cam, d, dist, nrm, rho_d, rho_s, level, lp, inten, beta, dtype, chunk, tables):
    """sum_i I_i e^{-beta d_vp} (rho_d M0 + rho_s Mn), (P, 3), only where dist is finite; pixels grouped by level."""
    m = NumpyOps(tables, dtype=dtype)
    P, N = len(d), len(lp)
    out = np.zeros((P, 3), dtype)
    hit = np.isfinite(dist)
    lp = lp.astype(dtype)
    I = inten.astype(dtype)
    b = dtype(beta)
    for lev in np.unique(level[hit]):
        idx = np.flatnonzero(hit & (level == lev))
        for a in range(0, len(idx), chunk):
            k = idx[a:a + chunk]
            dd, dv, n = d[k].astype(dtype), dist[k].astype(dtype), nrm[k].astype(dtype)
            p = cam.astype(dtype) + dd * dv[:, None]
            to_l = lp[None, :, :] - p[:, None, :]                       # (C, N, 3)
            d_sp = np.maximum(np.sqrt((to_l * to_l).sum(-1)), dtype(model.MIN_DISTANCE))
            cos_n = (to_l @ n[:, :, None])[..., 0] / d_sp
            r = 2 * (-dd * n).sum(1, keepdims=True) * n + dd           # mirror of -d about n
            cos_r = (to_l @ r[:, :, None])[..., 0] / d_sp
            with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
                dif = surface.surface_scatter(m, b, d_sp, cos_n, 0.0)
                glo = surface.surface_scatter(m, b, d_sp, cos_r, float(lev))
                t_vp = np.exp(-b * dv)[:, None]
                out[k] = (rho_d[k].astype(dtype) * (np.nan_to_num(dif, nan=0.0, posinf=0.0) @ I)
                          + rho_s[k].astype(dtype) * (np.nan_to_num(glo, nan=0.0, posinf=0.0) @ I)) * t_vp
    return out


def main(n):
    scene, cam, lights, beta = fog_scene(n)
    s = view.view_samples(scene, lights, grid=(W, H))
    lp = np.array([np.array(o.matrix_world.translation) for o in lights])
    inten = view.light_intensities(lights)
    tables = bakers.numpy_tables(0.0)
    glow_ref, scat_ref = predict.light_fog(s, inten, beta)
    ref = (glow_ref + scat_ref).sum(1)
    del glow_ref, scat_ref
    cam = s.camera[0]
    pl = W * H * len(lights)
    res = {"lights": len(lights), "levels": [float(v) for v in np.unique(s.level)]}
    for dt in (np.float64, np.float32):
        for chunk in (4096, 2048):
            def run():
                c0 = time.process_time()
                g, _ = glow(cam, s.direction, s.distance, lp, inten, beta, dt, chunk, True, tables)
                c1 = time.process_time()
                sc = scatter(cam, s.direction, s.distance, s.normal, s.rho_d, s.rho_s, s.level, lp, inten, beta, dt,
                             chunk, tables)
                return g + sc, c1 - c0, time.process_time() - c1
            c, w, (got, cg, cs) = timed(run)
            err = float(np.max(np.abs(got - ref)) / np.max(np.abs(ref)))
            rel = float(np.max(np.abs(got - ref) / np.maximum(np.abs(ref), 1e-3 * np.abs(ref).max())))
            key = f"{dt.__name__}_chunk{chunk}"
            res[key] = {"cpu": c, "wall": w, "ns_per_pixel_light": c / pl * 1e9, "glow_cpu_last": cg,
                        "scatter_cpu_last": cs, "maxerr_rel_peak": err, "maxerr_rel_pixel": rel}
            print(key, round(c, 3), round(w, 3), round(c / pl * 1e9), round(cg, 3), round(cs, 3), err, rel, flush=True)
    print("LEAN_JSON " + json.dumps(res), flush=True)


if __name__ == "__main__":
    main(int(sys.argv[1]))
