"""Insert the fog's airlight and background extinction into a World, and take them out again.

The background is seen through infinite fog: camera rays see only the fog's
airlight (black where no lamp glows), other rays (reflection, GI) only the
user's world, through a Mix Shader whose factor is exactly 0 or 1 (1 minus
the World group's Transmittance).  A factor of exactly 0 or 1 lets Cycles
skip the other branch, so its world importance map (evaluated without the
camera flag) does not run the fog's nodes (~50 s per render otherwise).  A
World of one colour gets no importance map at all while fogged
(``overrides.py``).  Linked and library-override Worlds are read-only:
reported, nothing changed.
"""
import bpy

from . import graph, groups, overrides, owned


def _constant_shader(sock):
    """True if nothing or an unlinked Background / Emission feeds ``sock``: a world of one colour."""
    src = graph.source(sock)
    return src is None or (src.node.bl_idname in graph.EMITTERS and not any(i.is_linked for i in src.node.inputs))


def wrap_world(world):
    """Add the fog's airlight and background extinction to ``world``; returns a reason string, else None.

    Adding twice is the same as once.
    """
    why = owned.read_only(world)
    if why:
        return why
    if world.node_tree is None:
        return "has no node tree"
    if owned.is_fogged(world):
        return None
    tree = world.node_tree
    x0 = max((n.location.x for n in tree.nodes), default=0) + 300
    fog = owned.add(tree, "ShaderNodeGroup", "World", (x0, -300))
    fog.node_tree = bpy.data.node_groups[groups.WORLD]
    inv = owned.add(tree, "ShaderNodeMath", "Mix Factor", (x0 + 200, -450), operation="SUBTRACT")
    inv.inputs[0].default_value = 1.0
    tree.links.new(fog.outputs["Transmittance"], inv.inputs[1])
    for k, target in enumerate(graph.TARGETS):
        out = graph.effective_output(tree, target)
        y = -600 - 200 * k
        # camera rays (mix factor 1) see only the airlight, other rays only the user's world
        mix = owned.add(tree, "ShaderNodeMixShader", f"{target} Mix", (x0 + 350, y))
        tree.links.new(inv.outputs[0], mix.inputs[0])
        if out is not None and out.inputs["Surface"].is_linked:
            tree.links.new(out.inputs["Surface"].links[0].from_socket, mix.inputs[1])
        tree.links.new(fog.outputs["Fog"], mix.inputs[2])   # the glow: a Background closure per light
        new_out = owned.add(tree, "ShaderNodeOutputWorld", f"{target} Output", (x0 + 650, y), target=target)
        tree.links.new(mix.outputs[0], new_out.inputs["Surface"])
        if out is not None and out.inputs["Volume"].is_linked:
            tree.links.new(out.inputs["Volume"].links[0].from_socket, new_out.inputs["Volume"])
    cycles_out = graph.effective_output(tree, "CYCLES", users_only=True)
    if cycles_out is None or _constant_shader(cycles_out.inputs["Surface"]):
        overrides.override(world, "cycles.sampling_method", "NONE")
    return None


def unwrap_world(world):
    """Take the fog out of ``world``: delete its nodes, give back the Cycles setting it changed."""
    if world.node_tree is None or owned.read_only(world):
        return
    overrides.restore(world)
    owned.remove_ours(world.node_tree)
