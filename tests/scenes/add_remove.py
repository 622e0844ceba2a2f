"""Add fog twice, edit a fogged material, add again, save and reopen, remove it; report what changed (JSON).

Adding the fog again after an edit re-syncs the fog's copies of the BSDF (the
inputs of each material's ``AnalyticFog Surface`` node and the links into
them) and must change nothing else.  The snapshots hold the node trees, every
custom (ID) property of the materials, worlds, lights, scenes and nodes, and
the Cycles settings the fog may touch, so remove must give all of them back.
The scene triggers both setting overrides (materials without emission, a
World of one colour) from non-default user values, and holds user nodes
named like the fog's ("AnalyticFog Mine"), which must survive.
"""
import json
import os
import pathlib
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import bpy  # noqa: E402

import fog_addon  # noqa: E402
from demo_scenes import spheres  # noqa: E402

EDIT_COLOR = (0.2, 0.5, 0.9, 1.0)   # the user's new Base Color for "Diffuse"
EDIT_NODE = "User Roughness"        # the user's Value node linked into "Glossy"'s Roughness
FOG_NODE = "AnalyticFog Surface"    # holds the fog's copies of the Principled values
USER_NODE = "AnalyticFog Mine"      # the user's own node, named like the fog's
TAG = "analytic_fog"                # the custom property on every node the fog adds


def id_props(owner):
    """The custom (ID) properties of ``owner`` (a data-block or a node) as plain data."""
    def plain(v):
        if hasattr(v, "to_dict"):
            return v.to_dict()
        if hasattr(v, "to_list"):
            return v.to_list()
        return v.name_full if isinstance(v, bpy.types.ID) else v
    return {k: plain(v) for k, v in owner.items()}


def snapshot_tree(tree):
    if tree is None:
        return None
    nodes = {}
    for n in tree.nodes:
        ins = {}
        for i, s in enumerate(n.inputs):
            v = getattr(s, "default_value", None)
            ins[i] = repr(tuple(v) if hasattr(v, "__len__") and not isinstance(v, str) else v)
        nodes[n.name] = (n.bl_idname, tuple(n.location), ins, getattr(n, "is_active_output", None), id_props(n))
    links = sorted((l.from_node.name, l.from_socket.identifier, l.to_node.name, l.to_socket.identifier)
                   for l in tree.links)
    return nodes, links


def snapshot_material(m):
    return snapshot_tree(m.node_tree), id_props(m), m.cycles.emission_sampling


def snapshot():
    return {
        "materials": {m.name: snapshot_material(m) for m in bpy.data.materials},
        "worlds": {w.name: (snapshot_tree(w.node_tree), id_props(w), w.cycles.sampling_method)
                   for w in bpy.data.worlds},
        "lights": {l.name: (l.use_nodes, l.energy, tuple(l.color), snapshot_tree(l.node_tree) if l.use_nodes else None,
                            id_props(l)) for l in bpy.data.lights},
        "scenes": {s.name: (id_props(s), s.cycles.shading_system) for s in bpy.data.scenes},
        "groups": sorted(g.name for g in bpy.data.node_groups),
        "images": sorted(i.name for i in bpy.data.images),
    }


def differing(a, b):
    """Keys of snapshots ``a`` and ``b`` that differ, as "key" or "key/data-block name"."""
    out = []
    for k in sorted(set(a) | set(b)):
        va, vb = a.get(k), b.get(k)
        if isinstance(va, dict) and isinstance(vb, dict):
            out += [f"{k}/{n}" for n in sorted(set(va) | set(vb))
                    if json.dumps(va.get(n), sort_keys=True) != json.dumps(vb.get(n), sort_keys=True)]
        elif json.dumps(va, sort_keys=True) != json.dumps(vb, sort_keys=True):
            out.append(k)
    return out


def without_fog_copies(snap):
    """``snap`` without the inputs of the fog's Surface nodes, the links into them and their stamps."""
    mats = {}
    for name, (tree, props, sampling) in snap["materials"].items():
        if tree is not None:
            nodes, links = tree
            nodes = {n: (v if n != FOG_NODE else (v[0], v[1], {}, v[3], {})) for n, v in nodes.items()}
            tree = (nodes, [link for link in links if link[2] != FOG_NODE])
        mats[name] = (tree, props, sampling)
    return {**snap, "materials": mats}


def fog_follows_edit():
    """The fog's copies show the edit: Diffuse's new Base Color, Glossy's Roughness from the user's node."""
    color = bpy.data.materials["Diffuse"].node_tree.nodes[FOG_NODE].inputs["Base Color"].default_value
    rough = bpy.data.materials["Glossy"].node_tree.nodes[FOG_NODE].inputs["Roughness"]
    return (all(abs(a - b) < 1e-6 for a, b in zip(color, EDIT_COLOR))
            and rough.is_linked and rough.links[0].from_node.name == EDIT_NODE)


def _principled(mat):
    return next(n for n in mat.node_tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")


def user_edit():
    """What a user might do to fogged materials: change a value, add a node linked into the BSDF.

    Returns the undo: a function putting the materials back as they were.
    """
    base = _principled(bpy.data.materials["Diffuse"]).inputs["Base Color"]
    old_color = tuple(base.default_value)
    base.default_value = EDIT_COLOR
    tree = bpy.data.materials["Glossy"].node_tree
    val = tree.nodes.new("ShaderNodeValue")
    val.name = val.label = EDIT_NODE
    val.location = (-400, -400)
    val.outputs[0].default_value = 0.6
    tree.links.new(val.outputs[0], _principled(bpy.data.materials["Glossy"]).inputs["Roughness"])

    def undo():   # by name: the file may have been reopened since
        _principled(bpy.data.materials["Diffuse"]).inputs["Base Color"].default_value = old_color
        glossy = bpy.data.materials["Glossy"].node_tree
        glossy.nodes.remove(glossy.nodes[EDIT_NODE])
    return undo


def user_edit_present():
    color = tuple(_principled(bpy.data.materials["Diffuse"]).inputs["Base Color"].default_value)
    rough = _principled(bpy.data.materials["Glossy"]).inputs["Roughness"]
    return (all(abs(a - b) < 1e-6 for a, b in zip(color, EDIT_COLOR))
            and rough.is_linked and rough.links[0].from_node.name == EDIT_NODE)


def user_setup():
    """User values for the settings the fog overrides (not the defaults), user nodes named like the fog's."""
    bpy.data.materials["Diffuse"].cycles.emission_sampling = "FRONT"
    bpy.data.materials["Glossy"].cycles.emission_sampling = "BACK"
    world = bpy.context.scene.world
    world.cycles.sampling_method = "MANUAL"
    for tree in (bpy.data.materials["Glossy"].node_tree, world.node_tree):
        node = tree.nodes.new("ShaderNodeValue")
        node.name = node.label = USER_NODE
        node.location = (-400, 300)


def overridden():
    """Both overrides on: every material's emission sampling and the World's sampling method are "NONE"."""
    return (all(m.cycles.emission_sampling == "NONE" for m in bpy.data.materials)
            and bpy.context.scene.world.cycles.sampling_method == "NONE")


def tagged():
    """"kind/name" of each material, world and light holding a node tagged as the fog's."""
    return sorted(f"{kind}/{idb.name}" for kind in ("materials", "worlds", "lights") for idb in getattr(bpy.data, kind)
                  if idb.node_tree is not None and any(TAG in n for n in idb.node_tree.nodes))


def user_nodes_kept():
    trees = (bpy.data.materials["Glossy"].node_tree, bpy.context.scene.world.node_tree)
    return all(USER_NODE in t.nodes and TAG not in t.nodes[USER_NODE] for t in trees)


def main():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    fog_addon.register()
    spheres.build(bpy.context.scene)
    user_setup()
    before = snapshot()
    assert bpy.ops.fog.add(density=0.1) == {"FINISHED"}
    once = snapshot()
    overrides_on, tagged_on, kept_by_add = overridden(), tagged(), user_nodes_kept()
    assert bpy.ops.fog.add(density=0.1) == {"FINISHED"}
    twice = snapshot()
    undo_edit = user_edit()
    edited = snapshot()
    assert bpy.ops.fog.add(density=0.1) == {"FINISHED"}
    edit_kept_by_add = user_edit_present()
    fog_follows = fog_follows_edit()
    thrice = snapshot()
    try:   # an operator that reports an error raises in bpy.ops
        bad = bpy.ops.fog.add(density=float("nan"))
    except RuntimeError as e:
        bad = {"CANCELLED"} if "must be finite" in str(e) else {str(e)}
    after_bad = snapshot()
    path = os.path.join(tempfile.mkdtemp(), "fogged.blend")   # the tags and kept values must survive a reload
    bpy.ops.wm.save_as_mainfile(filepath=path)
    bpy.ops.wm.open_mainfile(filepath=path)
    reopened = snapshot()
    assert bpy.ops.fog.remove() == {"FINISHED"}
    edit_kept_by_remove = user_edit_present()
    tagged_off, kept_by_remove = tagged(), user_nodes_kept()
    undo_edit()   # pre-fog materials plus the edit, minus the edit
    after = snapshot()
    fog_addon.unregister()
    print(json.dumps({
        "fog_changed_something": once != before,
        "overrides_on": overrides_on,
        "tagged_after_add": tagged_on,
        "tagged_after_remove": tagged_off,
        "user_nodes_kept": kept_by_add and kept_by_remove,
        "changed_by_second_add": differing(once, twice),
        "changed_by_add_after_edit": differing(without_fog_copies(edited), without_fog_copies(thrice)),
        "fog_follows_edit": fog_follows,
        "edit_kept_by_add": edit_kept_by_add,
        "edit_kept_by_remove": edit_kept_by_remove,
        "nan_cancelled": bad == {"CANCELLED"} and after_bad == thrice,
        "changed_by_reopen": differing(after_bad, reopened),
        "not_restored": differing(before, after),
    }))


if __name__ == "__main__":
    main()
