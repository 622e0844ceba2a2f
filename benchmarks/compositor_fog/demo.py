"""A demo scene rendered as the render tests do, with the fog's light moved into the compositor.

    .venv/bin/python benchmarks/compositor_fog/demo.py SCENE DENSITY OUT.exr [more render flags]
    .venv/bin/python benchmarks/compositor_fog/demo.py --compare OUT.exr REFERENCE.exr
    .venv/bin/python benchmarks/compositor_fog/demo.py --exact SCENE DENSITY OUT.exr [more render flags]

The first form is ``python -m fog_addon render`` with the render tests' flags (64x36, pixel-centre
sampling, no cast shadows, no interreflection), except that just before rendering ``build.to_compositor``
takes every light out of the materials and the World and computes its fog light in the compositor.  The
second prints the relative RMSE against a path-traced reference (``tests/references``) as JSON.  The
third keeps the fog in the materials with its passes (Quality Exact), renders at 320x180 with the scene's
own pixel filter and writes a multilayer EXR whose Composite is the compositor's fog light alone, with the
lights' pixels beside it (OUT.json) for ``compare.py``.
"""
import json
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path[:0] = [str(ROOT), str(ROOT / "tests"), str(pathlib.Path(__file__).resolve().parent)]


def render(scene_name, density, out, extra, exact=False):
    import bpy
    import build
    import render_harness
    from fog_addon import cli, measure
    original = measure.render_to_file

    def render_to_file(scene, path):
        build.to_compositor(scene, comp=not exact)
        if not exact:
            return original(scene, path)
        bpy.context.view_layer.update()
        build.write_light_pixels(scene, path)
        measure.configure_output(scene, path)
        scene.render.image_settings.media_type = "MULTI_LAYER_IMAGE"
        scene.render.image_settings.file_format = "OPEN_EXR_MULTILAYER"
        bpy.ops.render.render(write_still=True)

    measure.render_to_file = render_to_file
    blend = render_harness.scene_blend(scene_name)
    flags = (["--resolution", "320x180", "--passes", "--error", "exact"] if exact else
             ["--resolution", "64x36", "--pixel-centre"])
    return cli.main(["render", str(blend), "--engine", "cycles", "--density", density, *flags, "--no-interreflection",
                     "--no-cast-shadows", "--out", out, *extra])


def compare(test, ref):
    from fog_addon import compare as compare_mod
    m = compare_mod.compare_files(test, ref)
    print(json.dumps({k: float(v) for k, v in m.items() if isinstance(v, (int, float))}))


if __name__ == "__main__":
    if sys.argv[1] == "--compare":
        compare(sys.argv[2], sys.argv[3])
    elif sys.argv[1] == "--exact":
        render(sys.argv[2], sys.argv[3], sys.argv[4], sys.argv[5:], exact=True)
    else:
        sys.exit(render(sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:]))
