"""Tiny render of airlight over a black plane and the background; prints per-pixel
ratios to the numpy model (fog_addon.precompute.physics.point.airlight.airlight) as JSON.

    python tests/scenes/airlight_probe.py OUT_DIR [ENGINE [METHOD]]

METHOD "nodes" (default) is compared with the table model, "osl" with the
quadrature model; both are also compared with the other one ("other_*").
"""
import json
import math
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import bpy  # noqa: E402
import numpy as np  # noqa: E402

from fog_addon import imageio, measure  # noqa: E402
from fog_addon.ops import apply  # noqa: E402
from fog_addon.precompute.physics.point import airlight  # noqa: E402
from fog_scenes import probe_common  # noqa: E402

BETA, POWER, W, H = 0.2, 1000.0, 64, 48


def main(out_dir, engine="CYCLES", method="nodes"):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    s = bpy.context.scene
    cam = bpy.data.objects.new("cam", bpy.data.cameras.new("cam"))
    s.collection.objects.link(cam)
    s.camera = cam
    cam.location = (0, -6, 1)
    cam.rotation_euler = (math.radians(90), 0, 0)
    cam.data.clip_start = 0.001
    cam.data.lens = 35.0
    light = bpy.data.objects.new("L", bpy.data.lights.new("L", "POINT"))
    light.data.energy = POWER
    light.data.shadow_soft_size = 0
    s.collection.objects.link(light)
    light.location = (0.5, 0, 1.2)
    bpy.ops.mesh.primitive_plane_add(size=20, location=(0, 0, 0))
    mat = bpy.data.materials.new("black")
    bpy.context.object.data.materials.append(mat)
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (0, 0, 0, 1)
    bsdf.inputs["Specular IOR Level"].default_value = 0
    s.world = bpy.data.worlds.new("W")
    s.world.node_tree.nodes["Background"].inputs["Color"].default_value = (0, 0, 0, 1)
    apply.apply_fog(s, BETA, method=method)
    probe_common.tiny_render(s, engine, W, H)
    out = measure.render_to_file(s, str(pathlib.Path(out_dir) / "probe.exr"))
    got = imageio.read_rgb(out)[..., 0]
    c, d = probe_common.camera_rays(cam, W, H)
    lp = np.array(light.location)
    to = lp - c
    gamma = np.arccos(np.clip(d @ to / np.linalg.norm(to), -1, 1))
    t = np.where(d[..., 2] < 0, -c[2] / np.minimum(d[..., 2], -1e-12), np.inf)
    hit = c[:2] + d[..., :2] * np.where(np.isfinite(t), t, 0)[..., None]
    d_vp = np.where(np.all(np.abs(hit) <= 10.0, axis=-1), t, np.inf)   # the plane is 20 m wide
    scale = POWER / (4 * math.pi)
    want = scale * airlight.airlight(BETA, np.linalg.norm(to), d_vp, gamma, quadrature=method == "osl")
    other = scale * airlight.airlight(BETA, np.linalg.norm(to), d_vp, gamma, quadrature=method != "osl")
    r, ro = got / want, got / other
    bg = np.isinf(d_vp)
    print(json.dumps({"median": float(np.median(r)), "max_dev": float(np.max(np.abs(r - 1))),
                      "p99_dev": float(np.percentile(np.abs(r - 1), 99)),
                      "other_median": float(np.median(ro)), "other_max_dev": float(np.max(np.abs(ro - 1))),
                      "background_pixels": int(bg.sum()), "surface_pixels": int((~bg).sum())}))


if __name__ == "__main__":
    main(*sys.argv[1:])
