"""Shared by the farm scripts (farm_build.py WITH the add-on, farm_render.py WITHOUT it).

Imports nothing from ``fog_addon`` (farm_render.py must run where the add-on is not
importable), only bpy.  The render settings are written here once so that both
processes render with exactly the same ones.
"""
import json
import os
import sys

import bpy

# Cycles: tiny, few samples, pixel centres (Gaussian 0.01 px, as fog_addon.measure), no denoiser, seed 0.
CYCLES_RES = (48, 27)
CYCLES_SPP = 4
# EEVEE: one TAA sample at 32x18 (about 10-30 s on llvmpipe, mostly shader compilation).
EEVEE_RES = (32, 18)
EEVEE_SPP = 1
EEVEE_LIGHT_THRESHOLD = 1e-4   # as fog_addon.render: EEVEE's default 0.01 windows point lights

ANIM_FRAMES = (1, 5, 10)


def render_settings(scene, engine):
    """Engine, resolution, samples, filter and seed for a farm test render."""
    r = scene.render
    r.engine = engine
    res = CYCLES_RES if engine == "CYCLES" else EEVEE_RES
    r.resolution_x, r.resolution_y = res
    r.resolution_percentage = 100
    r.pixel_aspect_x = r.pixel_aspect_y = 1.0
    r.use_border = False
    r.threads_mode = "AUTO"
    r.filter_size = 0.0
    r.film_transparent = False
    c = scene.cycles
    c.device = "CPU"
    c.samples = CYCLES_SPP
    c.use_adaptive_sampling = False
    c.pixel_filter_type = "GAUSSIAN"
    c.filter_width = 0.01
    c.use_denoising = False
    c.seed = 0
    c.use_animated_seed = False
    scene.eevee.taa_render_samples = EEVEE_SPP
    scene.eevee.light_threshold = EEVEE_LIGHT_THRESHOLD


def render_exr(scene, out):
    """Render ``scene`` to a 32-bit float RGBA EXR at ``out``."""
    im = scene.render.image_settings
    im.media_type = "IMAGE"
    im.file_format = "OPEN_EXR"
    im.color_depth = "32"
    im.exr_codec = "ZIP"
    im.color_mode = "RGBA"
    scene.render.filepath = os.path.abspath(out)
    scene.render.use_file_extension = False
    bpy.ops.render.render(write_still=True, scene=scene.name)
    if not os.path.isfile(out):
        raise RuntimeError(f"render finished but {out} was not written")
    return out


def driver_report():
    """Every driver in the file: (owner, data path, index, type, is_valid, is_simple_expression)."""
    owners = []
    for coll in (bpy.data.node_groups, bpy.data.objects, bpy.data.scenes, bpy.data.lights,
                 bpy.data.cameras, bpy.data.materials, bpy.data.worlds):
        for idb in coll:
            owners.append((f"{type(idb).__name__}:{idb.name}", idb))
            tree = getattr(idb, "node_tree", None)
            if tree is not None and coll is not bpy.data.node_groups:
                owners.append((f"{type(idb).__name__}:{idb.name}/node_tree", tree))
    out = []
    for label, idb in owners:
        ad = idb.animation_data
        if ad is None:
            continue
        for fc in ad.drivers:
            d = fc.driver
            out.append({"owner": label, "path": fc.data_path, "index": fc.array_index, "type": d.type,
                        "valid": bool(d.is_valid), "simple": bool(d.is_simple_expression) if d.type == "SCRIPTED"
                        else None, "expression": d.expression if d.type == "SCRIPTED" else None})
    return out


def emit(result):
    """Print the one JSON line the test reads (last line of stdout)."""
    sys.stdout.flush()
    print(json.dumps(result))
    sys.stdout.flush()
