"""A property test of the panel: random sequences of settings changes on a scene of the user's; prints JSON.

The scene is the spheres demo with what a user's file holds that the fog must leave alone: their own
compositor (Render Layers -> Glare -> Color Balance -> Group Output, the Image also to a Viewer, a second
view layer's Render Layers over it by Alpha Over, a File Output of its Depth), a World with a volume of its
own, and two view layers that render.  Fog is added with the operator (``fog.add``), then ``--steps``
changes are drawn from ``--seed``, each as the panel makes it (a property set; background Blender syncs at
once): the method, anisotropy, density (0 included), Dense Fog, Light Shafts, Fog Passes, the Quality, the
Fog Top, a lamp added or taken out, an undo.  After each change:

* the user's compositor: every node of theirs is still there with its type, and every link of theirs still
  carries what it carried, directly or through the fog's nodes (``effective_links``);
* the fog is in place: with the Compositor method, each Render Layers node that feeds something feeds a
  fog group node; with another, no fog group node is in the tree;
* a setting the method can't serve was refused with a message (``apply.sync_error``), the fog kept as built;
* every ``--render-every`` changes (and after the last), a 24 x 16 render of 1 sample is finite and not flat.

At the end the lamps are put back as they were, Remove is run (``fog.remove``), and the user's data is
compared with the snapshot taken before Add Fog (``add_remove.snapshot`` plus the compositor and the view
layers' passes).  The first failure ends the run: its step, the change and what broke are printed.

    python tests/scenes/panel_property.py --seed 1 --steps 200 [--render-every 20]
"""
import argparse
import json
import math
import pathlib
import random
import sys
import traceback

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "scenes"))

import bpy  # noqa: E402
import numpy as np  # noqa: E402

import fog_addon  # noqa: E402
from demo_scenes import spheres  # noqa: E402
from fog_addon.nodes import comp_fog, owned  # noqa: E402
from fog_addon.ops import apply  # noqa: E402
import add_remove  # noqa: E402  (its snapshot of the user's data)

USER_TREE = "User Compositor"
SECOND_LAYER = "Second Layer"
ANISOTROPIES = (0.0, 0.85)   # Dense Fog bakes a table per g: two keep the run's bakes bounded (0.85: the
#                              farm's and the spot tests' g, baked in the default tier anyway)
DENSITIES = (0.0, 0.02, 0.1, 0.3)
RENDER_IMAGES = ("Render Result", "Viewer Node")   # images rendering makes


def build_scene():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    fog_addon.register()
    scene = bpy.context.scene
    spheres.build(scene)
    scene.render.engine = "CYCLES"
    scene.cycles.samples = 1
    scene.cycles.use_denoising = False
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 24, 16, 100
    second = scene.view_layers.new(SECOND_LAYER)
    second.use_pass_z = True
    # the user's World volume
    tree = scene.world.node_tree
    vol = tree.nodes.new("ShaderNodeVolumeAbsorption")
    vol.name = "User Volume"
    vol.inputs["Density"].default_value = 0.001
    out = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputWorld")
    tree.links.new(vol.outputs[0], out.inputs["Volume"])
    # the user's compositor
    ct = bpy.data.node_groups.new(USER_TREE, "CompositorNodeTree")
    ct.interface.new_socket("Image", in_out="OUTPUT", socket_type="NodeSocketColor")
    n = ct.nodes
    rl = n.new("CompositorNodeRLayers"); rl.name = "User RL"; rl.scene = scene; rl.layer = scene.view_layers[0].name
    rl2 = n.new("CompositorNodeRLayers"); rl2.name = "User RL 2"; rl2.scene = scene; rl2.layer = SECOND_LAYER
    glare = n.new("CompositorNodeGlare"); glare.name = "User Glare"
    balance = n.new("CompositorNodeColorBalance"); balance.name = "User Balance"
    over = n.new("CompositorNodeAlphaOver"); over.name = "User Over"
    viewer = n.new("CompositorNodeViewer"); viewer.name = "User Viewer"
    gout = n.new("NodeGroupOutput"); gout.name = "User Output"
    ct.links.new(rl.outputs["Image"], glare.inputs["Image"])
    ct.links.new(glare.outputs["Image"], balance.inputs["Image"])
    ct.links.new(rl2.outputs["Image"], over.inputs[1])
    ct.links.new(balance.outputs["Image"], over.inputs[2])
    ct.links.new(over.outputs["Image"], gout.inputs["Image"])
    ct.links.new(rl.outputs["Image"], viewer.inputs["Image"])
    scene.compositing_node_group = ct
    scene.render.use_compositing = True
    return scene


def user_tree():
    return bpy.data.node_groups[USER_TREE]


def tree_state(tree):
    """The user's nodes {name: type} and their links [(from, socket, to, socket)]."""
    nodes = {nd.name: nd.bl_idname for nd in tree.nodes if not owned.is_ours(nd)}
    links = sorted((lk.from_node.name, lk.from_socket.identifier, lk.to_node.name, lk.to_socket.identifier)
                   for lk in tree.links if not owned.is_ours(lk.from_node) and not owned.is_ours(lk.to_node))
    return nodes, links


def effective_links(tree):
    """The user's links as the user made them: a link from the fog's nodes into a node of the user's counts as
    a link from the user's socket that feeds the fog's chain's Image (followed upstream)."""
    out = []
    for lk in tree.links:
        if owned.is_ours(lk.to_node):
            continue
        src, node = lk.from_socket, lk.from_node
        seen = 0
        while owned.is_ours(node) and seen < 20:
            seen += 1
            feed = next((i for i in node.inputs if i.name == "Image" and i.is_linked), None)
            if feed is None:
                src = None
                break
            src = feed.links[0].from_socket
            node = src.node
        out.append((node.name if src is not None else None, src.identifier if src is not None else None,
                    lk.to_node.name, lk.to_socket.identifier))
    return sorted(out)


def fog_in_place(scene):
    """'' if the fog's chain is where the built method needs it, else what is wrong."""
    tree = user_tree()
    method = apply.built_method()
    fog_nodes = [nd for nd in tree.nodes if owned.is_ours(nd) and nd.bl_idname == "CompositorNodeGroup"]
    if method is None or method.name != "compositor":
        return f"fog group nodes with the {getattr(method, 'name', None)} method" if fog_nodes else ""
    for rl in tree.nodes:
        if rl.bl_idname != "CompositorNodeRLayers" or owned.is_ours(rl):
            continue
        users = [lk.to_node for lk in rl.outputs["Image"].links]
        if not users:
            continue
        if not all(owned.is_ours(u) and u.bl_idname == "CompositorNodeGroup" and u.node_tree is not None
                   and u.node_tree.name == comp_fog.FOG_GROUP for u in users):
            return f"{rl.name}'s Image feeds {[u.name for u in users]}, not the fog group"
    return ""


def world_volume_kept(scene):
    tree = scene.world.node_tree
    vol = tree.nodes.get("User Volume")
    return vol is not None and vol.outputs[0].is_linked


def render_stats(scene):
    """(finite, spread) of the composite: a 24 x 16 render of 1 sample, read from the Viewer's twin (the
    Render Result is read through a saved file)."""
    path = str(pathlib.Path(bpy.app.tempdir or "/tmp") / "panel_property.exr")
    scene.render.filepath = path
    scene.render.image_settings.file_format = "OPEN_EXR"
    bpy.ops.render.render(write_still=True)
    img = bpy.data.images.load(path, check_existing=False)
    px = np.array(img.pixels[:], dtype=np.float32).reshape(-1, 4)[:, :3]
    bpy.data.images.remove(img)
    return bool(np.isfinite(px).all()), float(px.max() - px.min())


def snapshot(scene):
    snap = add_remove.snapshot()
    for name in snap["scenes"]:   # the fog's settings are the user's own, not what Remove gives back
        props, osl = snap["scenes"][name]
        snap["scenes"][name] = ({k: v for k, v in props.items() if k != "analytic_fog"}, osl)
    snap["compositor"] = add_remove.snapshot_tree(user_tree())
    snap["use_compositing"] = scene.render.use_compositing
    snap["passes"] = {vl.name: (vl.use_pass_z, vl.use_pass_emit, vl.use_pass_environment,
                                sorted(a.name for a in vl.aovs)) for vl in scene.view_layers}
    return snap


class Lamps:
    """Lamps added and taken out by the sequence (taken out = unlinked from the scene, so they can come back)."""

    def __init__(self, kinds=("POINT", "SPOT", "POINT")):
        self.added, self.out, self.kinds = [], [], kinds

    def add(self, scene, rng):
        data = bpy.data.lights.new(f"Prop Lamp {len(self.added)}", rng.choice(self.kinds))
        data.energy = rng.uniform(20.0, 200.0)
        obj = bpy.data.objects.new(data.name, data)
        obj.location = (rng.uniform(-3, 3), rng.uniform(-3, 3), rng.uniform(0.5, 3))
        scene.collection.objects.link(obj)
        self.added.append(obj.name)
        return f"add lamp {obj.name} ({data.type})"

    def take_out(self, scene, rng):
        lamps = [o for o in scene.collection.objects if o.type == "LIGHT" and o.name not in self.out]
        if len(lamps) <= 1:
            return "take out a lamp: only one left, kept"
        obj = rng.choice(lamps)
        scene.collection.objects.unlink(obj)
        self.out.append(obj.name)
        return f"take out lamp {obj.name}"

    def restore(self, scene):
        for name in self.out:
            obj = bpy.data.objects.get(name)
            if obj is not None and name not in scene.collection.objects:
                scene.collection.objects.link(obj)
        for name in self.added:
            obj = bpy.data.objects.get(name)
            if obj is not None:
                data = obj.data
                bpy.data.objects.remove(obj)
                if data.users == 0:
                    bpy.data.lights.remove(data)
        self.added, self.out = [], []


def change(scene, rng, lamps, allow_dense):
    """One random settings change as the panel makes it; returns its description."""
    s = scene.analytic_fog
    kind = rng.choice(["method", "anisotropy", "density", "dense", "shafts", "passes", "quality", "top", "top",
                       "lamp", "lamp", "undo"])
    if kind == "method":
        s.method = rng.choice(["AUTO", "NODES", "COMPOSITOR", "AUTO"])
        return f"method {s.method}"
    if kind == "anisotropy":
        s.anisotropy = rng.choice(ANISOTROPIES)
        return f"anisotropy {s.anisotropy:g}"
    if kind == "density":
        s.density = rng.choice(DENSITIES)
        return f"density {s.density:g}"
    if kind == "dense":
        if not allow_dense:
            return "Dense Fog: left off (--no-dense)"
        s.use_multiple_scattering = not s.use_multiple_scattering
        return f"Dense Fog {s.use_multiple_scattering}"
    if kind == "shafts":
        s.use_shafts = not s.use_shafts
        return f"Light Shafts {s.use_shafts}"
    if kind == "passes":
        s.use_passes = not s.use_passes
        return f"Fog Passes {s.use_passes}"
    if kind == "quality":
        s.quality = rng.choice(["DRAFT", "FINAL", "EXACT"])
        return f"Quality {s.quality}"
    if kind == "top":
        if rng.random() < 0.5:
            s.use_fog_top = not s.use_fog_top
            return f"Fog Top {s.use_fog_top}"
        s.fog_top = rng.choice([2.0, 5.0, 50.0])
        return f"Fog Top at {s.fog_top:g}"
    if kind == "lamp":
        return lamps.add(scene, rng) if rng.random() < 0.5 or not lamps.added else lamps.take_out(scene, rng)
    bpy.ops.ed.undo_push(message="panel property: before")
    s.density = rng.choice(DENSITIES)
    bpy.ops.ed.undo_push(message="panel property: density")
    bpy.ops.ed.undo()
    return "undo of a density change"


def run(seed, steps, render_every, allow_dense, spots=True):
    scene = build_scene()
    rng = random.Random(seed)
    before_user = tree_state(user_tree())
    before_links = before_user[1]
    before = snapshot(scene)
    scene.analytic_fog.density = 0.1
    if not allow_dense:   # (Dense Fog is on by default: --no-dense turns it off, and no anisotropy bakes its tables)
        scene.analytic_fog.use_multiple_scattering = False
    result = {"seed": seed, "steps": 0, "failure": None, "refused": 0, "renders": 0, "methods": {}}
    if bpy.ops.fog.add() != {"FINISHED"}:
        result["failure"] = {"step": 0, "change": "Add Fog", "what": "fog.add did not finish"}
        return result
    lamps = Lamps() if spots else Lamps(("POINT",))
    for step in range(1, steps + 1):
        try:
            if step == steps // 2:   # the node groups once, whatever the draws (the walk must visit both methods)
                scene.analytic_fog.method = "NODES"
                what = "method NODES (the walk's visit)"
            else:
                what = change(scene, rng, lamps, allow_dense)
        except Exception:   # noqa: BLE001 - the run reports it as the failure
            result["failure"] = {"step": step, "change": "(raised)", "what": traceback.format_exc()[-1500:]}
            return result
        scene = bpy.context.scene   # (an undo reloads the file's data)
        if apply.sync_error(scene):
            result["refused"] += 1
        problems = []
        nodes, _ = tree_state(user_tree())
        if nodes != before_user[0]:
            problems.append(f"user nodes changed: {sorted(set(before_user[0]) ^ set(nodes))}")
        eff = effective_links(user_tree())
        if eff != before_links:
            problems.append(f"user links changed: missing {sorted(set(before_links) - set(eff))}, "
                            f"extra {sorted(set(eff) - set(before_links))}")
        where = fog_in_place(scene)
        if where:
            problems.append(where)
        if not world_volume_kept(scene):
            problems.append("the user's World volume is no longer linked")
        method = apply.built_method()
        result["methods"][getattr(method, "name", "none")] = result["methods"].get(getattr(method, "name", "none"), 0) + 1
        if render_every and (step % render_every == 0 or step == steps):
            finite, spread = render_stats(scene)
            result["renders"] += 1
            if not finite:
                problems.append("the render holds NaN or inf")
            elif spread <= 0.0:
                problems.append("the render is flat")
        result["steps"] = step
        if problems:
            result["failure"] = {"step": step, "change": what, "what": problems,
                                 "sync_error": apply.sync_error(scene)}
            return result
    lamps.restore(scene)
    bpy.ops.fog.remove()
    after = snapshot(scene)
    for snap in (before, after):   # what rendering makes, not the fog
        snap["images"] = [name for name in snap["images"] if name not in RENDER_IMAGES]
    differ = add_remove.differing(before, after)
    if "images" in differ:
        differ.append(f"images before {before['images']}, after {after['images']}")
    if differ:
        result["failure"] = {"step": "remove", "change": "Remove", "what": differ}
    return result


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    ap = argparse.ArgumentParser()
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--steps", type=int, default=200)
    ap.add_argument("--render-every", type=int, default=25)
    ap.add_argument("--no-dense", action="store_true")
    ap.add_argument("--no-spots", action="store_true", help="the lamps added are point lamps only")
    args = ap.parse_args(argv)
    print("RESULT " + json.dumps(run(args.seed, args.steps, args.render_every, not args.no_dense,
                                        not args.no_spots)))


if __name__ == "__main__":
    main()
