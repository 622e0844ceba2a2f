"""The Quality's proof scene: one scene fogged at a Quality and at Exact, the Fog Light pass of each written.

    python tests/scenes/quality_probe.py OUT_DIR SCENE QUALITY [METHOD [WIDTH HEIGHT]]

SCENE: a demo scene module name (street_lamps, boulevard, ...) at its default
density (and anisotropy, if it has one), or ``random:SEED`` (a ground, boxes and spheres with random
Principled materials, 2-40 point lights of random power and colour, a random
camera, beta log-uniform in [0.005, 0.3] 1/m), or ``randomspot:SEED``: the same with every other
light a spot (10-120 degrees, blend 0-1) aimed at a random point of the ground, or ``daylit:SEED``: the random
scene in a fog layer DAYLIT_TOP m deep under a sun (DAYLIT_SUN W/m^2, 25 degrees up), whose fog light is in
every pixel's fog (the predictor's ``ViewSamples.other``).  Cycles, 1 sample at each
pixel centre.  The lights light only the fog (hidden from diffuse and
glossy rays: in Cycles their diffuse and specular factors alone still let
them light surfaces) and the World is black, so the picture is the fog's
light alone, without noise and without the Fog Passes' cost.  METHOD: the fog's method (default nodes; with
"compositor" the same models are evaluated once per pixel, at the pixel centre's surface point here).
Light shafts are off: the prediction covers the lights' models, not the shafts' quadrature (its nodes per ray
follow the Quality too; ``apply.explain`` says so, and tests/test_shafts_render.py measures the shafts).

Writes OUT_DIR/auto.exr and OUT_DIR/exact.exr and prints one JSON line: the
predicted error of the choice, the steps, and the scene's lights and beta.
"""
import importlib
import json
import math
import os
import pathlib
import random
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import bpy  # noqa: E402
from mathutils import Vector  # noqa: E402

import demo_scenes  # noqa: E402
from fog_addon.ops import apply  # noqa: E402
from fog_scenes.probe_common import light_fog_only, tiny_render  # noqa: E402


def random_scene(scene, seed, spots=False):
    """A random fogged street-like scene; returns its beta (1/m).  ``spots``: every other light a spot."""
    rng = random.Random(seed)
    demo_scenes.clear_scene(scene)
    demo_scenes.set_world(scene)

    def mat(k):
        return demo_scenes.material(f"M{k}", tuple(rng.uniform(0.05, 0.9) for _ in range(3)),
                                    roughness=rng.uniform(0.05, 1.0), metallic=rng.choice((0.0, 0.0, 1.0)))
    demo_scenes.add_plane(scene, "Ground", -30, 30, -5, 60, 0.0, mat(0))
    for k in range(rng.randint(3, 8)):
        c = (rng.uniform(-10, 10), rng.uniform(3, 40), rng.uniform(0.3, 3))
        if rng.random() < 0.5:
            demo_scenes.add_box(scene, f"Box{k}", c, tuple(rng.uniform(0.3, 3) for _ in range(3)), mat(k + 1))
        else:
            demo_scenes.add_sphere(scene, f"Ball{k}", c, rng.uniform(0.3, 2.5), mat(k + 1), segments=24, rings=12)
    for k in range(rng.randint(2, 40)):
        ob = demo_scenes.add_point_light(scene, f"L{k:02d}", (rng.uniform(-15, 15), rng.uniform(-3, 50),
                                                             rng.uniform(0.5, 8)), math.exp(rng.uniform(2.3, 8.5)))
        ob.data.color = tuple(rng.uniform(0.3, 1.0) for _ in range(3))
        if spots and k % 2:
            ob.data.type = "SPOT"
            ob.data.spot_size, ob.data.spot_blend = math.radians(rng.uniform(10, 120)), rng.uniform(0, 1)
            aim = Vector((rng.uniform(-15, 15), rng.uniform(0, 50), 0.0)) - ob.location
            ob.rotation_euler = aim.to_track_quat("-Z", "Y").to_euler()
    demo_scenes.add_camera(scene, (rng.uniform(-3, 3), rng.uniform(-4, 0), rng.uniform(1, 3)),
                           (rng.uniform(-6, 6), rng.uniform(15, 40), rng.uniform(0, 4)), lens=rng.uniform(20, 50))
    return math.exp(rng.uniform(math.log(0.005), math.log(0.3)))


DAYLIT_TOP, DAYLIT_SUN = 15.0, 2.0   # ``daylit:SEED``: the layer's top (m) and the sun's strength (W/m^2)


def build(scene, name):
    """Build scene ``name``; returns its (beta in 1/m, anisotropy g)."""
    kind, _, seed = name.partition(":")
    if kind in ("random", "randomspot", "daylit"):
        beta = random_scene(scene, int(seed), spots=kind == "randomspot")
        if kind == "daylit":
            sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
            sun.data.energy = DAYLIT_SUN
            sun.rotation_euler = (math.radians(65.0), 0.0, math.radians(150.0))
            scene.collection.objects.link(sun)
        return beta, 0.0
    mod = importlib.import_module(f"demo_scenes.{name}")
    demo_scenes.clear_scene(scene)
    mod.build(scene)
    return mod.DEFAULT_DENSITY, getattr(mod, "ANISOTROPY", 0.0)


def fog_only(scene):
    """Lights that light nothing but the fog (``light_fog_only``), and a black World: the render is the fog's light."""
    for ob in scene.objects:
        if ob.type == "LIGHT":
            light_fog_only(ob)
    bg = next(n for n in scene.world.node_tree.nodes if n.bl_idname == "ShaderNodeBackground")
    bg.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)


def render(scene, path):
    im = scene.render.image_settings
    im.file_format = "OPEN_EXR"
    im.color_depth = "32"
    scene.render.filepath = str(path)
    scene.render.use_file_extension = False
    bpy.ops.render.render(write_still=True, scene=scene.name)


def main(out, name, quality, method="nodes", width=128, height=72):
    out = pathlib.Path(out)
    out.mkdir(parents=True, exist_ok=True)
    scene = bpy.context.scene
    beta, g = build(scene, name)
    fog_only(scene)
    tiny_render(scene, "CYCLES", width, height)
    quality = None if quality == "exact" else (float(quality) if quality[0].isdigit() else quality)
    # Dense Fog as the defaults have it, but with spots: the predictor judges Dense Fog's steps for point lights
    # only (a spot's multiply scattered terms are not in its twin), so the spots' scenes keep single scattering
    dense = not name.startswith("randomspot")
    top = DAYLIT_TOP if name.startswith("daylit") else None
    apply.apply_fog(scene, beta, anisotropy=g, error=quality, method=method, shafts=False, multiple_scattering=dense,
                    fog_top=top)
    choice = apply.stored_choice()
    render(scene, out / "auto.exr")
    apply.apply_fog(scene, beta, anisotropy=g, error=None, method=method, shafts=False, multiple_scattering=dense,
                    fog_top=top)
    render(scene, out / "exact.exr")
    print(json.dumps({"scene": name, "beta": beta, "quality": quality, "predicted": choice["error"],
                      "left_out": (choice["dense"]["missing"] if dense is False else 0.0)
                      + choice.get("shadows", {}).get("missing", 0.0)   # (shafts off: the shadows' share)
                      + choice["dense"].get("surplus_missing", 0.0),
                      # (Dense Fog's unbounded field beyond the scene's surfaces: both renders have it)
                      "surplus": choice["dense"].get("surplus_missing", 0.0),
                      "steps": {k: v[0] for k, v in choice["lights"].items()},
                      "light_error": {k: v[1] for k, v in choice["lights"].items()},
                      "rims": choice.get("rims", {}), "lights": len(choice["lights"]),
                      "explain": apply.explain(choice)}))


if __name__ == "__main__":
    os.environ.setdefault("TMPDIR", "/tmp")
    main(sys.argv[1], sys.argv[2], sys.argv[3], *sys.argv[4:5], *(int(a) for a in sys.argv[5:7]))
