"""Cycles attenuates direct light in the light's own node tree; insert that there and take it out again.

The light's emission strength is multiplied by e^{-beta * Ray Length} (Sun
et al. 2005 Eq. 14): in a Cycles light shader Ray Length is the distance
from the lit point to the light, so this is exact per light and keeps
shadows.  EEVEE ignores light node trees (the material attenuates direct
light there, see ``material.py``).  The light's ``use_nodes`` and its active
output are kept on the light and given back on remove; a light that had no
node tree keeps Blender's default one (it renders as before).
"""
import bpy

from . import groups, owned

_USE_NODES = "analytic_fog_use_nodes"           # on the light: its use_nodes before the fog
_ACTIVE_OUTPUT = "analytic_fog_active_output"   # on the light: the name of its active output before the fog


def wrap_light(light_data):
    """Attenuate ``light_data``'s direct light by the fog in Cycles.

    Returns a reason string for a linked or overridden light (left as it is), else None.
    """
    why = owned.read_only(light_data)
    if why:
        return why.replace("left without fog", "its direct light is not dimmed by the fog in Cycles")
    if _USE_NODES in light_data:
        return None
    light_data[_USE_NODES] = bool(light_data.use_nodes)
    light_data.use_nodes = True
    tree = light_data.node_tree
    out = next((n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputLight" and n.is_active_output), None)
    if out is None or not out.inputs["Surface"].is_linked:
        return None
    src = out.inputs["Surface"].links[0].from_socket
    params = owned.add(tree, "ShaderNodeGroup", "Params", (-800, 300))
    params.node_tree = bpy.data.node_groups[groups.PARAMS]
    path = owned.add(tree, "ShaderNodeLightPath", "Light Path", (-800, 100))
    neg = owned.add(tree, "ShaderNodeMath", "Negative Beta", (-600, 300), operation="MULTIPLY")
    tree.links.new(params.outputs["Beta"], neg.inputs[0])
    neg.inputs[1].default_value = -1.0
    tau = owned.add(tree, "ShaderNodeMath", "Optical Length", (-450, 200), operation="MULTIPLY")
    tree.links.new(neg.outputs[0], tau.inputs[0])
    tree.links.new(path.outputs["Ray Length"], tau.inputs[1])
    att = owned.add(tree, "ShaderNodeMath", "Transmittance", (-300, 200), operation="EXPONENT")
    tree.links.new(tau.outputs[0], att.inputs[0])
    fac = owned.add(tree, "ShaderNodeMath", "Mix Factor", (-150, 200), operation="SUBTRACT")
    fac.inputs[0].default_value = 1.0
    tree.links.new(att.outputs[0], fac.inputs[1])
    mix = owned.add(tree, "ShaderNodeMixShader", "Attenuate", (50, 200))
    tree.links.new(fac.outputs[0], mix.inputs[0])
    tree.links.new(src, mix.inputs[1])      # input 2 stays empty: no closure
    new_out = owned.add(tree, "ShaderNodeOutputLight", "Output", (250, 200))
    tree.links.new(mix.outputs[0], new_out.inputs["Surface"])
    light_data[_ACTIVE_OUTPUT] = out.name
    new_out.is_active_output = True
    return None


def unwrap_light(light_data):
    """Take the fog out of ``light_data``: delete its nodes, give back the active output and use_nodes."""
    if _USE_NODES not in light_data or owned.read_only(light_data):
        return
    tree = light_data.node_tree
    if tree is not None:
        owned.remove_ours(tree)
        active = tree.nodes.get(light_data.get(_ACTIVE_OUTPUT, ""))
        if active is not None:
            active.is_active_output = True
    light_data.pop(_ACTIVE_OUTPUT, None)
    light_data.use_nodes = light_data[_USE_NODES]
    del light_data[_USE_NODES]
