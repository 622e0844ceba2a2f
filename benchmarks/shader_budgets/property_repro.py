"""Re-run the panel property test's sequence (tests/scenes/panel_property.py) for one seed, printing the fog's
state before each render, so the log's "out of SVM stack space" lines can be pinned to a state.

    TMPDIR=/tmp/h3 .venv/bin/python benchmarks/shader_budgets/property_repro.py --seed 2 [--steps 200]
        [--render-every 25] [--save-before-render DIR]
"""
import json
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "scenes"))

import bpy  # noqa: E402

import panel_property as pp  # noqa: E402
from fog_addon.ops import apply  # noqa: E402

SAVE = None
_render_stats = pp.render_stats
_count = [0]


def render_stats(scene):
    s = scene.analytic_fog
    choice = apply.stored_choice() or {}
    lights = [(o.name, o.data.type) for o in scene.objects if o.type == "LIGHT"]
    state = {"render": _count[0], "method": choice.get("method"), "dense": bool(s.use_multiple_scattering),
             "g": s.anisotropy, "density": s.density, "quality": s.quality, "passes": bool(s.use_passes),
             "shafts": bool(s.use_shafts), "top": bool(s.use_fog_top), "lights": lights,
             "steps": {k: v[0] for k, v in choice.get("lights", {}).items()}}
    print("STATE " + json.dumps(state), flush=True)
    if SAVE:
        bpy.ops.wm.save_as_mainfile(filepath=str(pathlib.Path(SAVE) / f"render_{_count[0]}.blend"), copy=True)
    sys.stdout.flush()
    out = _render_stats(scene)
    print(f"END RENDER {_count[0]}", flush=True)
    _count[0] += 1
    return out


pp.render_stats = render_stats

if __name__ == "__main__":
    argv = sys.argv[1:]
    if "--save-before-render" in argv:
        i = argv.index("--save-before-render")
        SAVE = argv[i + 1]
        pathlib.Path(SAVE).mkdir(parents=True, exist_ok=True)
        del argv[i:i + 2]
    sys.argv = [sys.argv[0]] + argv
    pp.main()
