"""Hit buffers at pixel centres, 320x180, many_lights scene: scene.ray_cast vs BVHTree vs Cycles passes.

    .venv/bin/python benchmarks/screen_cache_bake/hits.py N [methods...]
methods: nofog scene bvh bvhobj cycles cyclesmat  (default all)
"""
import json
import os
import subprocess
import sys
import time

import pathlib  # noqa: E402
ROOT = str(pathlib.Path(__file__).resolve().parents[2])
HERE = str(pathlib.Path(__file__).resolve().parent)
sys.path.insert(0, ROOT)
sys.path.insert(0, ROOT + "/tests/scenes")

import bpy  # noqa: E402
import numpy as np  # noqa: E402
from mathutils import Vector  # noqa: E402
from mathutils.bvhtree import BVHTree  # noqa: E402

import many_lights  # noqa: E402
from fog_addon import measure  # noqa: E402
from fog_addon.ops import apply, view  # noqa: E402

W, H = 320, 180
OUT = ROOT + "/benchmarks/out/screen_cache_bake"
os.makedirs(OUT, exist_ok=True)
REPS = int(os.environ.get("REPS", 3))


def fog_scene(n):
    """(scene, camera, fog lights, beta 1/m) of the many-lights scene with ``n`` lights at W x H."""
    scene, cam = many_lights.build_scene(n, direct_light=True)
    measure.set_resolution(scene, W, H)
    bpy.context.view_layer.update()
    lights, _ = apply.fog_lights(scene)
    return scene, cam, lights, many_lights.BETA


def timed(fn, reps=REPS):
    """(min CPU s, min wall s, last result) of ``fn()`` over ``reps`` runs; the other probes import it."""
    best_c, best_w, res = 1e9, 1e9, None
    for _ in range(reps):
        c0, w0 = time.process_time(), time.perf_counter()
        res = fn()
        c, w = time.process_time() - c0, time.perf_counter() - w0
        best_c, best_w = min(best_c, c), min(best_w, w)
    return best_c, best_w, res


def setup(n):
    scene, cam = many_lights.build_scene(n, direct_light=True)
    scene.render.engine = "CYCLES"
    measure.set_resolution(scene, W, H)
    measure.set_samples(scene, 16)
    measure.set_cycles_cpu(scene)          # auto threads, as benchmarks/overhead.py
    scene.cycles.use_denoising = False
    scene.render.use_persistent_data = False
    for k, ob in enumerate([o for o in scene.objects if o.type == "MESH"], 1):
        ob.pass_index = k
        for j, slot in enumerate(ob.material_slots):
            slot.material.pass_index = k
    bpy.context.view_layer.update()
    return scene, cam


def rays(scene):
    origin, d = view._frame_rays(scene, scene.camera, (W, H))   # row 0 = bottom
    return origin, d


def m_scene(scene):
    origin, d = rays(scene)
    dg = bpy.context.evaluated_depsgraph_get()
    o = Vector(origin)
    dist = np.full(len(d), np.inf)
    nrm = np.zeros((len(d), 3))
    obj = np.zeros(len(d), int)
    rc = scene.ray_cast
    for i, di in enumerate(d.tolist()):
        hit, loc, normal, index, ob, mat = rc(dg, o, di)
        if hit:
            dist[i] = (loc - o).length
            nrm[i] = normal
            obj[i] = ob.pass_index
    return dist, nrm, obj


def m_bvh(scene):
    """One BVH of all triangles (view._SceneMesh) + per-pixel cast + vectorised smooth normals."""
    origin, d = rays(scene)
    dg = bpy.context.evaluated_depsgraph_get()
    sm = view._SceneMesh(dg)
    tree = sm.tree
    o = Vector(origin)
    P = len(d)
    loc = np.full((P, 3), np.nan)
    tri = np.full(P, -1, int)
    rc = tree.ray_cast
    for i, di in enumerate(d.tolist()):
        l, nn, idx, dd = rc(o, di)
        if l is not None:
            loc[i] = l
            tri[i] = idx
    hit = tri >= 0
    dist = np.where(hit, np.linalg.norm(loc - origin, axis=1), np.inf)
    # owner per hit, smooth normal by barycentrics (numpy, per owner)
    first = np.asarray(sm.first_tri)
    k = np.searchsorted(first, np.where(hit, tri, 0), side="right") - 1
    nrm = np.zeros((P, 3))
    obj = np.zeros(P, int)
    for j, info in enumerate(sm.owners):
        sel = hit & (k == j)
        if not sel.any():
            continue
        obj[sel] = info.ev.pass_index
        mesh = info.mesh
        lt = tri[sel] - first[j]
        corners = info.loops[lt]                                   # (S, 3) loop indices
        lv = np.empty(len(mesh.loops), np.int64)
        mesh.loops.foreach_get("vertex_index", lv)
        co = np.empty(3 * len(mesh.vertices))
        mesh.vertices.foreach_get("co", co)
        co = co.reshape(-1, 3)
        cn = np.empty(3 * len(mesh.corner_normals))
        mesh.corner_normals.foreach_get("vector", cn)
        cn = cn.reshape(-1, 3)
        a, b, c = (co[lv[corners[:, q]]] for q in range(3))
        p = (loc[sel] - info_mat_t(info)) @ info.inv[:3, :3].T
        v0, v1, v2 = b - a, c - a, p - a
        d00, d01, d11 = (v0 * v0).sum(1), (v0 * v1).sum(1), (v1 * v1).sum(1)
        d20, d21 = (v2 * v0).sum(1), (v2 * v1).sum(1)
        den = d00 * d11 - d01 * d01
        v = (d11 * d20 - d01 * d21) / den
        w = (d00 * d21 - d01 * d20) / den
        u = 1 - v - w
        nl = u[:, None] * cn[corners[:, 0]] + v[:, None] * cn[corners[:, 1]] + w[:, None] * cn[corners[:, 2]]
        nw = nl @ info.inv[:3, :3]          # inverse-transpose
        nrm[sel] = nw / np.linalg.norm(nw, axis=1)[:, None]
    return dist, nrm, obj


def info_mat_t(info):
    return np.linalg.inv(info.inv)[:3, 3]


def m_bvhobj(scene):
    """BVHTree.FromObject per object (local space), rays transformed per object, 4 casts per pixel."""
    origin, d = rays(scene)
    dg = bpy.context.evaluated_depsgraph_get()
    best = np.full(len(d), np.inf)
    nrm = np.zeros((len(d), 3))
    obj = np.zeros(len(d), int)
    for ob in scene.objects:
        if ob.type != "MESH":
            continue
        tree = BVHTree.FromObject(ob, dg)
        mw = np.array(ob.matrix_world)
        inv = np.linalg.inv(mw)
        ol = Vector(inv[:3, :3] @ origin + inv[:3, 3])
        dl = d @ inv[:3, :3].T
        rc = tree.ray_cast
        locs = np.full((len(d), 3), np.nan)
        nn = np.zeros((len(d), 3))
        for i, di in enumerate(dl.tolist()):
            l, n_, idx, _ = rc(ol, di)
            if l is not None:
                locs[i] = l
                nn[i] = n_
        wl = locs @ mw[:3, :3].T + mw[:3, 3]
        dist = np.linalg.norm(wl - origin, axis=1)
        closer = np.isfinite(dist) & (dist < best)
        best[closer] = dist[closer]
        nw = nn[closer] @ inv[:3, :3]
        nrm[closer] = nw / np.linalg.norm(nw, axis=1)[:, None]
        obj[closer] = ob.pass_index
    return best, nrm, obj


def cycles_setup(scene, override):
    vl = scene.view_layers[0]
    vl.use_pass_z = vl.use_pass_normal = vl.use_pass_position = True
    vl.use_pass_object_index = vl.use_pass_material_index = True
    scene.cycles.samples = 1
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.pixel_filter_type = "GAUSSIAN"
    scene.cycles.filter_width = 0.01
    scene.cycles.max_bounces = 0
    scene.render.use_compositing = False
    scene.render.use_sequencer = False
    im = scene.render.image_settings
    im.media_type = "MULTI_LAYER_IMAGE"
    im.file_format = "OPEN_EXR_MULTILAYER"
    im.color_depth = "32"
    im.exr_codec = "NONE"
    scene.render.filepath = OUT + "/passes.exr"
    if override:
        mat = bpy.data.materials.get("Flat") or bpy.data.materials.new("Flat")
        nt = mat.node_tree
        for nd in list(nt.nodes):
            nt.nodes.remove(nd)
        em = nt.nodes.new("ShaderNodeEmission")
        outn = nt.nodes.new("ShaderNodeOutputMaterial")
        nt.links.new(em.outputs[0], outn.inputs[0])
        vl.material_override = mat
    else:
        vl.material_override = None


def cycles_undo(scene):
    vl = scene.view_layers[0]
    vl.use_pass_z = vl.use_pass_normal = vl.use_pass_position = False
    vl.use_pass_object_index = vl.use_pass_material_index = False
    vl.material_override = None
    scene.cycles.samples = 16
    scene.cycles.pixel_filter_type = "BLACKMAN_HARRIS"
    scene.cycles.filter_width = 1.5
    scene.cycles.max_bounces = 12
    scene.render.use_compositing = True
    scene.render.use_sequencer = True


READER = r"""
import sys, numpy as np
sys.path.append(sys.argv[1])
import OpenImageIO as o
inp = o.ImageInput.open(sys.argv[2]); out = {}; k = 0
while inp.seek_subimage(k, 0):
    s = inp.spec(); a = inp.read_image(k, 0, 0, s.nchannels, "float")
    key = (s.getattribute("name") or str(k)).replace(".", "_")
    out[key] = np.asarray(a, np.float32).reshape(s.height, s.width, s.nchannels)
    k += 1
np.savez(sys.argv[3], **out)
"""


def read_exr(path, inproc):
    if inproc:
        from fog_addon import imageio
        return imageio.read_layers(path)
    from fog_addon import imageio
    sp = str(imageio._bundled_site_packages()[0])
    npz = OUT + "/passes.npz"
    subprocess.run([sys.executable, "-c", READER, sp, path, npz], check=True)
    z = np.load(npz)
    return {k: z[k] for k in z.files}


def m_cycles(scene, inproc, origin):
    bpy.ops.render.render(write_still=True, scene=scene.name)
    layers = read_exr(OUT + "/passes.exr", inproc)
    def get(word):
        for k, v in layers.items():
            if word in k:
                return v[::-1].reshape(-1, v.shape[2])     # bottom row first, as _frame_rays
        raise KeyError(word, list(layers))
    pos = get("Position")[:, :3]
    nrm = get("Normal")[:, :3]
    z = get("Depth")[:, 0]
    obj = np.rint(get("Object Index")[:, 0]).astype(int)
    dist = np.where(obj > 0, np.linalg.norm(pos - origin, axis=1), np.inf)
    return dist, nrm, obj, z, sorted(layers)


def main(n, methods):
    scene, cam = setup(n)
    res = {"lights": n, "pixels": W * H}
    ref = None
    origin, d = rays(scene)
    out = {}
    if "nofog" in methods:
        scene.render.filepath = OUT + "/nofog.exr"
        measure.configure_output(scene, OUT + "/nofog.exr")
        c, w, _ = timed(lambda: bpy.ops.render.render(write_still=True, scene=scene.name))
        res["nofog_render_16spp"] = (c, w)
        print("nofog", c, w, flush=True)
    for name, fn in (("scene_ray_cast", m_scene), ("bvh_combined", m_bvh), ("bvh_per_object", m_bvhobj)):
        key = {"scene_ray_cast": "scene", "bvh_combined": "bvh", "bvh_per_object": "bvhobj"}[name]
        if key not in methods:
            continue
        c, w, r = timed(lambda: fn(scene))
        res[name] = (c, w)
        out[name] = r
        print(name, c, w, flush=True)
    for key, override in (("cycles", True), ("cyclesmat", False)):
        if key not in methods:
            continue
        cycles_setup(scene, override)
        inproc = os.environ.get("INPROC") == "1"
        t0 = os.times()
        c, w, r = timed(lambda: m_cycles(scene, inproc, origin))
        t1 = os.times()
        child = t1.children_user + t1.children_system - t0.children_user - t0.children_system
        res["cycles_reader_child_cpu_per_call_" + key] = child / REPS
        # render alone
        c2, w2, _ = timed(lambda: bpy.ops.render.render(write_still=True, scene=scene.name))
        res["cycles_passes_" + ("override" if override else "materials")] = (c, w)
        res["cycles_render_only_" + ("override" if override else "materials")] = (c2, w2)
        res["layers"] = r[4]
        out["cycles_" + key] = r[:3]
        zs = r[3]
        print(key, c, w, "render only", c2, w2, flush=True)
        cycles_undo(scene)
    # agreement vs analytic hits (exact spheres/plane) and between methods
    c_, dd = many_lights.camera_rays(cam, W, H)
    _, t_an, valid, _ = many_lights.hits(c_, dd)
    t_an = t_an[::-1].reshape(-1)
    valid = valid[::-1].reshape(-1)
    base = out.get("bvh_combined") or next(iter(out.values()), None)
    agree = {}
    for k, r in out.items():
        dist, nrm, obj = r
        both = np.isfinite(dist) & np.isfinite(t_an)
        agree[k] = {"hits": int(np.isfinite(dist).sum()),
                    "miss_mismatch_vs_analytic": int((np.isfinite(dist) != np.isfinite(t_an)).sum()),
                    "max_abs_dist_diff_vs_analytic_valid": float(np.max(np.abs(dist - t_an)[both & valid])),
                    "max_rel_dist_diff_vs_analytic_valid": float(np.max((np.abs(dist - t_an) / t_an)[both & valid]))}
        if base is not None:
            bd, bn, bo = base
            bb = np.isfinite(dist) & np.isfinite(bd)
            agree[k].update({
                "miss_mismatch_vs_bvh": int((np.isfinite(dist) != np.isfinite(bd)).sum()),
                "max_abs_dist_diff_vs_bvh": float(np.max(np.abs(dist - bd)[bb])),
                "max_rel_dist_diff_vs_bvh": float(np.max((np.abs(dist - bd) / bd)[bb])),
                "p999_rel_dist_diff_vs_bvh": float(np.quantile((np.abs(dist - bd) / bd)[bb], 0.999)),
                "obj_mismatch_vs_bvh": int((obj != bo)[bb].sum()),
                "max_normal_angle_deg_vs_bvh": float(np.degrees(np.arccos(np.clip(
                    np.abs((nrm * bn).sum(1))[bb & (obj == bo)], -1, 1))).max()),
            })
    res["agreement"] = agree
    np.savez(OUT + f"/hits_{n}.npz", **{k + "_" + f: v for k, r in out.items() for f, v in zip("dno", r)})
    print("HITS_JSON " + json.dumps(res), flush=True)


if __name__ == "__main__":
    main(int(sys.argv[1]), sys.argv[2:] or ["nofog", "scene", "bvh", "bvhobj", "cycles", "cyclesmat"])
