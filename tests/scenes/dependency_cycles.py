"""The fog's drivers close no dependency cycle (issue 43, item 6), in the scenes the tests build most; one process,
no render; prints one JSON line.

Blender prints "Dependency cycle detected:" and "Detected N dependency cycles" from C (its depsgraph log, on
stderr) whenever a depsgraph is built with a cycle in it.  This script sends stderr into stdout (``os.dup2``) and
prints "=== CASE <name>" (flushed) before each case, so every line Blender prints falls under the case that caused
it: ``tests/test_dependency_cycles.py`` reads them there.

Cases (``main``), each on the spheres demo scene (``demo_scenes.spheres``, 32 x 24 px) made afresh, the fog added
with ``bpy.ops.fog.add()``, then the depsgraph evaluated (``evaluated_depsgraph_get``, ``view_layer.update``) and
the frames 1, 10, 5 set:

* ``point_compositor``, ``point_nodes``: its point lamp, the Compositor and the Node Groups methods;
* ``daylight_nodes``, ``daylight_compositor``: a Fog Top (10 m) and a Sun light, the World a uniform Background;
* ``dense``: Dense Fog (multiple scattering) on, the point lamp, Node Groups (its table is baked on first use,
  about a minute, then read from the table cache: a change to ``fog_addon/precompute`` bakes it again);
* ``spot``: the lamp a spot (Compositor); ``area``: an area light (Node Groups).

In every case the lamp moves between frames 1 and 10 (keyframes), and in the daylight cases the sun turns and the
World's Background Strength goes from 1 to 2 over the same frames.  After each frame set, every driver of the fog
(on its node groups, the World's and the materials' trees) is evaluated here in Python from its variables (simple
expressions, sums and averages of single properties and world transforms) and compared with the value the driver
left in its property: ``stale`` lists those that differ (a driver in a cycle may read the frame before).  The
daylight cases also give the driven sun direction against the sun's, ``world_sky``: the World group's copy of the
sky's radiance (``sunsky._sky``: a value, not driven) against the Background's as built and after its colour
changed (the fog's depsgraph handler sets it again: ``sunsky.refresh_world_sky``), and ``daylight_notes``: the World's
notes for Node Groups and the Compositor once the sun stands still (an animated Background is noted where the World
group's sky glow reads its copy).

``probe_*`` cases (no fog): the ways a value of the World's Background could reach a group inside the World's own
tree by a driver (``sunsky._sky``), each in a World of its own: a driver on a node group in the World's tree
reading the World (``probe_group_world``), on the World's tree reading itself (``probe_tree``), and a Context
Property of the scene's world (``probe_context``).  Each closes a cycle in Blender 5.0: they show the capture
sees one, and if one ever stops, the World group can be driven again.
"""
import json
import math
import os
import pathlib
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

os.dup2(1, 2)   # Blender's C log (stderr) into stdout, in order with the case markers

import bpy  # noqa: E402

import fog_addon  # noqa: E402
from demo_scenes import spheres  # noqa: E402
from fog_addon import sunsky  # noqa: E402
from fog_addon.nodes import groups  # noqa: E402
from fog_addon.ops import apply, report  # noqa: E402

FRAMES = (1, 10, 5)
FOG_TOP_M = 10.0
# the functions of Blender's simple expressions (BLI_expr_pylike_eval), as Python evaluates them
SIMPLE = {name: getattr(math, name) for name in ("sin", "cos", "tan", "asin", "acos", "atan", "atan2", "sqrt", "exp",
                                                 "log", "floor", "ceil", "trunc", "fmod", "fabs", "pi", "radians",
                                                 "degrees")}
SIMPLE.update(min=min, max=max, abs=abs, pow=pow, round=round, int=lambda x: float(math.trunc(x)), float=float,
              clamp=lambda x, lo=0.0, hi=1.0: min(max(x, lo), hi))


def mark(name):
    print(f"=== CASE {name}", flush=True)


def fresh():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    spheres.build(scene)
    scene.render.resolution_x, scene.render.resolution_y = 32, 24
    scene.render.resolution_percentage = 100
    scene.frame_start, scene.frame_end = 1, 10
    return scene


def animate_lamp(lamp):
    lamp.location = spheres.LAMP_LOCATION
    lamp.keyframe_insert("location", frame=1)
    lamp.location = (0.6, -0.8, 1.9)
    lamp.keyframe_insert("location", frame=10)


def add_sun(scene):
    """A Sun light of 3 W/m^2 that turns between frames 1 and 10; returns it and the World's Background node."""
    data = bpy.data.lights.new("Sun", "SUN")
    data.energy = 3.0
    sun = bpy.data.objects.new("Sun", data)
    scene.collection.objects.link(sun)
    sun.rotation_euler = (math.radians(50.0), 0.0, math.radians(30.0))
    sun.keyframe_insert("rotation_euler", frame=1)
    sun.rotation_euler = (math.radians(30.0), 0.0, math.radians(-40.0))
    sun.keyframe_insert("rotation_euler", frame=10)
    sun.rotation_euler = (math.radians(50.0), 0.0, math.radians(30.0))
    bg = sunsky.uniform_sky(scene.world)
    assert bg is not None, "the spheres' World is a uniform Background"
    return sun, bg


def animate_background(bg):
    """The Background's Strength keyed 1 (frame 1) -> 2 (frame 10)."""
    strength = bg.inputs["Strength"]
    strength.default_value = 1.0
    strength.keyframe_insert("default_value", frame=1)
    strength.default_value = 2.0
    strength.keyframe_insert("default_value", frame=10)
    strength.default_value = 1.0


def _fog_ids():
    """The IDs whose drivers are the fog's: its node groups, the World's and the materials' trees."""
    ids = [ng for ng in bpy.data.node_groups if ng.name.startswith("AnalyticFog")]
    ids += [w.node_tree for w in bpy.data.worlds if w.node_tree is not None]
    ids += [m.node_tree for m in bpy.data.materials if m.node_tree is not None]
    return ids


def _variable(var):
    t = var.targets[0]
    if var.type == "TRANSFORMS":
        assert t.transform_space == "WORLD_SPACE" and t.transform_type.startswith("LOC_"), (t.transform_space,
                                                                                          t.transform_type)
        return t.id.matrix_world.translation["XYZ".index(t.transform_type[-1])]
    if var.type == "SINGLE_PROP":
        return t.id.path_resolve(t.data_path)
    raise AssertionError(f"variable type {var.type}")


def _expected(driver):
    values = {v.name: float(_variable(v)) for v in driver.variables}
    if driver.type == "SCRIPTED":
        frame = bpy.context.scene.frame_current_final   # (a simple expression's ``frame``)
        return eval(driver.expression, {"__builtins__": {}}, {**SIMPLE, "frame": frame, **values})  # noqa: S307
    if driver.type == "SUM":
        return sum(values.values())
    if driver.type == "AVERAGE":
        return sum(values.values()) / len(values)
    raise AssertionError(f"driver type {driver.type}")


def stale_drivers():
    """(count of the fog's drivers, [(ID, path, index, driven value, value of its variables now)] that differ by
    more than float32 rounding, invalid ones too)."""
    count, stale = 0, []
    for idb in _fog_ids():
        ad = idb.animation_data
        if ad is None:
            continue
        for fc in ad.drivers:
            count += 1
            value = idb.path_resolve(fc.data_path)
            if hasattr(value, "__len__"):
                value = value[fc.array_index]
            want = _expected(fc.driver)
            if not fc.driver.is_valid or abs(value - want) > 2e-6 * max(1.0, abs(want)):
                stale.append((idb.name, fc.data_path, fc.array_index, float(value), float(want)))
    return count, stale


def _sun_direction_nodes():
    """Driven inputs (x, y, z) of every 'Sun Direction' node of the fog's groups."""
    return [[s.default_value for s in n.inputs[:3]] for ng in bpy.data.node_groups
            if ng.name.startswith("AnalyticFog") for n in ng.nodes if n.label == "Sun Direction"]


def sky_of(bg):
    """A uniform sky's radiance now: its Background's Color x Strength."""
    return [c * bg.inputs["Strength"].default_value for c in bg.inputs["Color"].default_value[:3]]


def world_sky():
    ng = bpy.data.node_groups.get(groups.WORLD)
    return [[s.default_value for s in n.inputs[:3]] for n in ng.nodes if n.label == sunsky.WORLD_SKY_LABEL]


def fog_case(name, method, kind="POINT", daylight=False, dense=False):
    """Add the fog (``method``, Light Shafts off: no shadow maps to bake) to the spheres with the lamp of ``kind``;
    returns what the module docstring lists."""
    mark(name)
    t0 = time.time()
    scene = fresh()
    lamp = bpy.data.objects["Lamp"]
    if kind != "POINT":
        lamp.data.type = kind
        lamp.rotation_euler = (math.radians(20.0), 0.0, 0.0)
        if kind == "AREA":
            lamp.data.size = 0.3
    animate_lamp(lamp)
    sun = bg = None
    if daylight:
        sun, bg = add_sun(scene)
        animate_background(bg)
    s = scene.analytic_fog
    s.method = method
    s.use_fog_top = daylight
    s.fog_top = FOG_TOP_M
    s.use_multiple_scattering = dense
    s.use_shafts = False
    added = bpy.ops.fog.add()
    bpy.context.evaluated_depsgraph_get()
    bpy.context.view_layer.update()
    out = {"added": sorted(added), "method": s.method, "frames": {}}
    if daylight:
        out["world_sky_built"] = {"sky": sky_of(bg), "world_group": world_sky()}
    for frame in FRAMES:
        scene.frame_set(frame)
        count, stale = stale_drivers()
        f = {"drivers": count, "stale": stale[:10], "n_stale": len(stale)}
        if daylight:
            z = sun.matrix_world.to_3x3().col[2]
            f["sun"] = list(z)
            f["sun_driven"] = _sun_direction_nodes()
            f["strength"] = bg.inputs["Strength"].default_value
        out["frames"][str(frame)] = f
    if daylight:
        bg.inputs["Color"].default_value = (0.2, 0.3, 0.9, 1.0)   # the sky changed (its colour is not animated)
        bpy.context.view_layer.update()                           # the fog's depsgraph handler refreshes it
        out["world_sky_refreshed"] = {"sky": sky_of(bg), "world_group": world_sky()}
        sun.animation_data_clear()   # a still sun and camera: the World group's sky glow reads the Background's copy
        out["notes"] = {m: [n for n in report.daylight_notes(scene, apply.spec_of(scene), m)
                            if n[0] == scene.world.name] for m in ("nodes", "compositor")}
    out["seconds"] = round(time.time() - t0, 2)
    return out


def _probe_world(name):
    """A World of its own: Background -> Output, a Combine XYZ to drive; returns (world, tree, background)."""
    mark(name)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    world = bpy.data.worlds.new("Probe")
    scene.world = world
    tree = world.node_tree
    if tree is None:
        world.use_nodes = True
        tree = world.node_tree
    bg = next(n for n in tree.nodes if n.type == "BACKGROUND")
    return scene, world, tree, bg


def _drive(sock, owner, path, context=False):
    fc = sock.driver_add("default_value")
    d = fc.driver
    d.type = "AVERAGE"
    var = d.variables.new()
    if context:
        var.type = "CONTEXT_PROP"
        var.targets[0].context_property = "ACTIVE_SCENE"
    else:
        var.type = "SINGLE_PROP"
        var.targets[0].id_type = owner.id_type
        var.targets[0].id = owner
    var.targets[0].data_path = path


def probe(name):
    """A driver reading the World's Background Strength that feeds the World's own shading (``sunsky._sky``)."""
    scene, world, tree, bg = _probe_world(name)
    strength = 'nodes["Background"].inputs["Strength"].default_value'
    if name == "probe_group_world":   # a group in the World's tree, its driver reading through the World
        ng = bpy.data.node_groups.new("Probe Group", "ShaderNodeTree")
        ng.interface.new_socket("V", in_out="OUTPUT", socket_type="NodeSocketVector")
        vec = ng.nodes.new("ShaderNodeCombineXYZ")
        ng.links.new(vec.outputs[0], ng.nodes.new("NodeGroupOutput").inputs[0])
        node = tree.nodes.new("ShaderNodeGroup")
        node.node_tree = ng
        tree.links.new(node.outputs[0], bg.inputs["Color"])
        _drive(vec.inputs[0], world, "node_tree." + strength)
    else:
        vec = tree.nodes.new("ShaderNodeCombineXYZ")
        tree.links.new(vec.outputs[0], bg.inputs["Color"])
        if name == "probe_tree":   # on the World's tree, reading itself
            _drive(vec.inputs[0], tree, strength)
        else:                      # a Context Property: the active scene's world
            _drive(vec.inputs[0], None, "world.node_tree." + strength, context=True)
    bpy.context.evaluated_depsgraph_get()
    scene.frame_set(2)
    return {"value": vec.inputs[0].default_value}


CASES = {
    "point_compositor": lambda: fog_case("point_compositor", "COMPOSITOR"),
    "point_nodes": lambda: fog_case("point_nodes", "NODES"),
    "daylight_nodes": lambda: fog_case("daylight_nodes", "NODES", daylight=True),
    "daylight_compositor": lambda: fog_case("daylight_compositor", "COMPOSITOR", daylight=True),
    "dense": lambda: fog_case("dense", "NODES", dense=True),
    "spot": lambda: fog_case("spot", "COMPOSITOR", kind="SPOT"),
    "area": lambda: fog_case("area", "NODES", kind="AREA"),
}
PROBES = ("probe_group_world", "probe_tree", "probe_context")


def main(names):
    """The cases ``names`` (default: every fog case and probe), in CASES' then PROBES' order."""
    fog_addon.register()
    names = set(names or (*CASES, *PROBES))
    res = {name: make() for name, make in CASES.items() if name in names}
    for name in PROBES:
        if name in names:
            res[name] = probe(name)
    mark("end")
    fog_addon.unregister()
    print("CYCLES_JSON " + json.dumps(res), flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
