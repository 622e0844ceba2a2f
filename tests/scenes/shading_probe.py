"""Tiny render of the whole fog on a lit plane and the background, against its numpy twin, per pixel.

    python tests/scenes/shading_probe.py OUT_DIR ENGINE METHOD CASE [G] [KIND]

The lights are kept out of the surfaces' direct lighting (Cycles: light ray
visibility; EEVEE: diffuse and specular factors 0) and the world is black, so
each pixel is exactly the fog's emission: the glow of two lights of different
colours plus the fog light the plane reflects (Sun et al. 2005 Eq. 19).  The
twin is ``precompute.model.shading`` run by numpy at each pixel centre's camera
ray, with the models METHOD chooses.  CASE "principled" is a diffuse-and-glossy dielectric; "mirror" is a
smooth metal (roughness 0: only the glossy fog light, Phong n = 1024).  G: the fog's
Henyey-Greenstein anisotropy (default 0), the twin's models and tables baked for it.  KIND "spot": the
lights are spots (``SPOTS``: cones of 40 and 70 degrees aimed across the plane, one scaled non-uniformly),
their cones' rows from the inverse of the light's world matrix in numpy.

Prints JSON: ratio statistics over all pixels, and for the glossy term alone
(render minus the twin's other terms, against the twin's glossy term) where
it is at least 5 % of the pixel.
"""
import json
import math
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import bpy  # noqa: E402
import numpy as np  # noqa: E402
from mathutils import Vector  # noqa: E402

from fog_addon import imageio, measure  # noqa: E402
from fog_addon.ops import apply  # noqa: E402
from fog_addon.precompute.model import bakers  # noqa: E402
from fog_addon.precompute.model import rungs, shading  # noqa: E402
from fog_addon.precompute.physics.point import surface  # noqa: E402
from fog_addon.precompute.core.medium import Medium  # noqa: E402
from fog_addon.precompute.core.ops import NumpyOps  # noqa: E402
from fog_scenes import probe_common  # noqa: E402

BETA, W, H = 0.2, 64, 48
ALBEDO = (0.9, 0.8, 0.7)
LIGHTS = (((0.5, 1.5, 0.6), 600.0, (1.0, 0.8, 0.6)), ((-2.0, 4.0, 1.0), 1500.0, (0.5, 0.7, 1.0)))
SPOTS = ((40.0, 0.3, (0.3, 2.0, 0.0), (1.0, 1.0, 1.0)), (70.0, 0.8, (-0.5, 1.0, 0.0), (1.0, 0.6, 1.4)))
#        (size in degrees, blend, target, object scale) for LIGHTS' two lights with KIND "spot"
CASES = {"principled": dict(base=(0.6, 0.5, 0.4), metallic=0.3, roughness=0.35, ior_level=0.5),
         "mirror": dict(base=(0.9, 0.85, 0.8), metallic=1.0, roughness=0.0, ior_level=0.5)}


def build(engine, method, case, g=0.0, kind="point"):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    s = bpy.context.scene
    cam = bpy.data.objects.new("cam", bpy.data.cameras.new("cam"))
    s.collection.objects.link(cam)
    s.camera = cam
    cam.location = (0, -5, 2.5)
    cam.rotation_euler = (math.radians(65), 0, 0)
    cam.data.clip_start = 0.001
    cam.data.lens = 30.0
    for k, (loc, power, colour) in enumerate(LIGHTS):
        ob = bpy.data.objects.new(f"L{k}", bpy.data.lights.new(f"L{k}", kind.upper()))
        ob.data.energy, ob.data.color, ob.data.shadow_soft_size = power, colour, 0.0
        ob.data.diffuse_factor = ob.data.specular_factor = 0.0   # EEVEE: no direct light on surfaces
        ob.visible_diffuse = ob.visible_glossy = False           # Cycles: the same
        ob.location = loc
        if kind == "spot":
            size, blend, target, scale = SPOTS[k]
            ob.data.spot_size, ob.data.spot_blend = math.radians(size), blend
            ob.rotation_euler = (Vector(target) - Vector(loc)).to_track_quat("-Z", "Y").to_euler()
            ob.scale = scale
        s.collection.objects.link(ob)
    bpy.ops.mesh.primitive_plane_add(size=40, location=(0, 0, 0))
    mat = bpy.data.materials.new("probe")
    bpy.context.object.data.materials.append(mat)
    c = CASES[case]
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*c["base"], 1)
    bsdf.inputs["Metallic"].default_value = c["metallic"]
    bsdf.inputs["Roughness"].default_value = c["roughness"]
    bsdf.inputs["Specular IOR Level"].default_value = c["ior_level"]
    s.world = bpy.data.worlds.new("W")
    s.world.node_tree.nodes["Background"].inputs["Color"].default_value = (0, 0, 0, 1)
    apply.apply_fog(s, BETA, albedo=ALBEDO, method=method, anisotropy=g, error=None)   # Exact: the twin's models
    probe_common.tiny_render(s, engine, W, H)
    return s, cam


def twin(c, d, case, method, without=None, g=0.0, spots=None):
    """The numpy twin of the fog's emission per pixel; ``without`` "glossy": that term zeroed; ``spots``:
    a shading.Spot per light (None: point lights)."""
    m = NumpyOps(bakers.numpy_tables(g))
    p = CASES[case]
    rho_d, rho_s, level = surface.principled_to_phong(
        m, np.asarray(p["base"], float), np.asarray(p["metallic"]), np.asarray(p["roughness"]),
        np.asarray(p["ior_level"]), -d[..., 2])   # the plane's normal is +Z
    if without == "glossy":
        rho_s = 0.0 * rho_s
    t = np.where(d[..., 2] < 0, -c[2] / np.minimum(d[..., 2], -1e-12), np.inf)
    hit = np.isfinite(t) & np.all(np.abs(c[:2] + d[..., :2] * np.where(np.isfinite(t), t, 0)[..., None]) <= 20, -1)
    t = np.where(hit, t, 1.0)
    geo = shading.Geometry(c, c + d * t[..., None], -d, t, np.array([0.0, 0.0, 1.0]))
    material = shading.Material(rho_d, rho_s, level)
    med = Medium(BETA, np.asarray(ALBEDO))
    models = rungs.choose(method, 0, g, "spot" if spots is not None else "point")
    lights = [shading.Light(np.asarray(loc, float), power / (4 * math.pi) * np.asarray(col),
                            None if spots is None else spots[k]) for k, (loc, power, col) in enumerate(LIGHTS)]
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        terms = [shading.shade_point(m, geo, material, li, med, models) for li in lights]
        surf = shading.shade_surface(m, terms, med, t, 1.0).emission
        bg = shading.shade_background(m, [shading.background_point(m, c, d, li, med, models) for li in lights],
                                      med, 1.0)[0]
    return np.where(hit[..., None], surf, bg), hit


def main(out_dir, engine="CYCLES", method="nodes", case="principled", g="0", kind="point"):
    g = float(g)
    s, cam = build(engine, method, case, g, kind)
    got = imageio.read_rgb(measure.render_to_file(s, str(pathlib.Path(out_dir) / "probe.exr")))
    c, d = probe_common.camera_rays(cam, W, H)
    spots = None
    if kind == "spot":
        spots = [shading.Spot(tuple(np.linalg.inv(np.array(ob.matrix_world.to_3x3()))), math.cos(ob.data.spot_size / 2),
                              ob.data.spot_blend) for ob in (s.objects["L0"], s.objects["L1"])]
    want, hit = twin(c, d, case, method, g=g, spots=spots)
    lit = want > 1e-9 * want.max()   # spots light part of the view: the rest must stay black
    r = got[lit] / want[lit]
    res = {"median": float(np.median(r)), "max_dev": float(np.max(np.abs(r - 1))),
           "p99_dev": float(np.percentile(np.abs(r - 1), 99)),
           "dark_max": float(np.abs(got[~lit]).max(initial=0.0) / want.max()),   # relative to the peak
           # above 1e-3 of the peak (EEVEE's half floats resolve 6e-8 near 0: the spots' faint rims)
           "bright_max_dev": float(np.max(np.abs(got / want - 1)[want >= 1e-3 * want.max()])),
           "surface_pixels": int(hit.sum()), "background_pixels": int((~hit).sum())}
    rest, _ = twin(c, d, case, method, without="glossy", g=g, spots=spots)
    np.save(pathlib.Path(out_dir) / "twin.npy", want)
    glossy = want - rest
    big = hit[..., None] & (glossy > 0.05 * want)
    g_err = np.abs((got - rest)[big] / glossy[big] - 1)
    res.update({"glossy_pixels": int(big[..., 0].sum()), "glossy_share_max": float(np.max(glossy[lit] / want[lit])),
                "glossy_median_dev": float(np.median(g_err)) if g_err.size else None,
                "glossy_p99_dev": float(np.percentile(g_err, 99)) if g_err.size else None,
                "glossy_max_dev": float(np.max(g_err)) if g_err.size else None})
    print(json.dumps(res))


if __name__ == "__main__":
    main(*sys.argv[1:])
