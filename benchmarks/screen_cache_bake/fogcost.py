"""Cost of the per-pixel numpy fog twin at 320x180 on many_lights: predict.light_fog (float64) and a copy
with a dtype (float64 / float32), by stage; glow-only.

    .venv/bin/python benchmarks/screen_cache_bake/fogcost.py N
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
from fog_addon.precompute import bakers, model, predict, rungs, shading  # noqa: E402
from fog_addon.precompute.ops import NumpyOps  # noqa: E402

from hits import H, REPS, W, fog_scene, timed  # noqa: E402,F401
CHUNK = int(os.environ.get("CHUNK", 20000))


def original(samples, inten, beta):
    P = len(samples.distance)
    fog = np.zeros((P, 3))
    for a in range(0, P, CHUNK):
        part = predict.ViewSamples(*[None if f is None else f[a:a + CHUNK] for f in samples])
        glow, scatter = predict.light_fog(part, inten, beta)
        fog[a:a + CHUNK] = (glow + scatter).sum(axis=1)
    return fog


STAGES = {}


def fog_dtype(samples, light_pos, inten, beta, dtype, glow_only=False, tables=None):
    """predict.light_fog for point lights, lights (N, 3) broadcast (not (P, N, 3)), arrays in ``dtype``,
    summed over the lights to (P, 3); per-stage CPU times into STAGES."""
    m = NumpyOps(tables, dtype=dtype)
    full = rungs.choose("nodes", 0, 0.0)
    P = len(samples.distance)
    out = np.zeros((P, 3), dtype)
    lp = np.asarray(light_pos, dtype)[None, :, :]
    I = np.asarray(inten, dtype)
    b = dtype(beta)
    for a in range(0, P, CHUNK):
        s = slice(a, a + CHUNK)
        t0 = time.process_time()
        cam = np.asarray(samples.camera[s], dtype)[:, None, :]
        d = np.asarray(samples.direction[s], dtype)[:, None, :]
        dist = np.asarray(samples.distance[s], dtype)[:, None]
        sky = ~np.isfinite(dist)
        d_vp = np.where(sky, dtype(0), dist)
        d_sv, along, h = model.ray_light_geometry(m, cam, d, lp)
        t1 = time.process_time()
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            if sky.any():
                air = np.where(sky, m.run(full.background, b, d_sv, along, h),
                               m.run(full.airlight, b, d_sv, along, h, d_vp))
            else:
                air = m.run(full.airlight, b, d_sv, along, h, d_vp)
            air = np.nan_to_num(air, nan=0.0, posinf=0.0)
            t2 = time.process_time()
            fog = air @ I                                           # (C, 3): sum over lights of I_i * air_i
            t3 = time.process_time()
            if not glow_only:
                to_l = lp - (cam + m.scale(d, d_vp))
                d_sp = np.maximum(m.length(to_l), dtype(model.MIN_DISTANCE))
                n = np.asarray(samples.normal[s], dtype)[:, None, :]
                cos_n = m.dot(to_l, n) / d_sp
                cos_r = m.dot(to_l, shading.mirror(m, -d, n)) / d_sp
                level = np.broadcast_to(np.asarray(samples.level[s], dtype)[:, None], cos_r.shape)
                diffuse = m.run(full.scatter, b, d_sp, cos_n, np.zeros_like(level))
                glossy = m.run(full.scatter, b, d_sp, cos_r, level)
                t4 = time.process_time()
                t_vp = np.exp(-b * d_vp)                            # (C, 1)
                dif = np.nan_to_num(diffuse * t_vp, nan=0.0, posinf=0.0) @ I
                glo = np.nan_to_num(glossy * t_vp, nan=0.0, posinf=0.0) @ I
                refl = (np.asarray(samples.rho_d[s], dtype) * dif + np.asarray(samples.rho_s[s], dtype) * glo)
                fog = fog + np.where(sky, dtype(0), refl)
                t5 = time.process_time()
                STAGES["scatter_kernels"] = STAGES.get("scatter_kernels", 0) + t4 - t3
                STAGES["scatter_combine"] = STAGES.get("scatter_combine", 0) + t5 - t4
        out[s] = fog
        STAGES["geometry"] = STAGES.get("geometry", 0) + t1 - t0
        STAGES["airlight"] = STAGES.get("airlight", 0) + t2 - t1
        STAGES["glow_combine"] = STAGES.get("glow_combine", 0) + t3 - t2
    return out


def main(n):
    scene, cam, lights, beta = fog_scene(n)
    res = {"lights": len(lights), "pixels": W * H, "beta": beta, "chunk": CHUNK,
           "rungs": {k: getattr(rungs.choose("nodes", 0, 0.0), k).kernel.__name__
                     for k in ("airlight", "background", "scatter")}}
    c, w, samples = timed(lambda: view.view_samples(scene, lights, grid=(W, H)), reps=1)
    res["view_samples_existing_1rep"] = (c, w)
    print("view_samples", c, w, flush=True)
    inten = view.light_intensities(lights)
    light_pos = np.array([np.array(o.matrix_world.translation) for o in lights])
    tables = bakers.numpy_tables(0.0)
    pl = W * H * len(lights)

    c, w, ref = timed(lambda: original(samples, inten, beta))
    res["predict_light_fog_f64"] = (c, w, c / pl * 1e9)
    print("original", c, w, flush=True)
    for name, dt in (("f64", np.float64), ("f32", np.float32)):
        for go in (False, True):
            STAGES.clear()
            c, w, got = timed(lambda: fog_dtype(samples, light_pos, inten, beta, dt, go, tables))
            key = f"copy_{name}_{'glow' if go else 'full'}"
            res[key] = (c, w, c / pl * 1e9, {k: v / REPS for k, v in STAGES.items()})
            if not go:
                err = np.abs(got - ref).max() / np.abs(ref).max()
                res[key + "_maxerr_rel_peak"] = float(err)
                rel = np.abs(got - ref) / np.maximum(np.abs(ref), 1e-3 * np.abs(ref).max())
                res[key + "_maxerr_rel_pixel"] = float(rel.max())
            print(key, c, w, flush=True)
    print("FOG_JSON " + json.dumps(res), flush=True)


if __name__ == "__main__":
    main(int(sys.argv[1]))
