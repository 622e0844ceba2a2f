"""Glow-only prototypes at 320x180 on many_lights: model.airlight_segment as is (both branches everywhere)
against a branch-masked copy (the short quadrature only where the segment is short, the tables only where
long), float32/float64, several chunk sizes.  Hits from a combined BVH (fast path).

    .venv/bin/python benchmarks/screen_cache_bake/glowfast.py N
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
from fog_addon.precompute import bakers, model  # noqa: E402
from fog_addon.precompute.model import (  # noqa: E402
    INV_2PI, MIN_ANGLE, SHORT_SEGMENT, _GL_W, _GL_X, airlight_background,
    airlight_segment, airlight_tail, phase_scale, segment_ends)
from fog_addon.precompute.ops import NumpyOps  # noqa: E402

from hits import m_bvh  # noqa: E402

from hits import H, REPS, W, fog_scene, timed  # noqa: E402,F401


def segment_masked(m, beta, d_sv, along, h, d_vp):
    """airlight_segment (g = 0), each element through its own branch only (1-D arrays)."""
    h, d_sp, q0, q1, seg = segment_ends(m, d_sv, along, h, d_vp, MIN_ANGLE * d_sv)
    is_short = beta * seg < SHORT_SEGMENT * np.minimum(1.0, beta * phase_scale(m, 0.0, q0, h))
    out = np.empty_like(seg)
    s = is_short
    if s.any():
        sq0, sh, sseg = q0[s], h[s], seg[s]
        h2 = sh * sh
        short = 0.0
        for x, w in zip(_GL_X, _GL_W):
            p = sseg * x
            q = sq0 + p
            short = short + w * np.exp(-beta * p) / np.maximum(q * q + h2, 1e-30)
        out[s] = short * sseg
    lg = ~s
    if lg.any():
        out[lg] = (airlight_tail(m, beta, q0[lg], h[lg], d_sv[lg])
                   - np.exp(-beta * seg[lg]) * airlight_tail(m, beta, q1[lg], h[lg], d_sp[lg]))
    return (beta * INV_2PI) * np.exp(-beta * d_sv) * out, float(s.mean())


def glow(cam, d, dist, lp, inten, beta, dtype, chunk, masked, tables):
    m = NumpyOps(tables, dtype=dtype)
    P, N = len(d), len(lp)
    out = np.zeros((P, 3), dtype)
    lp = lp.astype(dtype)
    I = inten.astype(dtype)
    b = dtype(beta)
    cam = cam.astype(dtype)
    shares = []
    for a in range(0, P, chunk):
        dd = d[a:a + chunk].astype(dtype)
        dv = dist[a:a + chunk].astype(dtype)
        sky = ~np.isfinite(dv)
        tl = lp[None, :, :] - cam                                # (1, N, 3)
        d_sv = np.broadcast_to(np.sqrt((tl * tl).sum(-1)), (len(dd), N))
        along = dd @ tl[0].T                                     # (C, N)
        t = tl[0]                                                # |to_light x d|, (C, N), no cancellation
        cx = dd[:, 1:2] * t[None, :, 2] - dd[:, 2:3] * t[None, :, 1]
        cy = dd[:, 2:3] * t[None, :, 0] - dd[:, 0:1] * t[None, :, 2]
        cz = dd[:, 0:1] * t[None, :, 1] - dd[:, 1:2] * t[None, :, 0]
        h = np.sqrt(cx * cx + cy * cy + cz * cz)
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            air = np.zeros((len(dd), N), dtype)
            hit = ~sky
            dvp = np.broadcast_to(dv[:, None], (len(dd), N))
            if masked:
                if hit.any():
                    v, sh = segment_masked(m, b, d_sv[hit].ravel(), along[hit].ravel(), h[hit].ravel(),
                                           dvp[hit].ravel())
                    air[hit] = v.reshape(-1, N)
                    shares.append(sh)
            elif hit.any():
                air[hit] = airlight_segment(m, b, d_sv[hit], along[hit], h[hit], dvp[hit])
            if sky.any():
                air[sky] = airlight_background(m, b, d_sv[sky], along[sky], h[sky])
            air = np.nan_to_num(air, nan=0.0, posinf=0.0)
        out[a:a + chunk] = air @ I
    return out, (float(np.mean(shares)) if shares else None)


def main(n):
    scene, cam, lights, beta = fog_scene(n)
    origin, d = view._frame_rays(scene, scene.camera, (W, H))
    dist, nrm, obj = m_bvh(scene)
    lp = np.array([np.array(o.matrix_world.translation) for o in lights])
    inten = view.light_intensities(lights)
    tables = bakers.numpy_tables(0.0)
    pl = W * H * len(lights)
    res = {"lights": len(lights)}
    ref, _ = glow(origin, d, dist, lp, inten, beta, np.float64, 20000, False, tables)
    for dt in (np.float64, np.float32):
        for chunk in (20000, 4096, 1024):
            for masked in (False, True):
                c, w, (got, share) = timed(lambda: glow(origin, d, dist, lp, inten, beta, dt, chunk, masked, tables))
                err = float(np.max(np.abs(got - ref)) / np.max(np.abs(ref)))
                key = f"{dt.__name__}_chunk{chunk}_{'masked' if masked else 'asis'}"
                res[key] = {"cpu": c, "wall": w, "ns_per_pixel_light": c / pl * 1e9, "maxerr_rel_peak": err,
                            "short_share": share}
                print(key, round(c, 3), round(w, 3), round(c / pl * 1e9), err, share, flush=True)
    print("GLOW_JSON " + json.dumps(res), flush=True)


if __name__ == "__main__":
    main(int(sys.argv[1]))
