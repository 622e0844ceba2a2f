"""Add fog twice, remove it, and report whether every material, light and world is as before (JSON)."""
import json
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import bpy  # noqa: E402

import fog_addon  # noqa: E402
from demo_scenes import spheres  # noqa: E402


def snapshot_tree(tree):
    if tree is None:
        return None
    nodes = {}
    for n in tree.nodes:
        ins = {}
        for i, s in enumerate(n.inputs):
            v = getattr(s, "default_value", None)
            ins[i] = repr(tuple(v) if hasattr(v, "__len__") and not isinstance(v, str) else v)
        nodes[n.name] = (n.bl_idname, tuple(n.location), ins, getattr(n, "is_active_output", None))
    links = sorted((l.from_node.name, l.from_socket.identifier, l.to_node.name, l.to_socket.identifier)
                   for l in tree.links)
    return nodes, links


def snapshot():
    return {
        "materials": {m.name: snapshot_tree(m.node_tree) for m in bpy.data.materials},
        "worlds": {w.name: snapshot_tree(w.node_tree) for w in bpy.data.worlds},
        "lights": {l.name: (l.use_nodes, l.energy, tuple(l.color), snapshot_tree(l.node_tree) if l.use_nodes else None)
                   for l in bpy.data.lights},
        "groups": sorted(g.name for g in bpy.data.node_groups),
        "images": sorted(i.name for i in bpy.data.images),
    }


def main():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    fog_addon.register()
    spheres.build(bpy.context.scene)
    before = snapshot()
    assert bpy.ops.fog.add(density=0.1) == {"FINISHED"}
    once = snapshot()
    assert bpy.ops.fog.add(density=0.1) == {"FINISHED"}
    twice = snapshot()
    try:   # an operator that reports an error raises in bpy.ops
        bad = bpy.ops.fog.add(density=float("nan"))
    except RuntimeError as e:
        bad = {"CANCELLED"} if "must be finite" in str(e) else {str(e)}
    after_bad = snapshot()
    assert bpy.ops.fog.remove() == {"FINISHED"}
    after = snapshot()
    fog_addon.unregister()
    same = [k for k in once if json.dumps(once[k], sort_keys=True) == json.dumps(twice[k], sort_keys=True)]
    print(json.dumps({
        "unchanged_by_second_add": same,
        "fog_changed_something": once != before,
        "nan_cancelled": bad == {"CANCELLED"} and after_bad == twice,
        "restored": json.dumps(after, sort_keys=True) == json.dumps(before, sort_keys=True),
    }))


if __name__ == "__main__":
    main()
