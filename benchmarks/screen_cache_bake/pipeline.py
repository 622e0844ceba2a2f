"""End-to-end bake prototype at 320x180 on many_lights: hit buffer (Cycles 1-spp passes with an emission
override, or the combined BVH) -> materials by object index (Principled values, principled_albedos at each
pixel's view cosine) -> lean fog (glowfast.glow masked + fulllean.scatter, float32) -> Blender float image.
Checked against predict.light_fog on view.view_samples.

    .venv/bin/python benchmarks/screen_cache_bake/pipeline.py N
"""
import json
import math
import os
import sys
import time

import hits  # noqa: E402  (first: it puts the repository and tests/scenes on sys.path)

import bpy  # noqa: E402
import numpy as np  # noqa: E402

import many_lights  # noqa: E402
from fog_addon.ops import apply, view  # noqa: E402
from fog_addon.precompute import bakers, predict, surface, tables  # noqa: E402
from fulllean import scatter  # noqa: E402
from glowfast import glow  # noqa: E402

from hits import H, REPS, W, timed  # noqa: E402,F401
CHUNK = 4096


def materials(scene, d, dist, nrm, obj):
    """(rho_d, rho_s, level) per pixel from each object's Principled values (one material per object)."""
    P = len(d)
    rho_d, rho_s, level = np.zeros((P, 3)), np.zeros((P, 3)), np.zeros(P)
    cos_v = np.clip(-(d * nrm).sum(1), 0.0, 1.0)
    by_index = {ob.pass_index: ob for ob in scene.objects if ob.type == "MESH"}
    for k in np.unique(obj[obj > 0]):
        sel = obj == k
        vals = view._principled(by_index[int(k)].material_slots[0].material)
        base, metal, rough, lev, ior = vals
        rd, rs, _ = surface.principled_albedos(np.asarray(base)[None], metal, rough, lev, ior, cos_v[sel][:, None])
        rho_d[sel], rho_s[sel] = np.reshape(rd, (-1, 3)), np.reshape(rs, (-1, 3))
        level[sel] = tables.PHONG_LEVELS_PER_OCTAVE * math.log2(surface.phong_exponent_from_roughness(rough))
    return rho_d, rho_s, level


def main(n):
    scene, cam = hits.setup(n)
    lights, _ = apply.fog_lights(scene)
    beta = many_lights.BETA
    origin, d = view._frame_rays(scene, scene.camera, (W, H))
    lp = np.array([np.array(o.matrix_world.translation) for o in lights])
    inten = view.light_intensities(lights)
    tabs = bakers.numpy_tables(0.0)
    s = view.view_samples(scene, lights, grid=(W, H))
    g, sc = predict.light_fog(s, inten, beta)
    ref = (g + sc).sum(1)
    del g, sc
    img = bpy.data.images.new("FogCache", W, H, alpha=True, float_buffer=True, is_data=True)
    img.use_half_precision = False
    res = {"lights": len(lights)}
    for kind in ("cycles", "bvh"):
        if kind == "cycles":
            hits.cycles_setup(scene, True)
        stage = {}

        def run():
            t = [time.process_time()]
            if kind == "cycles":
                dist, nrm, obj, _, _ = hits.m_cycles(scene, True, origin)
            else:
                dist, nrm, obj = hits.m_bvh(scene)
            nrm = np.where(((nrm * d).sum(1) > 0)[:, None], -nrm, nrm)   # face the camera, as view.py
            t.append(time.process_time())
            rd, rs, lev = materials(scene, d, dist, nrm, obj)
            t.append(time.process_time())
            fog, _ = glow(origin, d, dist, lp, inten, beta, np.float32, CHUNK, True, tabs)
            fog = fog + scatter(origin, d, dist, nrm, rd, rs, lev, lp, inten, beta, np.float32, CHUNK, tabs)
            t.append(time.process_time())
            rgba = np.ones((W * H, 4), np.float32)
            rgba[:, :3] = fog
            rgba[:, 3] = np.where(np.isfinite(dist), dist, 1e9)
            img.pixels.foreach_set(rgba.ravel())
            img.update()
            t.append(time.process_time())
            for name, a, b in zip(("hits", "materials", "fog", "image"), t, t[1:]):
                stage.setdefault(name, []).append(b - a)
            return fog
        c, w, fog = timed(run)
        if kind == "cycles":
            hits.cycles_undo(scene)
        err = float(np.max(np.abs(fog - ref)) / np.max(np.abs(ref)))
        rel = float(np.max(np.abs(fog - ref) / np.maximum(np.abs(ref), 1e-3 * np.abs(ref).max())))
        rr = np.abs(fog - ref).max(1) / np.maximum(np.abs(ref).max(1), 1e-3 * np.abs(ref).max())
        res.setdefault("bad_pixels_gt_1pct", {})[kind] = int((rr > 0.01).sum())
        res[kind] = {"cpu": c, "wall": w, "stages_min_cpu": {k: min(v) for k, v in stage.items()},
                     "maxerr_rel_peak": err, "maxerr_rel_pixel": rel,
                     "p999_rel_pixel": float(np.quantile(
                         np.abs(fog - ref) / np.maximum(np.abs(ref), 1e-3 * np.abs(ref).max()), 0.999))}
        print(kind, json.dumps(res[kind]), flush=True)
    print("PIPE_JSON " + json.dumps(res), flush=True)


if __name__ == "__main__":
    main(int(sys.argv[1]))
