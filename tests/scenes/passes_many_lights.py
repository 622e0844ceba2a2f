"""The fog passes with many lights: one tiny Cycles render whose Combined is the fog's light alone.

    python tests/scenes/passes_many_lights.py OUT_DIR N_LIGHTS [WITH_PASSES [SVM_LOG]]

``N_LIGHTS`` point lights (radius 0, different powers and colours) on a grid
3.5 m above a ground plane with a glossy sphere, the camera looking along the
ground with the sky above the horizon; every light fully modelled (Quality
Exact).  The lights light only the fog (Cycles: no diffuse or glossy ray
visibility), no bounces and camera rays see the fog instead of the World, so
Combined is the fog's light alone and the Fog Light pass must equal it.
Cycles 64x36, 1 sample at each pixel centre.  ``WITH_PASSES`` (default 1): 0
renders without the passes (for timing the passes' cost).  ``SVM_LOG`` 1: turn
on Cycles' debug log (``cycles_debug_log.py``), whose compilation summary gives
each shader's peak SVM stack use.

Writes OUT_DIR/passes_many_<N>.exr (multilayer: Combined, Fog Light, Fog
Transmittance) and prints one JSON line: the times (fog added, render), per
class of pixel ("sky", "ground", "sphere") the pixel count, and whether the
debug log is on.  The class map is OUT_DIR/passes_many_<N>_classes.npy (0 sky,
1 ground, 2 sphere).
"""
import json
import pathlib
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import bpy  # noqa: E402
import numpy as np  # noqa: E402

from fog_scenes import cycles_debug_log  # noqa: E402
from fog_addon.ops import apply  # noqa: E402
from fog_scenes.probe_common import add_point_lights, camera_rays, look_at, tiny_render  # noqa: E402

W, H = 64, 36
BETA = 0.05
TOTAL_POWER = 6000.0
CAMERA = ((0.0, -12.0, 2.0), (0.0, 4.0, 2.5), 28.0)   # location, target, lens (mm, sensor 36 mm)
GROUND = 40.0          # half size, m
SPHERE = ((1.5, 2.0, 1.0), 1.0)
COLOURS = ((1.0, 0.62, 0.25), (1.0, 1.0, 1.0), (0.75, 0.85, 1.0), (1.0, 0.85, 0.6))


def lights(n):
    """[(location, power, colour)] of ``n`` lights on a grid 3.5 m up, 8 per row, deterministic."""
    out = []
    for k in range(n):
        i, j = k % 8, k // 8
        where = (-10.0 + 20.0 * (i + 0.5) / 8, -4.0 + 3.0 * j, 3.5)
        out.append((where, TOTAL_POWER / n * (0.4 + 1.2 * ((k * 7) % 11) / 10.0), COLOURS[k % len(COLOURS)]))
    return out


def _material(name, base, roughness):
    mat = bpy.data.materials.new(name)
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*base, 1.0)
    bsdf.inputs["Roughness"].default_value = roughness
    return mat


def build(n):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    s = bpy.context.scene
    cam = look_at(s, *CAMERA)
    add_point_lights(s, lights(n))   # the lights light the fog only
    bpy.ops.mesh.primitive_plane_add(size=2 * GROUND)
    bpy.context.object.data.materials.append(_material("ground", (0.35, 0.35, 0.35), 0.8))
    bpy.ops.mesh.primitive_uv_sphere_add(radius=SPHERE[1], location=SPHERE[0], segments=32, ring_count=16)
    bpy.ops.object.shade_smooth()
    bpy.context.object.data.materials.append(_material("sphere", (0.2, 0.4, 0.8), 0.2))
    s.world = bpy.data.worlds.new("W")
    s.world.node_tree.nodes["Background"].inputs["Color"].default_value = (0, 0, 0, 1)
    tiny_render(s, "CYCLES", W, H)
    return s, cam


def classes(cam):
    """Per pixel: 0 sky, 1 ground, 2 sphere (exact ray casts; the sphere's mesh edge is left as it falls)."""
    c, d = camera_rays(cam, W, H)
    out = np.zeros((H, W), int)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(d[..., 2] < 0, -c[2] / d[..., 2], np.inf)
    p = c + d * np.where(np.isfinite(t), t, 0.0)[..., None]
    ground = np.isfinite(t) & np.all(np.abs(p[..., :2]) <= GROUND, axis=-1)
    out[ground] = 1
    oc = c - np.asarray(SPHERE[0])
    b = d @ oc
    out[b * b - (oc @ oc - SPHERE[1] ** 2) > 0] = 2
    return out


def main(out_dir, n, with_passes="1", svm_log="0"):
    out_dir, n = pathlib.Path(out_dir), int(n)
    svm_log = svm_log == "1" and cycles_debug_log.enable()
    s, cam = build(n)
    t0 = time.perf_counter()
    apply.apply_fog(s, BETA, with_passes=with_passes == "1", error=None)
    t_apply = time.perf_counter() - t0
    tiny_render(s, "CYCLES", W, H)   # again: the fog may have set up its own compositor
    im = s.render.image_settings
    im.media_type = "MULTI_LAYER_IMAGE"
    im.file_format = "OPEN_EXR_MULTILAYER"
    im.color_depth = "32"
    s.render.filepath = str(out_dir / f"passes_many_{n}.exr")
    s.render.use_file_extension = False
    t0 = time.perf_counter()
    bpy.ops.render.render(write_still=True, scene=s.name)
    t_render = time.perf_counter() - t0
    cls = classes(cam)
    np.save(out_dir / f"passes_many_{n}_classes.npy", cls)
    print(json.dumps({"lights": n, "passes": with_passes == "1", "apply_s": round(t_apply, 2),
                      "render_s": round(t_render, 2), "svm_log": svm_log,
                      "pixels": {k: int((cls == i).sum()) for i, k in enumerate(("sky", "ground", "sphere"))}}),
          flush=True)


if __name__ == "__main__":
    main(*sys.argv[1:])
