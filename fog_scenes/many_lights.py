"""Many point lights: a tiny render of the whole fog against its numpy twin, per pixel.

    python -m fog_scenes.many_lights OUT_DIR ENGINE METHOD N_LIGHTS [SAMPLES]   (from the repository root)

ENGINE: CYCLES | BLENDER_EEVEE; METHOD: nodes | osl; N_LIGHTS: a square
number (1, 4, 16, 64, 256) of point lights (radius 0, different powers and
colours) on a grid 3.5 m above a ground plane with three spheres: matte
(Principled roughness 0.9), glossy (dielectric roughness 0.2) and metallic
(metallic 1, roughness 0.3); the ground is a rough dielectric.

The lights are kept out of the surfaces' direct lighting (Cycles: light ray
visibility; EEVEE: diffuse and specular factors 0), the world is black and
there are no bounces, so each pixel is exactly the fog's emission: the glow
of every light plus the fog light each surface reflects (Sun et al. 2005
Eq. 19).  The twin is ``precompute.model.shading`` run by numpy at each pixel
centre's camera ray (ray-plane / ray-sphere), with each light's models as the
add-on chose them (METHOD and its stored steps) -- as tests/scenes/shading_probe.py,
for four surfaces and N lights.
A material that renders black (shader too big for SVM, a GLSL compile or
uniform-buffer failure, ...) shows as a ratio render / twin near 0 on its
object's pixels.

Prints one line ``MANY_LIGHTS_JSON {...}``: the times (fog added, first
render), and per object (and "background") the pixel count, the median,
min and max of render / twin and the relative RMSE, plus the relative RMSE
over every pixel compared.  Pixels within 4 % of a sphere's silhouette or
1 m of the ground's edge are not compared (the mesh is not the twin's exact
sphere / plane there).
"""
import json
import math
import pathlib
import sys
import time

import bpy
import numpy as np

from fog_addon import imageio, measure
from fog_addon import view
from fog_addon.ops import apply
from fog_addon.precompute.model import bakers
from fog_addon.precompute.model import predict, rungs, shading
from fog_addon.precompute.physics.point import model, surface
from fog_addon.precompute.core.medium import Medium
from fog_addon.precompute.core.ops import NumpyOps
from fog_scenes.probe_common import add_point_lights, camera_rays, look_at, tiny_render

BETA = 0.1                      # 1/m: optical thickness ~1.2 to the spheres, ~2 to the far lights
ALBEDO = (0.9, 0.9, 0.85)
W, H = 48, 27
TOTAL_POWER = 6000.0            # W, shared by the lights (the picture's brightness does not grow with N)
LIGHT_HEIGHT = 3.5
GRID_X = (-8.0, 8.0)            # the lights' grid, m
GRID_Y = (-4.0, 12.0)
GROUND = (-30.0, 30.0, -20.0, 40.0)   # x0, x1, y0, y1 at z = 0
CAMERA = ((0.0, -11.0, 3.0), (0.0, 2.0, 0.8), 30.0)   # location, target, lens (mm; sensor 36 mm)
COLOURS = ((1.0, 0.62, 0.25),   # sodium
           (1.0, 1.0, 1.0),     # white LED
           (0.75, 0.85, 1.0),   # cold LED
           (1.0, 0.85, 0.6))    # warm white
# name: (base colour, roughness, metallic, specular IOR level); spheres: (centre, radius)
MATERIALS = {"ground": ((0.35, 0.35, 0.35), 0.8, 0.0, 0.5),
             "matte": ((0.8, 0.3, 0.2), 0.9, 0.0, 0.5),
             "glossy": ((0.2, 0.4, 0.8), 0.2, 0.0, 0.5),
             "metal": ((0.9, 0.7, 0.4), 0.3, 1.0, 0.5)}
SPHERES = {"matte": ((-2.8, 0.0, 1.2), 1.2), "glossy": ((0.0, 0.0, 1.2), 1.2), "metal": ((2.8, 0.0, 1.2), 1.2)}
SILHOUETTE_MARGIN = 0.04        # of the radius
EDGE_MARGIN = 1.0               # m


def lights(n):
    """[(location, power W, colour)] of ``n`` (a square) lights on the grid, deterministic."""
    k = math.isqrt(n)
    if k * k != n:
        raise ValueError(f"N_LIGHTS must be a square number, got {n}")
    out = []
    for j in range(k):
        for i in range(k):
            idx = j * k + i
            x = GRID_X[0] + (GRID_X[1] - GRID_X[0]) * (i + 0.5) / k
            y = GRID_Y[0] + (GRID_Y[1] - GRID_Y[0]) * (j + 0.5) / k
            power = TOTAL_POWER / n * (0.4 + 1.2 * ((idx * 7) % 11) / 10.0)   # 0.4 ... 1.6 x the mean
            out.append(((x, y, LIGHT_HEIGHT), power, COLOURS[idx % len(COLOURS)]))
    return out


def _material(name):
    base, rough, metal, level = MATERIALS[name]
    mat = bpy.data.materials.new(name)
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*base, 1.0)
    bsdf.inputs["Roughness"].default_value = rough
    bsdf.inputs["Metallic"].default_value = metal
    bsdf.inputs["Specular IOR Level"].default_value = level
    return mat


def build_scene(n, direct_light=False):
    """A fresh file with the ground, the spheres, ``n`` lights, the camera and a black world; no fog.

    ``direct_light`` False keeps the lights out of the surfaces' direct lighting (the test: each pixel
    is the fog's emission alone); True is an ordinary scene (benchmarks/overhead.py).
    """
    import bmesh
    bpy.ops.wm.read_factory_settings(use_empty=True)
    s = bpy.context.scene
    cam = look_at(s, *CAMERA)
    add_point_lights(s, lights(n), fog_only=not direct_light)
    x0, x1, y0, y1 = GROUND
    bm = bmesh.new()
    bm.faces.new([bm.verts.new(v) for v in ((x0, y0, 0), (x1, y0, 0), (x1, y1, 0), (x0, y1, 0))])
    mesh = bpy.data.meshes.new("ground")
    bm.to_mesh(mesh)
    bm.free()
    mesh.materials.append(_material("ground"))
    ground = bpy.data.objects.new("ground", mesh)
    s.collection.objects.link(ground)
    for name, (centre, radius) in SPHERES.items():
        bm = bmesh.new()
        bmesh.ops.create_uvsphere(bm, u_segments=64, v_segments=32, radius=radius)
        mesh = bpy.data.meshes.new(name)
        bm.to_mesh(mesh)
        bm.free()
        mesh.shade_smooth()
        mesh.materials.append(_material(name))
        ob = bpy.data.objects.new(name, mesh)
        ob.location = centre
        s.collection.objects.link(ob)
    s.world = bpy.data.worlds.new("W")
    s.world.node_tree.nodes["Background"].inputs["Color"].default_value = (0, 0, 0, 1)
    return s, cam


def build(engine, method, n):
    """The test's scene: fog emission only, 1 spp at pixel centres, no bounces; (scene, camera, seconds to add
    the fog)."""
    s, cam = build_scene(n)
    tiny_render(s, engine, W, H)
    measure.set_cycles_cpu(s)
    t0 = time.perf_counter()
    apply.apply_fog(s, BETA, albedo=ALBEDO, method=method, shafts=False)   # the twin has no shadows
    measure.set_pixel_centre_filter(s)   # again: the fog may set up its own compositor
    return s, cam, time.perf_counter() - t0


def pixel_rays(scene, width, height):
    """A function (i, j, sx, sy) -> the unit directions (..., 3) of the camera rays through pixel (i, j) (from the
    bottom-left) at offsets sx, sy px from its centre (arrays of one shape), for a render of width x height."""
    _, rays = view.frame_rays(scene, scene.camera, (width, height))
    rays = rays.reshape(height, width, 3)
    forward = -np.array(scene.camera.matrix_world.to_3x3().col[2])
    plane = rays / (rays @ forward)[..., None]          # on the plane at unit depth: linear in pixel coords
    origin, ex, ey = plane[0, 0], plane[0, 1] - plane[0, 0], plane[1, 0] - plane[0, 0]

    def through(i, j, sx, sy):
        v = origin + (i + sx)[..., None] * ex + (j + sy)[..., None] * ey
        return v / np.linalg.norm(v, axis=-1, keepdims=True)
    return through


def sky_glow(scene):
    """A function: unit directions (..., 3) of camera rays to the sky -> the fog's light along them (..., 3):
    every fog light's background glow (Sun et al. 2005 Eq. 12; the numpy twin of the full models) times
    ALBEDO.  With ``pixel_rays``, the reference of a pixel's mean under a pixel filter near lights
    (benchmarks/compositor_fog/peaks.py, tests/scenes/eevee_peaks.py)."""
    lights = apply.fog_lights(scene)[0]
    intensity = view.light_intensities(lights)
    positions = np.array([list(o.matrix_world.translation) for o in lights])
    cam = np.array(scene.camera.matrix_world.translation)
    m, full = predict._numpy_ops(0.0), rungs.choose("nodes", 0, 0.0)

    def glow(d):
        d_sv, along, h = model.ray_light_geometry(m, cam, d[..., None, :], positions)
        return (m.run(full.background, BETA, d_sv, along, h)[..., None] * intensity).sum(-2) * np.array(ALBEDO)
    return glow


def hits(c, d):
    """(object index per pixel: 0 background, 1 ground, 2.. spheres; distance; valid mask; names)."""
    names = ["background", "ground"] + list(SPHERES)
    t_best = np.full(d.shape[:2], np.inf)
    obj = np.zeros(d.shape[:2], int)
    valid = np.ones(d.shape[:2], bool)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(d[..., 2] < 0, -c[2] / d[..., 2], np.inf)
        p = c + d * np.where(np.isfinite(t), t, 0)[..., None]
        x0, x1, y0, y1 = GROUND
        inside = (p[..., 0] >= x0) & (p[..., 0] <= x1) & (p[..., 1] >= y0) & (p[..., 1] <= y1) & np.isfinite(t)
        edge_dist = np.minimum.reduce([p[..., 0] - x0, x1 - p[..., 0], p[..., 1] - y0, y1 - p[..., 1]])
        near_edge = np.isfinite(t) & (np.abs(edge_dist) < EDGE_MARGIN)
    t_best = np.where(inside, t, t_best)
    obj[inside] = 1
    valid &= ~near_edge
    for k, (centre, radius) in enumerate(SPHERES.values(), 2):
        oc = c - np.asarray(centre)
        b = np.einsum("ijk,k->ij", d, oc)
        closest = np.sqrt(np.maximum(np.dot(oc, oc) - b * b, 0.0))     # ray's distance from the centre
        disc = b * b - (np.dot(oc, oc) - radius * radius)
        with np.errstate(invalid="ignore"):
            ts = -b - np.sqrt(disc)
        hit = (disc > 0) & (ts > 0) & (ts < t_best)
        t_best = np.where(hit, ts, t_best)
        obj[hit] = k
        edge = np.abs(closest / radius - 1.0) < SILHOUETTE_MARGIN
        valid &= ~(edge & (b < 0))   # a silhouette in front of the camera
    return obj, t_best, valid, names


def twin(c, d, method, n, steps=None):
    """The numpy twin of the fog's emission per pixel, and (object index, valid mask, names).

    ``steps``: each light's step down the ladder (rungs.STEPS) as the add-on chose it; default all full."""
    m = NumpyOps(bakers.numpy_tables(0.0))
    med = Medium(BETA, np.asarray(ALBEDO))
    models = [rungs.choose(method, k) for k in ([0] * n if steps is None else steps)]
    ls = [shading.Light(np.asarray(loc, float), power / (4 * math.pi) * np.asarray(col)) for loc, power, col
          in lights(n)]
    obj, t, valid, names = hits(c, d)
    out = np.zeros(d.shape)
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        for k, name in enumerate(names):
            sel = obj == k
            if not sel.any():
                continue
            dd = d[sel]
            if name == "background":
                out[sel] = shading.shade_background(
                    m, [shading.background_point(m, c, dd, li, med, mod) for li, mod in zip(ls, models)],
                    med, 1.0)[0]
                continue
            tt = t[sel]
            p = c + dd * tt[:, None]
            if name == "ground":
                normal = np.array([0.0, 0.0, 1.0])
            else:
                centre, radius = SPHERES[name]
                normal = (p - np.asarray(centre)) / radius
            base, rough, metal, level = MATERIALS[name]
            rho_d, rho_s, lev = surface.principled_to_phong(m, np.asarray(base, float), np.asarray(metal),
                                                             np.asarray(rough), np.asarray(level),
                                                             np.sum(-dd * np.broadcast_to(normal, dd.shape), -1))
            geo = shading.Geometry(c, p, -dd, tt, normal)
            terms = [shading.shade_point(m, geo, shading.Material(rho_d, rho_s, lev), li, med, mod)
                     for li, mod in zip(ls, models)]
            out[sel] = shading.shade_surface(m, terms, med, tt, 1.0).emission
    return out, obj, valid, names


def stats(got, want, mask):
    if not mask.any():
        return {"pixels": 0}
    g, w = got[mask], want[mask]
    r = np.mean(g, -1) / np.maximum(np.mean(w, -1), 1e-30)
    rel = np.sqrt(np.sum((g - w) ** 2) / max(np.sum(w ** 2), 1e-30))
    return {"pixels": int(mask.sum()), "median_ratio": float(np.median(r)), "min_ratio": float(np.min(r)),
            "max_ratio": float(np.max(r)), "rel_rmse": float(rel), "mean_twin": float(np.mean(w))}


def main(out_dir, engine="CYCLES", method="nodes", n="1", samples="1"):
    n, samples = int(n), int(samples)
    s, cam, t_apply = build(engine, method, n)
    measure.set_samples(s, samples)
    print(f"many_lights: {n} lights, {engine} {method}: fog added in {t_apply:.2f} s", flush=True)
    t0 = time.perf_counter()
    out = measure.render_to_file(s, str(pathlib.Path(out_dir) / f"many_{engine}_{method}_{n}.exr"))
    t_render = time.perf_counter() - t0
    print(f"many_lights: first render {t_render:.2f} s", flush=True)
    got = imageio.read_rgb(out)
    c, d = camera_rays(cam, W, H)
    choice = apply.stored_choice()
    steps = [choice["lights"][f"L{k:03d}"][0] for k in range(n)]
    want, obj, valid, names = twin(c, d, method, n, steps)
    res = {"lights": n, "engine": engine, "method": method, "samples": samples, "apply_s": round(t_apply, 3),
           "render_s": round(t_render, 3), "steps": steps, "predicted_error": choice["error"],
           "limited": choice.get("limited"), "all": stats(got, want, valid),
           "objects": {name: stats(got, want, valid & (obj == k)) for k, name in enumerate(names)}}
    np.save(pathlib.Path(out_dir) / f"twin_{engine}_{method}_{n}.npy", want)
    print("MANY_LIGHTS_JSON " + json.dumps(res), flush=True)


if __name__ == "__main__":
    main(*sys.argv[1:])
