"""Switching the render engine re-chooses the lights' models: into EEVEE within its uniform block, back out of it.

    python tests/scenes/engine_switch.py

The many-lights scene with 25 lights, the fog added in Cycles with the add-on registered (its
depsgraph handler on); the engine switched to EEVEE, then back to Cycles; then the Compositor method.
Prints one line ``ENGINE_SWITCH_JSON {...}``: after each step the stored choice's engine, steps, "limited"
and whether its steps fit EEVEE's budget (``budgets.eevee_budget``); the notes the node groups' and the
Compositor method's ``apply_fog`` returned.
"""
import json
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import bpy  # noqa: E402

import fog_addon  # noqa: E402
from fog_scenes import many_lights  # noqa: E402
from fog_addon.nodes import budgets  # noqa: E402
from fog_addon.ops import apply  # noqa: E402


def state():
    choice = apply.stored_choice()
    steps = [step for step, _ in choice["lights"].values()]
    return {"engine": choice["engine"], "steps": steps, "limited": choice["limited"],
            "fits_eevee": budgets.eevee_budget().fits(steps), "error": choice["error"]}


def main():
    fog_addon.register()
    scene, _ = many_lights.build_scene(25, direct_light=True)
    scene.render.engine = "CYCLES"
    scene.render.resolution_x, scene.render.resolution_y = many_lights.W, many_lights.H
    notes = apply.apply_fog(scene, many_lights.BETA)
    scene.analytic_fog.enabled = True   # as the Add Fog operator leaves it: the handler follows the scene
    out = {"cycles": state()}
    scene.render.engine = "BLENDER_EEVEE"
    bpy.context.view_layer.update()
    out["eevee"] = state()
    scene.render.engine = "CYCLES"
    bpy.context.view_layer.update()
    out["cycles_again"] = state()
    out["notes"] = {"nodes": notes, "compositor": apply.apply_fog(scene, many_lights.BETA, method="compositor")}
    print("ENGINE_SWITCH_JSON " + json.dumps(out), flush=True)


if __name__ == "__main__":
    main()
