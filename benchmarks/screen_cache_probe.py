"""Evidence for the next many-lights design: a screen-space fog cache, measured against the exact fog.

    .venv/bin/python benchmarks/screen_cache_probe.py exact  SCENE OUT             # default filter 64 spp, pixel centres 1 spp
    .venv/bin/python benchmarks/screen_cache_probe.py cached SCENE OUT SCALE INTERP # cache baked at SCALE x res, INTERP lookup
    .venv/bin/python benchmarks/screen_cache_probe.py time   SCENE OUT KIND [INTERP] # KIND: nofog | exact | cached | cachedbsdf
    .venv/bin/python benchmarks/screen_cache_probe.py compare CACHED.exr EXACT.exr
SCENE: boulevard (45 lamps, beta 0.015) | many16 (tests/scenes/many_lights.py, 16 lights, beta 0.1).
INTERP: Closest | Linear | Matched (distance-matched, below; MATCH_TOL=x changes its 0.02).
(SPP=N in the environment changes the 64 spp of exact/cached.)

Not shipped code: a probe of the design the README's Known limits discuss.  The cache
is one ray per pixel centre (``ops/view.py``) and the shaders' numpy twin
(``predict.light_fog``) summed over the lights, stored in a float image; every
material shows it through an Emission of an Image Texture at the Window coordinate
(Closest or Linear), the World a Background of the same.  ``Matched``: the bake also
stores each centre ray's hit distance in alpha (1e9 for the sky), and the lookup reads
the 3x3 texels around the Window coordinate (offsets of one texel, Closest) and keeps
the centre's fog unless its distance differs from the shading point's (Camera Data View
Distance; 1e9 in the World) by more than 2 %, else takes the texel nearest in distance:
62 nodes per material, whatever the lights.  Pictures are fog only
(``probe_common.light_fog_only``, black World, no bounces), Cycles CPU, 160x90,
one thread, seed 0.  ``compare``: relative error per pixel (max over RGB) over the
pixels >= 1e-3 of the exact picture's peak.

Measured (bpy 5.0.1; benchmarks/out/screen_cache_probe.json):

* pixel centres (Gaussian 0.01 filter, 1 spp): cached = exact (relative RMSE 5.9e-6
  boulevard, 1.7e-6 many16): the bake and the lookup are right;
* Blender's default filter (Blackman-Harris 1.5 px), 64 spp, share of pixels off by
  more than 1 % / max: boulevard 15.0 % / 41 %, many16 4.0 % / 29 % (bias, not noise:
  the same against exact at 256 spp).  Where: thin lamp posts, object and depth edges
  (a filter sample on another surface than its pixel's centre ray) and the glow peaks
  around lamps.  Linear lookups: no better; a bake at 2x / 4x the resolution: boulevard
  10.8 % / 7.5 %, many16 2.1 % / 0.85 %, the worst pixel not better (28 % / 37 %);
* 160x90 at 16 spp, CPU time, fog over no fog: exact 216x (boulevard), 53x (many16);
  the cached render with each material's BSDF dimmed by e^(-beta d) plus the cache
  1.13x / 1.25x; its bake (ray casts 0.6 s, numpy 1.5 s / 1.0 s) brings it to 4.4x /
  5.9x.  The bake grows with pixels x lights;
* distance-matched lookup (``Matched``, bake at 1x): View Distance = the baked ray_cast
  distance at pixel centres (max relative difference 8e-6), so pixel centres stay exact
  (relative RMSE 5.9e-6 / 1.7e-6).  Default filter, 64 spp, > 1 % / > 5 % / > 20 % / max / relative
  RMSE of the image, Closest -> Matched: boulevard 15.0 / 7.3 / 0.80 % / 41 % / 0.074 ->
  10.4 / 2.4 / 0.30 % / 38 % / 0.070; many16 4.0 / 1.1 / 0.05 % / 29 % / 0.063 ->
  2.5 / 0.48 / 0.05 % / 29 % / 0.063.  Left: glow peaks (56 % / 33 % of those pixels still
  > 1 %, the worst pixel hardly better: the fog is convex across the pixel, no texel holds the
  footprint's mean), posts (49 % > 1 %, but 3 % > 5 % against 59 %: a post thinner than a
  pixel has no texel of its own) and edges (27 % / 16 %).  With no tolerance (pick the
  nearest distance always) it is worse: boulevard 15.7 % > 1 %, max 74 % (where the
  neighbours' distances nearly tie a neighbour's fog wins, mostly around glows).
  Matched on a 2x bake: boulevard 4.8 / 0.76 / 0.02 % / 28 %, many16 0.76 / 0.24 / 0.03 % / 25 %.
  Cost, 16 spp, same session: cache + dimmed BSDF over no fog 1.08x / 1.05x with Closest,
  1.55x / 1.81x with Matched (1.4 / 1.1 us more per camera sample).
"""
import json
import math
import os
import sys
import time

import pathlib

ROOT = str(pathlib.Path(__file__).resolve().parents[1])
sys.path.insert(0, ROOT)
sys.path.insert(0, ROOT + "/tests/scenes")

import bpy  # noqa: E402
import numpy as np  # noqa: E402

from fog_addon import imageio, measure  # noqa: E402
from fog_addon.nodes import compositor  # noqa: E402
from fog_addon.ops import apply, view  # noqa: E402
from fog_addon.precompute import predict  # noqa: E402
from probe_common import light_fog_only  # noqa: E402

W, H = 160, 90
SKY = 1e9               # baked distance of a pixel-centre ray that misses (the World's own distance)
MATCH_TOL = float(os.environ.get("MATCH_TOL", 0.02))   # Matched: mismatch (x distance) leaving the centre
LOOKUP_NODES = [0]      # nodes of the last material lookup (Camera Data included)


def build(name):
    if name == "boulevard":
        import demo_scenes
        from demo_scenes import boulevard
        scene = bpy.context.scene
        demo_scenes.clear_scene(scene)
        boulevard.build(scene)
        beta, albedo = 0.015, (1.0, 1.0, 1.0)
    elif name == "many16":
        import many_lights
        scene, _ = many_lights.build_scene(16)
        beta, albedo = many_lights.BETA, many_lights.ALBEDO
    else:
        raise ValueError(name)
    for ob in scene.objects:
        if ob.type == "LIGHT":
            light_fog_only(ob)
    bg = next(n for n in scene.world.node_tree.nodes if n.bl_idname == "ShaderNodeBackground")
    bg.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    scene.render.engine = "CYCLES"
    measure.set_resolution(scene, W, H)
    measure.set_cycles_cpu(scene, threads=1)
    scene.cycles.max_bounces = 0
    scene.cycles.use_denoising = False
    scene.cycles.use_adaptive_sampling = False
    scene.render.use_persistent_data = False
    return scene, beta, albedo


def set_filter(scene, kind, spp):
    compositor.teardown(scene)
    scene.cycles.use_denoising = False
    scene.cycles.samples = spp
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.seed = 0
    if kind == "centre":
        scene.cycles.pixel_filter_type = "GAUSSIAN"
        scene.cycles.filter_width = 0.01
    else:
        scene.cycles.pixel_filter_type = "BLACKMAN_HARRIS"
        scene.cycles.filter_width = 1.5


def render(scene, path):
    measure.render_to_file(scene, path)


def timed_render(scene, path):
    t0, w0 = time.process_time(), time.perf_counter()
    render(scene, path)
    return time.process_time() - t0, time.perf_counter() - w0


def bake(scene, beta, albedo, scale):
    """(image, seconds) with the per-pixel fog at scale x the render resolution."""
    t0 = time.process_time()
    lights, _ = apply.fog_lights(scene)
    gw, gh = W * scale, H * scale
    t1 = time.process_time()
    samples = view.view_samples(scene, lights, grid=(gw, gh))
    t2 = time.process_time()
    if len(samples.distance) != gw * gh:
        raise RuntimeError(f"{len(samples.distance)} samples for {gw}x{gh}: materials not Principled")
    inten = view.light_intensities(lights)
    fog = np.zeros((gw * gh, 3))
    for a in range(0, gw * gh, 20000):      # chunks: (P, N, 3) arrays stay small
        part = predict.ViewSamples(*[None if f is None else f[a:a + 20000] for f in samples])
        glow, scatter = predict.light_fog(part, inten, beta)
        fog[a:a + 20000] = np.asarray(albedo)[None, :] * (glow + scatter).sum(axis=1)   # row 0 = bottom
    t3 = time.process_time()
    rgba = np.ones((gh * gw, 4), np.float32)
    rgba[:, :3] = fog
    rgba[:, 3] = np.where(np.isfinite(samples.distance), samples.distance, SKY)   # for the Matched lookup
    img = bpy.data.images.new("FogCache", gw, gh, alpha=True, float_buffer=True, is_data=True)
    img.colorspace_settings.name = "Non-Color"
    img.alpha_mode = "CHANNEL_PACKED"
    img.use_half_precision = False
    img.pixels.foreach_set(rgba.ravel())
    img.update()
    img.pack()
    t4 = time.process_time()
    return img, {"bake_total": t4 - t0, "ray_casts": t2 - t1, "numpy": t3 - t2, "image": t4 - t3,
                 "lights": len(lights)}


def lookup(tree, img, interp, dist=None):
    """Colour socket of the cache at the Window coordinate.  ``Matched``: of the 3x3 texels
    around it, the one whose baked distance (alpha) is nearest the shading point's ``dist``
    (a socket; None = the sky's SKY); centre first, ties to the earlier tap."""
    if interp == "Matched":
        return lookup_matched(tree, img, dist)
    nodes, links = tree.nodes, tree.links
    tc = nodes.new("ShaderNodeTexCoord")
    tex = nodes.new("ShaderNodeTexImage")
    tex.image, tex.interpolation, tex.extension = img, interp, "EXTEND"
    links.new(tc.outputs["Window"], tex.inputs["Vector"])
    return tex.outputs["Color"]


def lookup_matched(tree, img, dist):
    """Texture Coordinate, 9 taps of 4 nodes (offset, Closest texture, |alpha - dist| as
    subtract + absolute; none for the centre's offset), the centre's tolerance (multiply-add)
    and 3 nodes per other tap to keep the best (less than, colour mix, minimum):
    1 + 35 + 1 + 24 = 61 nodes, 62 with the material's Camera Data."""
    nodes, links = tree.nodes, tree.links
    tc = nodes.new("ShaderNodeTexCoord")
    gw, gh = img.size
    best_col = best_err = None
    for i, j in ((0, 0), (1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (-1, 1), (1, -1), (-1, -1)):
        tex = nodes.new("ShaderNodeTexImage")
        tex.image, tex.interpolation, tex.extension = img, "Closest", "EXTEND"
        if (i, j) == (0, 0):
            links.new(tc.outputs["Window"], tex.inputs["Vector"])
        else:
            off = nodes.new("ShaderNodeVectorMath"); off.operation = "ADD"
            off.inputs[1].default_value = (i / gw, j / gh, 0.0)
            links.new(tc.outputs["Window"], off.inputs[0])
            links.new(off.outputs["Vector"], tex.inputs["Vector"])
        sub = nodes.new("ShaderNodeMath"); sub.operation = "SUBTRACT"
        links.new(tex.outputs["Alpha"], sub.inputs[0])
        if dist is None:
            sub.inputs[1].default_value = SKY
        else:
            links.new(dist, sub.inputs[1])
        err = nodes.new("ShaderNodeMath"); err.operation = "ABSOLUTE"
        links.new(sub.outputs[0], err.inputs[0])
        if best_col is None:      # the centre texel keeps the sample unless it is off by > MATCH_TOL * dist
            keep = nodes.new("ShaderNodeMath"); keep.operation = "MULTIPLY_ADD"
            if dist is None:
                keep.inputs[0].default_value = SKY
            else:
                links.new(dist, keep.inputs[0])
            keep.inputs[1].default_value = -MATCH_TOL
            links.new(err.outputs[0], keep.inputs[2])
            best_col, best_err = tex.outputs["Color"], keep.outputs[0]
            continue
        less = nodes.new("ShaderNodeMath"); less.operation = "LESS_THAN"
        links.new(err.outputs[0], less.inputs[0]); links.new(best_err, less.inputs[1])
        mix = nodes.new("ShaderNodeMix"); mix.data_type = "RGBA"
        links.new(less.outputs[0], mix.inputs[0])
        links.new(best_col, mix.inputs[6]); links.new(tex.outputs["Color"], mix.inputs[7])
        mn = nodes.new("ShaderNodeMath"); mn.operation = "MINIMUM"
        links.new(err.outputs[0], mn.inputs[0]); links.new(best_err, mn.inputs[1])
        best_col, best_err = mix.outputs[2], mn.outputs[0]
    return best_col


def rewire(scene, img, interp, keep_bsdf=False, beta=0.015):
    """Every material: Emission(cache) (keep_bsdf: BSDF * T + Emission(cache)); World: Background(cache)."""
    mats = {s.material for ob in scene.objects for s in getattr(ob, "material_slots", []) if s.material}
    for mat in mats:
        tree = mat.node_tree
        mat.cycles.emission_sampling = "NONE"      # as the add-on does: the fog's emission lights nothing
        out = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial" and n.is_active_output)
        old = out.inputs["Surface"].links[0].from_socket if out.inputs["Surface"].is_linked else None
        em = tree.nodes.new("ShaderNodeEmission")
        dist = tree.nodes.new("ShaderNodeCameraData").outputs["View Distance"] if interp == "Matched" else None
        n0 = len(tree.nodes)
        tree.links.new(lookup(tree, img, interp, dist), em.inputs["Color"])
        LOOKUP_NODES[0] = len(tree.nodes) - n0 + (dist is not None)
        em.inputs["Strength"].default_value = 1.0
        if keep_bsdf and old is not None:
            # BSDF dimmed by the camera-ray transmittance e^(-beta d) (a few nodes), plus the cached fog
            cam = tree.nodes.new("ShaderNodeCameraData")
            mul = tree.nodes.new("ShaderNodeMath"); mul.operation = "MULTIPLY"; mul.inputs[1].default_value = -beta
            ex = tree.nodes.new("ShaderNodeMath"); ex.operation = "EXPONENT"
            tree.links.new(cam.outputs["View Distance"], mul.inputs[0])
            tree.links.new(mul.outputs[0], ex.inputs[0])
            black = tree.nodes.new("ShaderNodeEmission"); black.inputs["Strength"].default_value = 0.0
            mix = tree.nodes.new("ShaderNodeMixShader")
            tree.links.new(ex.outputs[0], mix.inputs["Fac"])
            tree.links.new(black.outputs[0], mix.inputs[1])
            tree.links.new(old, mix.inputs[2])
            add = tree.nodes.new("ShaderNodeAddShader")
            tree.links.new(mix.outputs[0], add.inputs[0])
            tree.links.new(em.outputs[0], add.inputs[1])
            tree.links.new(add.outputs[0], out.inputs["Surface"])
        else:
            tree.links.new(em.outputs[0], out.inputs["Surface"])
    wt = scene.world.node_tree
    scene.world.cycles.sampling_method = "NONE"
    bg = next(n for n in wt.nodes if n.bl_idname == "ShaderNodeBackground")
    wt.links.new(lookup(wt, img, interp), bg.inputs["Color"])
    bg.inputs["Strength"].default_value = 1.0
    return len(mats)


def read(path):
    return np.asarray(imageio.read_rgb(path), float)[..., :3]


def stats(cached, exact, floor=1e-3):
    """Relative error of ``cached`` against ``exact`` per pixel (max over RGB), over pixels >= floor * peak."""
    judged = exact >= floor * exact.max()
    rel = np.abs(cached - exact) / np.where(judged, exact, 1.0)
    per_pixel = np.where(judged, rel, 0.0).max(axis=-1)[judged.any(axis=-1)]
    out = {"rel_rmse_image": float(np.sqrt(((cached - exact) ** 2).mean() / (exact ** 2).mean())),
           "rel_rmse_judged": float(np.sqrt((rel[judged] ** 2).mean())), "judged_frac": float(judged.mean()),
           "max": float(per_pixel.max()), "median": float(np.median(per_pixel)),
           "p99": float(np.percentile(per_pixel, 99))}
    for t in (0.01, 0.05, 0.2):
        out[f">{int(t * 100)}%"] = float((per_pixel > t).mean())
    return out


def centre_and_default(scene, stem):
    """Render at pixel centres (1 spp) and with the default filter (SPP, 64): {name: (cpu s, wall s)}."""
    set_filter(scene, "centre", 1)
    info = {"centre_1": timed_render(scene, f"{stem}_centre.exr")}
    spp = int(os.environ.get("SPP", 64))
    set_filter(scene, "default", spp)
    info[f"default_{spp}"] = timed_render(scene, f"{stem}_default{spp}.exr")
    return info


def main():
    if sys.argv[1] == "compare":
        print(json.dumps(stats(read(sys.argv[2]), read(sys.argv[3])), indent=1))
        return
    mode, name, out = sys.argv[1:4]
    os.makedirs(out, exist_ok=True)
    scene, beta, albedo = build(name)
    info = {"mode": mode, "scene": name}
    if mode == "exact":
        t0 = time.process_time()
        apply.apply_fog(scene, beta, albedo=albedo, error="exact")
        info["apply"] = time.process_time() - t0
        info.update(centre_and_default(scene, f"{out}/exact"))
    elif mode == "cached":
        scale, interp = int(sys.argv[4]), sys.argv[5]
        img, info["bake"] = bake(scene, beta, albedo, scale)
        rewire(scene, img, interp)
        info["lookup_nodes"] = LOOKUP_NODES[0]
        tag = f"s{scale}_{interp}"
        info.update(centre_and_default(scene, f"{out}/cached_{tag}"))
    elif mode == "time":
        kind = sys.argv[4]
        set_filter(scene, "default", 16)
        if kind == "exact":
            t0 = time.process_time()
            apply.apply_fog(scene, beta, albedo=albedo, error="exact")
            info["apply"] = time.process_time() - t0
            set_filter(scene, "default", 16)
        elif kind.startswith("cached"):
            img, info["bake"] = bake(scene, beta, albedo, 1)
            interp = sys.argv[5] if len(sys.argv) > 5 else "Closest"
            rewire(scene, img, interp, keep_bsdf=(kind == "cachedbsdf"), beta=beta)
            info["lookup_nodes"], kind = LOOKUP_NODES[0], f"{kind}_{interp}"
        info["render_16"] = timed_render(scene, f"{out}/time_{kind}.exr")
    print("PROTO_JSON " + json.dumps(info))


if __name__ == "__main__":
    main()
