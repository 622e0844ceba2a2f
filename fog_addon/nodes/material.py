"""Insert the fog into a material, and take it out again exactly.

The user's nodes and values are never edited: for each engine the fog reads
the user's shader through a scale and an add and feeds an output node of its
own with an exact target (CYCLES, EEVEE), which Blender prefers over an
output for ALL.  Where the user already has an output with that exact target,
that output's Surface link is routed through the fog instead (Blender would
prefer the user's node, and only one output per tree can be active), and
removing the fog links it back.  Removing the fog deletes the nodes it added
(tagged as its own, see ``owned.py``), so user edits made in between survive.
Adding the fog to a fogged material compares what its fog nodes were built
from (a stamp kept on the ``AnalyticFog Surface`` node, see ``graph.stamp``)
with the user's nodes now: unchanged, nothing is touched (adding twice is the
same as once); changed (a Principled value the fog copies, a link, the shader
plugged into the output), the fog nodes are rebuilt in place, so the fog
follows the edit.

A camera ray that meets a fogged surface sees (Sun et al. 2005 Eq. 19)

    s * S + (1 - s) * P + o * (airlight + fog light scattered onto the surface)

with S the user's shader, s = e^{-beta D_vp} (times EEVEE's Direct
Attenuation), P the shader's pass-through part and o its opacity.  How each
kind of material comes out (how the shader is read: ``graph.py``):

* Emission (Emission shader, Principled Emission): dimmed by e^{-beta D_vp}
  like everything else and restored exactly on remove.  EEVEE's extra
  direct-light factor is given back to the emission (an emission of
  (T - s) times the user's emission, read from the shader), so emission is
  dimmed by T alone in both engines (a Principled emission under coat or
  sheen is given back as if uncoated).
* Transparent BSDF, Principled Alpha < 1, Mix / Add with those: the part
  that lets light through is not dimmed (P keeps its full weight: what is
  seen through it is fogged by its own distance, so dimming it would fog it
  twice) and the airlight is weighted by the opacity o, so a transparent
  surface stays exactly as transparent and adds no airlight of its own.
  Transparency inside a user's node group cannot be weighted from outside
  it and is reported.
* Holdout: a holdout stays an exact holdout (alpha 0 in film-transparent
  renders, colour 0) with no airlight in front of it.  A holdout marks where
  the compositor puts something else: live footage that already went through
  the real atmosphere, or another render layer that gets its own fog.
  Either way, fog added here would be counted twice, and a partly opaque
  hole would show the plate dimmed.  (The physical alternative, which the
  fog gave before: airlight A at alpha 1 - T in the hole, so that "plate
  under render" gives A + T plate; right only for a plate with no
  atmosphere of its own and no fog added to it later.)  Holdouts mixed with
  other shaders keep their holdout weight the same way.  A material that
  only lets light through (pure Transparent BSDF or Holdout) is left
  untouched.
* Volume (a Volume output linked): the surface is fogged as above and the
  volume is passed to the fog's outputs unchanged; the volume's own light is
  not dimmed by the fog in front of it (reported where the surface lets the
  volume be seen).  A volume-only material is left without fog and reported.
* Shared materials are fogged once; every object using them sees the same
  fog (it depends on each shading point only).
* Several Material Outputs: each engine's effective output is fogged.
* Other reflecting shaders than Principled and Diffuse BSDFs get no fog
  light (reported).
* Linked (library) and library-override materials are read-only (the fog's
  nodes would not be saved): reported, nothing changed.  Grease Pencil
  materials and materials with no surface shader connected are left without
  fog and reported.
* A fogged material without emission of its own gets Cycles' emission
  sampling off while fogged (``overrides.py``).
* The fog passes (``passes.py``) are written inside the Surface group; a
  material that lets light through gives the group its opacity o (input
  ``Opacity``), so the passes hold what it adds.

The weights, the opacity o and the emission given back are built by
``sockets.NodeOps``: constant parts fold in Python and make no nodes.
"""
import bpy

from . import glass_tails, graph, groups, overrides, owned, passes
from .graph import BLACK, TARGETS, WHITE
from .sockets import NodeOps, Val

STAMP = "analytic_fog_signature"   # on the fog's Surface node: graph.stamp of what it was built from


class _Terms(NodeOps):
    """NodeOps whose nodes are the fog's own (tagged ``Term N``); ``memo`` shares weight nodes."""

    def __init__(self, tree, x0, y0):
        super().__init__(tree, x0=x0, y0=y0)
        self.count, self.memo = 0, {}

    def node(self, bl_idname, col, **props):
        n = owned.mark(super().node(bl_idname, col, **props), f"Term {self.count}", named=False)
        self.count += 1
        return n


def _colour(ops, c):
    """A colour (socket or 3-tuple) as a vector Val."""
    return ops.wrap(c, vector=True)


def _scalar(ops, v):
    """A scalar (socket or float) as a scalar Val (a vector socket is read as a scalar, like a link would)."""
    return Val(ops, sock=v) if isinstance(v, bpy.types.NodeSocket) else ops.const(v)


def _factor(ops, f, memo):
    """A weight factor (see ``graph``) as a Val: a float, or its socket clamped to [0, 1] (1 minus that)."""
    if isinstance(f, float):
        return f
    sock, inverted = f
    key = ("factor", graph.skey(sock), inverted)
    if key not in memo:
        clamped = key[:2] + (False,)
        if clamped not in memo:
            memo[clamped] = ops.clamp(_scalar(ops, sock))
        memo[key] = 1.0 - memo[clamped] if inverted else memo[clamped]
    return memo[key]


def _weight(ops, weight, memo):
    """``weight`` (a tuple of factors) as a Val, the product taken left to right; ``memo`` shares nodes."""
    w, keys = ops.const(1.0), graph.weight_key(weight)
    for i, f in enumerate(weight):
        key = ("weight",) + keys[:i + 1]
        if key not in memo:
            memo[key] = w * _factor(ops, f, memo)
        w = memo[key]
    return w


def _opacity(ops, kinds, weights):
    """o = max(0, 1 - sum of the pass-through parts' weights times colours) (``weights``: their Vals)."""
    o = ops.wrap(WHITE)
    for w, (_, _, c) in zip(weights, kinds.passes):
        o = o - _colour(ops, c) * w
    return ops.maximum(o, BLACK)


def _lets_all_through(kinds):
    """True if the shader only lets light through (Transparent BSDF, Holdout): nothing to fog."""
    if kinds.opaque or kinds.emitters or kinds.hidden or not kinds.constant_passes():
        return False
    ops = NodeOps(None)   # constants only: folds without making a node
    return _opacity(ops, kinds, [_weight(ops, w, {}) for w, _, _ in kinds.passes]).const == BLACK


def _set_value(dst, v):
    """Set input ``dst`` to ``v`` (a float or a tuple), converting between scalar, vector and colour."""
    size = len(dst.default_value) if hasattr(dst.default_value, "__len__") else 0
    if size and not isinstance(v, tuple):
        v = (v, v, v, 1.0)
    elif not size and isinstance(v, tuple):
        v = sum(v[:3]) / 3.0
    if size:
        v = (tuple(v) + (1.0,) * size)[:size]
    dst.default_value = v


def _set_copy(tree, dst, v):
    """Link source socket ``v`` into ``dst``, or set ``dst`` to the value ``v``."""
    if isinstance(v, bpy.types.NodeSocket):
        tree.links.new(v, dst)
    else:
        _set_value(dst, v)


def wrap_material(mat):
    """Add the fog to ``mat`` (rebuilding it if there); returns a reason or note string, else None.

    Adding twice is the same as once; adding after an edit follows the edit.
    """
    why = owned.read_only(mat)
    if why:
        return why
    if getattr(mat, "is_grease_pencil", False):
        return "is a Grease Pencil material: left without fog"
    tree = mat.node_tree
    if tree is None:
        return "has no node tree"
    outs, srcs, kinds = graph.plan(tree)
    volume = any(o is not None and graph.source(o.inputs["Volume"]) is not None for o in outs.values())
    if not any(srcs.values()):
        unwrap_material(mat)
        if volume:
            return ("has only a volume shader: left without fog (the fog does not dim volumes; "
                    "what is seen through it is fogged)")
        return "has no surface shader connected to a Material Output"
    if all(_lets_all_through(k) for k in kinds.values()):
        unwrap_material(mat)
        if volume:
            return ("its surface only lets light through and its volume shader is left as it is: the fog does "
                    "not dim the volume (what is seen through it is fogged)")
        return None
    first = kinds[next(iter(kinds))]
    copies = graph.bsdf_copies(first.reads)
    lost = [name for name, _, ok in copies if not ok]
    built = graph.built_from(outs, srcs, kinds, copies)
    built["passes"] = passes.VERSION   # a material fogged before the fog passes is rebuilt once
    glass, glass_weight = _glass_copies(kinds, srcs)
    built["glass"] = [(name, graph.skey(v) if isinstance(v, bpy.types.NodeSocket) else v) for name, v in glass]
    built["glass weight"] = None if glass_weight is None else graph.weight_key(glass_weight)
    fog = owned.find(tree, "Surface")
    if (fog is not None and fog.bl_idname == "ShaderNodeGroup"
            and fog.node_tree == bpy.data.node_groups.get(groups.SURFACE)
            and fog.get(STAMP) == graph.stamp(built, tree)):
        return _notes(mat, kinds, lost) or None   # fogged, and nothing it reads has changed
    # rebuild from the user's current nodes (the sockets found above are all the user's), in the same place
    anchor = tuple(fog.location) if fog is not None else None
    unwrap_material(mat)
    fog = _build(tree, anchor, outs, srcs, kinds, copies + [(name, v, True) for name, v in glass], glass_weight)
    fog[STAMP] = graph.stamp(built, tree)
    if not any(k.emitters for k in kinds.values()):
        # the fog's emission is for camera rays only: as a light it would only steal light samples
        overrides.override(mat, "cycles.emission_sampling", "NONE")
    return _notes(mat, kinds, lost) or None


def _dim_emitted_light(ops, tree, emitting, last, location):
    """Cycles: a glowing surface's light that reaches another surface (every ray but the camera's: Ray Length is
    the path's length through the fog) dimmed by e^{-beta Ray Length} (Sun et al. 2005 Eq. 14, as the lights'
    own node trees do, ``light.py``): an emission of (e^{-beta L} - 1) times the user's added to ``last``.  The
    camera's rays are dimmed by the Attenuate mix already."""
    total = ops.wrap(BLACK)
    for w, c, s in emitting:
        total = total + _colour(ops, c) * _scalar(ops, s) * _weight(ops, w, ops.memo)
    params = owned.add(tree, "ShaderNodeGroup", "Cycles Emission Params", (location[0] - 300, location[1]), named=False)
    params.node_tree = bpy.data.node_groups[groups.PARAMS]
    path = owned.add(tree, "ShaderNodeLightPath", "Cycles Emission Path", (location[0] - 300, location[1] - 150),
                     named=False)
    beta, length = _scalar(ops, params.outputs["Beta"]), _scalar(ops, path.outputs["Ray Length"])
    off_camera = 1.0 - _scalar(ops, path.outputs["Is Camera Ray"])
    dim = owned.add(tree, "ShaderNodeEmission", "Cycles Emission Dimmed", location, named=False)
    ops.feed(dim.inputs["Color"], total * ((ops.exp(-1.0 * beta * length) - 1.0) * off_camera))
    add = owned.add(tree, "ShaderNodeAddShader", "Cycles Add Dimmed", (location[0] + 75, location[1] + 60), named=False)
    tree.links.new(last, add.inputs[0])
    tree.links.new(dim.outputs[0], add.inputs[1])
    return add.outputs[0]


def _build(tree, anchor, outs, srcs, kinds, copies, glass_weight=None):
    """Make the fog's nodes in ``tree`` (at ``anchor``, or beside the user's nodes); returns its Surface node.
    ``glass_weight``: the weight of the glass in its mix (``_glass_copies``), or None."""
    x0, y0 = anchor or (max((n.location.x for n in tree.nodes), default=0) + 300,
                        min((n.location.y for n in tree.nodes), default=0) - 300)
    ops = _Terms(tree, x0 - 400, y0 - 900)
    fog = owned.add(tree, "ShaderNodeGroup", "Surface", (x0, y0))   # named: where a script finds the fog
    fog.node_tree = bpy.data.node_groups[groups.SURFACE]
    for name, v, _ in copies:
        _set_copy(tree, fog.inputs[name], v)
    if glass_weight:   # glass in a mix: the share of the light that passes, times its own (Transmission Weight)
        own = fog.inputs[glass_tails.GLASS_WEIGHT]
        factor = (_scalar(ops, own.links[0].from_socket) if own.is_linked
                  else ops.const(float(own.default_value)))
        ops.feed(own, _weight(ops, glass_weight, ops.memo) * factor)
    transmittance = _scalar(ops, fog.outputs["Transmittance"])
    shared = {}   # per shader source: (the fog light as a shader, pass-through shader or None)
    for k, target in enumerate(TARGETS):
        out, src = outs[target], srcs[target]
        if src is None:
            continue
        key = graph.skey(src)
        kd = kinds[key]
        if key not in shared:
            shared[key] = _fog_light(ops, tree, kd, fog, len(shared), (x0, y0))
        fog_shader, passed = shared[key]
        y = y0 - 250 * (k + 1)
        # 1 - scale of the user's shader: e^{-beta D_vp}, in EEVEE times the Direct Attenuation
        # (EEVEE ignores light node trees: direct light is attenuated here)
        mix_factor = fog.outputs[f"{'EEVEE' if target == 'EEVEE' else 'Cycles'} Mix Factor"]
        mix = owned.add(tree, "ShaderNodeMixShader", f"{target} Attenuate", (x0 + 500, y), named=False)
        tree.links.new(mix_factor, mix.inputs[0])
        tree.links.new(src, mix.inputs[1])
        if passed is not None:   # what lets light through keeps its weight: s P + (1 - s) P
            tree.links.new(passed, mix.inputs[2])
        last = mix.outputs[0]
        emitting = [e for e in kd.emitters if not graph.is_zero(e[0])]
        if target == "EEVEE" and emitting:   # emission is dimmed by T only: give back (T - s) E
            total = ops.wrap(BLACK)
            for w, c, s in emitting:
                total = total + _colour(ops, c) * _scalar(ops, s) * _weight(ops, w, ops.memo)
            back = owned.add(tree, "ShaderNodeEmission", f"{target} Emission Restore", (x0 + 500, y - 120), named=False)
            ops.feed(back.inputs["Color"], total * (transmittance - (1.0 - _scalar(ops, mix_factor))))
            add_back = owned.add(tree, "ShaderNodeAddShader", f"{target} Add Restore", (x0 + 575, y - 60), named=False)
            tree.links.new(last, add_back.inputs[0])
            tree.links.new(back.outputs[0], add_back.inputs[1])
            last = add_back.outputs[0]
        if target == "CYCLES" and emitting:
            last = _dim_emitted_light(ops, tree, emitting, last, (x0 + 500, y - 120))
        add = owned.add(tree, "ShaderNodeAddShader", f"{target} Add", (x0 + 650, y), named=False)
        tree.links.new(last, add.inputs[0])
        tree.links.new(fog_shader, add.inputs[1])
        if target == "CYCLES":   # the glows past glass and mirrors: Cycles traces those segments, EEVEE doesn't
            see = owned.add(tree, "ShaderNodeAddShader", f"{target} See Through", (x0 + 725, y - 60), named=False)
            tree.links.new(add.outputs[0], see.inputs[0])
            tree.links.new(fog.outputs[glass_tails.SEE_THROUGH], see.inputs[1])
            add = see
        if out.target == target:   # the user's own output for this engine: route it through the fog
            tree.links.new(add.outputs[0], out.inputs["Surface"])
            continue
        new_out = owned.add(tree, "ShaderNodeOutputMaterial", f"{target} Output", (x0 + 800, y), named=False,
                            target=target)
        tree.links.new(add.outputs[0], new_out.inputs["Surface"])
        for sock in out.inputs:
            link = graph.link_into(sock)
            if sock.name != "Surface" and link is not None and sock.name in new_out.inputs:
                tree.links.new(link.from_socket, new_out.inputs[sock.name])
    return fog


def _glass_copies(kinds, srcs):
    """([(Surface group input, value or source socket)], the glass's weight in its mix or None) for the glass in a
    material's shader (``graph.Kinds.glass``: the first, not inside a group): a Glass BSDF (its Color and IOR), a
    Refraction BSDF (its Color), or a Principled BSDF that lets light through (its Base Color, IOR and Transmission
    Weight; its reflection is its own glossy fog light), rough or not, on its own or in a Mix or Add Shader
    (Cycles weighs the glass's paths by its weight there; ``_build`` multiplies Glass Weight by it):
    ``glass_tails.place_tails`` adds the fog past it in Cycles.  ([], None) without glass."""
    def value(sock):
        return graph.source(sock) or graph.own_value(sock)
    for src in srcs.values():
        glass = None if src is None else kinds[graph.skey(src)].glass
        if glass is None:
            continue
        weight, node = glass
        weight = weight or None   # (the shader itself: its weight is 1)
        if node.bl_idname == "ShaderNodeBsdfGlass":
            return [(glass_tails.GLASS_COLOR, value(node.inputs["Color"])),
                    (glass_tails.GLASS_IOR, value(node.inputs["IOR"]))], weight
        if node.bl_idname == "ShaderNodeBsdfRefraction":   # all its light passes: no Fresnel (IOR 1), no reflection
            return [(glass_tails.GLASS_COLOR, value(node.inputs["Color"])), (glass_tails.GLASS_IOR, 1.0),
                    (glass_tails.GLASS_MIRRORED, 0.0)], weight
        return [(glass_tails.GLASS_COLOR, value(node.inputs["Base Color"])),
                (glass_tails.GLASS_IOR, value(node.inputs["IOR"])),
                (glass_tails.GLASS_WEIGHT, value(node.inputs["Transmission Weight"])),
                (glass_tails.GLASS_MIRRORED, 0.0)], weight
    return [], None


def _fog_light(ops, tree, kd, fog, n, origin):
    """(the shader adding o times the fog's light, the shader's pass-through part P or None) for shader ``kd``.

    The first shader source takes the Surface group's Fog shader (one Emission closure per light, which
    keeps Cycles' SVM stack bounded whatever the number of lights), its opacity given to the group; a
    second source (a material with other outputs per engine) gets an Emission of the summed colour.
    """
    x0, y0 = origin
    weights = [_weight(ops, w, ops.memo) for w, _, _ in kd.passes]
    opacity = _opacity(ops, kd, weights)
    if n == 0:   # the group's fog light and passes hold what is added: weighted by the first shader's opacity
        passes.weight_surface(ops, fog, opacity)
        fog_shader = fog.outputs["Fog"]
    else:
        emit = owned.add(tree, "ShaderNodeEmission", f"Emission {n + 1}", (x0 + 200, y0 - 120 * n), named=False)
        ops.feed(emit.inputs["Color"], _colour(ops, fog.outputs["Emission"]) * opacity)
        fog_shader = emit.outputs[0]
    passed = None
    for w, (_, shader, _) in zip(weights, kd.passes):
        if shader is None:   # Principled 1 - Alpha: a white Transparent BSDF
            shader = (owned.find(tree, "Transparent") or owned.add(
                tree, "ShaderNodeBsdfTransparent", "Transparent", (x0 - 200, y0 - 700), named=False)).outputs[0]
        term = shader
        if w.const != 1.0:
            mix = ops.node("ShaderNodeMixShader", w.col + 1)
            ops.feed(mix.inputs[0], w)
            tree.links.new(shader, mix.inputs[2])   # input 1 stays empty: w * shader
            term = mix.outputs[0]
        if passed is None:
            passed = term
        else:
            add = ops.node("ShaderNodeAddShader", w.col + 2)
            tree.links.new(passed, add.inputs[0])
            tree.links.new(term, add.inputs[1])
            passed = add.outputs[0]
    return fog_shader, passed


def _notes(mat, kinds, lost):
    notes = []
    hidden = sorted({g for k in kinds.values() for g in k.hidden})
    if hidden:
        notes.append(f"transparency or a holdout inside node group {', '.join(map(repr, hidden))} is dimmed by "
                     "the fog like the rest (only Transparent BSDF, Holdout and Principled Alpha outside groups "
                     "keep their pass-through)")
    unread = sorted({u for k in kinds.values() if k.reads is None for u in k.unread})
    if unread:
        notes.append(f"the fog reads only Principled and Diffuse BSDFs: no fog light scattered onto its "
                     f"{', '.join(unread)}")
    if lost:
        notes.append(f"its BSDF's {', '.join(lost)} {'is' if len(lost) == 1 else 'are'} computed inside a node "
                     "group: the fog light scattered onto it uses the socket's own value")
    outs = [graph.effective_output(mat.node_tree, t, users_only=True) for t in TARGETS]
    vol = any(o is not None and graph.source(o.inputs["Volume"]) is not None for o in outs)
    if vol and any(k.passes for k in kinds.values()):
        notes.append("its volume, seen through its transparent surface, is not dimmed by the fog")
    return "; ".join(notes)


def unwrap_material(mat):
    """Take the fog out of ``mat``: delete its nodes, link the user's outputs it took over back,
    give back the Cycles settings it changed."""
    tree = mat.node_tree
    if tree is None or owned.read_only(mat):
        return
    overrides.restore(mat)
    back = []
    for link in tree.links:
        if owned.is_ours(link.from_node) and not owned.is_ours(link.to_node):
            target = owned.role_of(link.from_node).split(" ")[0]
            mix = owned.find(tree, f"{target} Attenuate")
            src = (graph.link_into(mix.inputs[1])
                   if mix is not None and mix.bl_idname == "ShaderNodeMixShader" else None)
            if src is not None and not owned.is_ours(src.from_node):
                back.append((src.from_node.name, src.from_socket.identifier, link.to_node.name,
                             link.to_socket.identifier))
    owned.remove_ours(tree)
    for from_node, from_id, to_node, to_id in back:
        src = next(s for s in tree.nodes[from_node].outputs if s.identifier == from_id)
        dst = next(s for s in tree.nodes[to_node].inputs if s.identifier == to_id)
        tree.links.new(src, dst)
