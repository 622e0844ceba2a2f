"""Insert the fog into materials, the World and lights, and take it out again exactly.

Nothing of the user's is edited: for each engine the fog adds its own output
node with an exact target (CYCLES, EEVEE), which Blender prefers over an
output for ALL, reading the user's shader through a scale and an add.
Removing the fog deletes the nodes it added (all named ``AnalyticFog ...``),
so user edits made in between survive.
"""
import bpy

from . import groups

PREFIX = "AnalyticFog"
TARGETS = ("CYCLES", "EEVEE")
_PRINCIPLED_INPUTS = ("Base Color", "Metallic", "Roughness", "Specular IOR Level")
_OUTPUT_TYPES = ("ShaderNodeOutputMaterial", "ShaderNodeOutputWorld")


def _ours(node):
    return node.name.startswith(PREFIX)


def effective_output(tree, target):
    """The output node ``target``'s engine renders: exact target beats ALL, then the active one."""
    best = None
    for n in tree.nodes:
        if n.bl_idname not in _OUTPUT_TYPES or n.target not in ("ALL", target):
            continue
        if best is None:
            best = n
        elif best.target == "ALL" and n.target == target:
            best = n
        elif best.target == n.target and n.is_active_output and not best.is_active_output:
            best = n
    return best


def _add(tree, bl_idname, name, location, **props):
    n = tree.nodes.new(bl_idname)
    n.name = n.label = f"{PREFIX} {name}"
    n.location = location
    for k, v in props.items():
        setattr(n, k, v)
    return n


def is_fogged(idblock):
    return idblock.node_tree is not None and any(_ours(n) for n in idblock.node_tree.nodes)


def _principled_source(tree, out):
    link = out.inputs["Surface"].links[0] if out.inputs["Surface"].is_linked else None
    node = link.from_node if link else None
    return node if node is not None and node.bl_idname == "ShaderNodeBsdfPrincipled" else None


def wrap_material(mat):
    """Add the fog to ``mat``; returns a reason string if it can't, else None.  Idempotent."""
    tree = mat.node_tree
    if tree is None:
        return "has no node tree"
    if is_fogged(mat):
        return None
    outs = {t: effective_output(tree, t) for t in TARGETS}
    if not any(o is not None and o.inputs["Surface"].is_linked for o in outs.values()):
        return "has no surface shader connected to a Material Output"
    x0, y0 = max((n.location.x for n in tree.nodes), default=0) + 300, min((n.location.y for n in tree.nodes), default=0) - 300
    fog = _add(tree, "ShaderNodeGroup", "Surface", (x0, y0))
    fog.node_tree = bpy.data.node_groups[groups.SURFACE]
    principled = next((p for p in (_principled_source(tree, o) for o in outs.values() if o) if p), None)
    for name in _PRINCIPLED_INPUTS:
        if principled is not None and name in principled.inputs:
            src = principled.inputs[name]
            if src.is_linked:
                tree.links.new(src.links[0].from_socket, fog.inputs[name])
            else:
                fog.inputs[name].default_value = src.default_value
    emit = _add(tree, "ShaderNodeEmission", "Emission", (x0 + 200, y0))
    tree.links.new(fog.outputs["Emission"], emit.inputs["Color"])
    for k, target in enumerate(TARGETS):
        out = outs[target]
        if out is None or not out.inputs["Surface"].is_linked:
            continue
        y = y0 - 250 * (k + 1)
        fac = _add(tree, "ShaderNodeMath", f"{target} Scale", (x0 + 200, y), operation="MULTIPLY")
        tree.links.new(fog.outputs["Transmittance"], fac.inputs[0])
        if target == "EEVEE":   # EEVEE ignores light node trees: attenuate direct light here
            tree.links.new(fog.outputs["Direct Attenuation"], fac.inputs[1])
        else:
            fac.inputs[1].default_value = 1.0
        inv = _add(tree, "ShaderNodeMath", f"{target} Mix Factor", (x0 + 350, y), operation="SUBTRACT")
        inv.inputs[0].default_value = 1.0
        tree.links.new(fac.outputs[0], inv.inputs[1])
        mix = _add(tree, "ShaderNodeMixShader", f"{target} Attenuate", (x0 + 500, y))
        tree.links.new(inv.outputs[0], mix.inputs[0])
        tree.links.new(out.inputs["Surface"].links[0].from_socket, mix.inputs[1])   # input 2 stays empty: no closure
        add = _add(tree, "ShaderNodeAddShader", f"{target} Add", (x0 + 650, y))
        tree.links.new(mix.outputs[0], add.inputs[0])
        tree.links.new(emit.outputs[0], add.inputs[1])
        new_out = _add(tree, "ShaderNodeOutputMaterial", f"{target} Output", (x0 + 800, y), target=target)
        tree.links.new(add.outputs[0], new_out.inputs["Surface"])
        for sock in out.inputs:
            if sock.name != "Surface" and sock.is_linked and sock.name in new_out.inputs:
                tree.links.new(sock.links[0].from_socket, new_out.inputs[sock.name])
    return None


def wrap_world(world):
    """Add the fog's airlight and background extinction to ``world``.  Idempotent."""
    if world.node_tree is None:
        return "has no node tree"
    if is_fogged(world):
        return None
    tree = world.node_tree
    x0 = max((n.location.x for n in tree.nodes), default=0) + 300
    fog = _add(tree, "ShaderNodeGroup", "World", (x0, -300))
    fog.node_tree = bpy.data.node_groups[groups.WORLD]
    bg = _add(tree, "ShaderNodeBackground", "Airlight", (x0 + 200, -300))
    tree.links.new(fog.outputs["Emission"], bg.inputs["Color"])
    inv = _add(tree, "ShaderNodeMath", "Mix Factor", (x0 + 200, -450), operation="SUBTRACT")
    inv.inputs[0].default_value = 1.0
    tree.links.new(fog.outputs["Transmittance"], inv.inputs[1])
    for k, target in enumerate(TARGETS):
        out = effective_output(tree, target)
        y = -600 - 200 * k
        add = _add(tree, "ShaderNodeAddShader", f"{target} Add", (x0 + 500, y))
        if out is not None and out.inputs["Surface"].is_linked:
            mix = _add(tree, "ShaderNodeMixShader", f"{target} Attenuate", (x0 + 350, y))
            tree.links.new(inv.outputs[0], mix.inputs[0])
            tree.links.new(out.inputs["Surface"].links[0].from_socket, mix.inputs[1])
            tree.links.new(mix.outputs[0], add.inputs[0])
        tree.links.new(bg.outputs[0], add.inputs[1])
        new_out = _add(tree, "ShaderNodeOutputWorld", f"{target} Output", (x0 + 650, y), target=target)
        tree.links.new(add.outputs[0], new_out.inputs["Surface"])
        if out is not None and out.inputs["Volume"].is_linked:
            tree.links.new(out.inputs["Volume"].links[0].from_socket, new_out.inputs["Volume"])
    return None


def unwrap(idblock):
    """Delete every node the fog added to ``idblock``'s tree."""
    tree = idblock.node_tree
    if tree is None:
        return
    for n in [n for n in tree.nodes if _ours(n)]:
        tree.nodes.remove(n)


# --- lights: Cycles attenuates direct light in the light's own node tree ----------

_LIGHT_STATE = "analytic_fog_use_nodes"
_ACTIVE_OUTPUT = "analytic_fog_active_output"


def wrap_light(light_data):
    """Multiply the light's emission strength by e^{-beta * Ray Length} (Sun et al. 2005 Eq. 14).

    In a Cycles light shader Ray Length is the distance from the lit point to
    the light.  EEVEE ignores light node trees (see wrap_material).
    """
    if _LIGHT_STATE in light_data:
        return
    light_data[_LIGHT_STATE] = bool(light_data.use_nodes)
    light_data.use_nodes = True
    tree = light_data.node_tree
    out = next((n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputLight" and n.is_active_output), None)
    if out is None or not out.inputs["Surface"].is_linked:
        return
    src = out.inputs["Surface"].links[0].from_socket
    params = _add(tree, "ShaderNodeGroup", "Params", (-800, 300))
    params.node_tree = bpy.data.node_groups[groups.PARAMS]
    path = _add(tree, "ShaderNodeLightPath", "Light Path", (-800, 100))
    neg = _add(tree, "ShaderNodeMath", "Negative Beta", (-600, 300), operation="MULTIPLY")
    tree.links.new(params.outputs["Beta"], neg.inputs[0])
    neg.inputs[1].default_value = -1.0
    tau = _add(tree, "ShaderNodeMath", "Optical Length", (-450, 200), operation="MULTIPLY")
    tree.links.new(neg.outputs[0], tau.inputs[0])
    tree.links.new(path.outputs["Ray Length"], tau.inputs[1])
    att = _add(tree, "ShaderNodeMath", "Transmittance", (-300, 200), operation="EXPONENT")
    tree.links.new(tau.outputs[0], att.inputs[0])
    fac = _add(tree, "ShaderNodeMath", "Mix Factor", (-150, 200), operation="SUBTRACT")
    fac.inputs[0].default_value = 1.0
    tree.links.new(att.outputs[0], fac.inputs[1])
    mix = _add(tree, "ShaderNodeMixShader", "Attenuate", (50, 200))
    tree.links.new(fac.outputs[0], mix.inputs[0])
    tree.links.new(src, mix.inputs[1])      # input 2 stays empty: no closure
    new_out = _add(tree, "ShaderNodeOutputLight", "Output", (250, 200))
    tree.links.new(mix.outputs[0], new_out.inputs["Surface"])
    light_data[_ACTIVE_OUTPUT] = out.name
    new_out.is_active_output = True


def unwrap_light(light_data):
    if _LIGHT_STATE not in light_data:
        return
    tree = light_data.node_tree
    if tree is not None:
        for n in [n for n in tree.nodes if _ours(n)]:
            tree.nodes.remove(n)
        active = tree.nodes.get(light_data.get(_ACTIVE_OUTPUT, ""))
        if active is not None:
            active.is_active_output = True
    light_data.pop(_ACTIVE_OUTPUT, None)
    light_data.use_nodes = light_data[_LIGHT_STATE]
    del light_data[_LIGHT_STATE]
