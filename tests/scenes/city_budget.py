"""The city at night's budgets (tests/test_city_night.py): demo_scenes/city_night.py with N lamps, the fog added with
the defaults at a Quality, then optionally rendered, and what the budgets did printed as one JSON line.

    python tests/scenes/city_budget.py OUT_DIR LAMPS QUALITY WIDTHxHEIGHT RENDER [SETS]

RENDER: 0 (add the fog only) or 1 (Cycles at 1 spp: no fog, then fog, the pictures saved as OUT_DIR/city_nofog.exr
and city_fog.exr); SETS: 0 to build the fog group without sets of bundles (``comp_bundles.SET_SIZE`` made too large
to use), as it is up to 64 lights (default 1).

The JSON: each lamp's distance to the camera (m, by name), the shadow maps' grids (by lamp name), the choice's
shadows account and error, the notes, the panel's lines of what the predicted error counts, and the process's peak resident memory (GB, ``ru_maxrss``) after the scene
(and its fog-free render), after Add Fog and after the fog's render.
"""
import json
import pathlib
import resource
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import bpy  # noqa: E402

from demo_scenes import city_night  # noqa: E402
from fog_addon import measure, shadow_maps  # noqa: E402
from fog_addon.nodes import comp_bundles  # noqa: E402
from fog_addon.ops import apply  # noqa: E402
from fog_addon.precompute.core.spec import FogSpec  # noqa: E402


def rss_gb():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6


def main(out, lamps, quality, size, render, sets=1):
    out = pathlib.Path(out)
    out.mkdir(parents=True, exist_ok=True)
    if not int(sets):
        comp_bundles.SET_SIZE = 1 << 30
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = city_night.build(bpy.context.scene, int(lamps))
    w, h = (int(v) for v in size.split("x"))
    measure.set_resolution(scene, w, h)
    measure.set_samples(scene, 1)
    measure.set_cycles_cpu(scene)
    scene.cycles.use_denoising = False
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    res = {}
    if int(render):
        bpy.ops.render.render()
        bpy.data.images["Render Result"].save_render(str(out / "city_nofog.exr"), scene=scene)
    res["rss_scene_gb"] = rss_gb()
    quality = float(quality) if quality[0].isdigit() else quality
    notes = apply.apply(scene, FogSpec(density=city_night.DEFAULT_DENSITY, quality=quality))
    res["rss_apply_gb"] = rss_gb()
    eye = scene.camera.matrix_world.translation
    res["distances"] = {o.name: (o.matrix_world.translation - eye).length for o in scene.objects if o.type == "LIGHT"}
    res["maps"] = {img.name[len(shadow_maps.IMAGE_PREFIX):]: list(img.size) for img in bpy.data.images
                   if img.name.startswith(shadow_maps.IMAGE_PREFIX)}
    choice = apply.stored_choice() or {}
    res["shadows"] = choice.get("shadows")
    res["error"] = choice.get("error")
    res["notes"] = [f"{a}: {b}" for a, b in notes]
    res["panel"] = apply.left_out_lines(choice)   # the panel's lines of what the predicted error counts
    if int(render):
        bpy.ops.render.render()
        bpy.data.images["Render Result"].save_render(str(out / "city_fog.exr"), scene=scene)
        res["rss_fog_gb"] = rss_gb()
    print(json.dumps(res))
    return 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:]))
