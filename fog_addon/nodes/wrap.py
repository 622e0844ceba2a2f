"""Insert the fog into materials, the World and lights, and take it out again exactly.

The user's nodes and values are never edited: for each engine the fog reads
the user's shader through a scale and an add and feeds an output node of its
own with an exact target (CYCLES, EEVEE), which Blender prefers over an
output for ALL.  Where the user already has an output with that exact target,
that output's Surface link is routed through the fog instead (Blender would
prefer the user's node, and only one output per tree can be active), and
removing the fog links it back.  Removing the fog deletes the nodes it added
(all named ``AnalyticFog ...``), so user edits made in between survive.
Adding the fog to a fogged material compares what its fog nodes were built
from (kept on the ``AnalyticFog Surface`` node) with the user's nodes now:
unchanged, nothing is touched (adding twice is the same as once); changed
(a Principled value the fog copies, a link, the shader plugged into the
output), the fog nodes are rebuilt in place, so the fog follows the edit.

A camera ray that meets a fogged surface sees (Sun et al. 2005 Eq. 19)

    s * S + (1 - s) * P + o * (airlight + fog light scattered onto the surface)

with S the user's shader, s = e^{-beta D_vp} (times EEVEE's Direct
Attenuation), P the shader's pass-through part and o its opacity.  How each
kind of material comes out:

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
  The weights are read through Mix Shader factors (values or links),
  Add Shader, reroutes and muted nodes; transparency inside a user's node
  group cannot be weighted from outside it and is reported.
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
* Several Material Outputs (ALL plus CYCLES or EEVEE): each engine's
  effective output (exact target over ALL, then the active one) is fogged.
* Node-group shaders: a Principled (or Diffuse) BSDF inside a group is read
  through the group's inputs; the rest is scaled like any shader.
* Only Principled and Diffuse BSDFs are read for the fog light the surface
  reflects (Sun Eq. 17-18); other reflecting shaders get none (reported).
* Linked (library) and library-override materials, worlds and lights are
  read-only (the fog's nodes would not be saved): reported, nothing changed.
  Grease Pencil materials and materials with no surface shader connected
  are left without fog and reported.
"""
import bpy

from . import groups

PREFIX = "AnalyticFog"
TARGETS = ("CYCLES", "EEVEE")
_PRINCIPLED_INPUTS = ("Base Color", "Metallic", "Roughness", "Specular IOR Level")
_OUTPUT_TYPES = ("ShaderNodeOutputMaterial", "ShaderNodeOutputWorld")
_PASS_THROUGH = ("ShaderNodeBsdfTransparent", "ShaderNodeHoldout")
_EMITTERS = ("ShaderNodeEmission", "ShaderNodeBackground")
WHITE = (1.0, 1.0, 1.0)
BLACK = (0.0, 0.0, 0.0)


def _ours(node):
    return node.name.startswith(PREFIX)


def read_only(idblock):
    """Why the fog must not edit ``idblock`` (linked or overridden library data), or None."""
    if idblock.library is not None:
        return f"is linked from the library {idblock.library.name!r}: read-only, left without fog"
    if idblock.override_library is not None:
        return "is a library override: the fog's nodes would not be saved, left without fog (make it local first)"
    return None


def effective_output(tree, target, users_only=False):
    """The output node ``target``'s engine renders: exact target beats ALL, then the active one.

    ``users_only``: among the user's outputs (the fog's own ignored).
    """
    best = None
    for n in tree.nodes:
        if n.bl_idname not in _OUTPUT_TYPES or n.target not in ("ALL", target) or (users_only and _ours(n)):
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


def _link_into(sock):
    """The first enabled link into input ``sock``, or None."""
    if not sock.is_linked:
        return None
    return next((link for link in sock.links if link.is_valid and not link.is_muted), None)


def _source(sock):
    """The output socket that really feeds input ``sock`` (through reroutes and muted nodes), or None."""
    for _ in range(256):
        link = _link_into(sock)
        if link is None:
            return None
        node, out = link.from_node, link.from_socket
        if node.bl_idname == "NodeReroute":
            sock = node.inputs[0]
        elif node.mute:
            inner = next((il for il in node.internal_links if il.to_socket == out), None)
            if inner is None:
                return None
            sock = inner.from_socket
        else:
            return out
    return None


# --- lazily built scalar and colour expressions ------------------------------------
# A scalar is a float or ("sock", socket) or (op, args...); a colour is a 3-tuple or
# ("csock", socket) or (op, args...).  Constants fold; nodes are made only for what is used.

def _const(x):
    return isinstance(x, float) or (isinstance(x, tuple) and len(x) == 3 and all(isinstance(v, float) for v in x))


def _mul(a, b):
    if isinstance(a, float) and isinstance(b, float):
        return a * b
    if a == 0.0 or b == 0.0:
        return 0.0
    if a == 1.0:
        return b
    if b == 1.0:
        return a
    return ("mul", a, b)


def _sub(a, b):
    if isinstance(a, float) and isinstance(b, float):
        return a - b
    if b == 0.0:
        return a
    return ("sub", a, b)


def _clamp(a):
    return min(max(a, 0.0), 1.0) if isinstance(a, float) else ("clamp", a)


def _cscale(c, s):
    if _const(c) and isinstance(s, float):
        return tuple(v * s for v in c)
    if s == 0.0 or c == BLACK:
        return BLACK
    if s == 1.0:
        return c
    return ("cscale", c, s)


def _cadd(a, b):
    if _const(a) and _const(b):
        return tuple(x + y for x, y in zip(a, b))
    if a == BLACK:
        return b
    if b == BLACK:
        return a
    return ("cadd", a, b)


def _csub(a, b):
    if _const(a) and _const(b):
        return tuple(x - y for x, y in zip(a, b))
    if b == BLACK:
        return a
    return ("csub", a, b)


def _cmul(a, b):
    if _const(a) and _const(b):
        return tuple(x * y for x, y in zip(a, b))
    if a == WHITE:
        return b
    if b == WHITE:
        return a
    return ("cmul", a, b)


def _cmax0(a):
    return tuple(max(v, 0.0) for v in a) if _const(a) else ("cmax0", a)


def _value(sock):
    """A scalar input as a float or ("sock", its source)."""
    src = _source(sock)
    return ("sock", src) if src is not None else float(sock.default_value)


def _colour(sock):
    src = _source(sock)
    return ("csock", src) if src is not None else tuple(float(v) for v in tuple(sock.default_value)[:3])


class _Builder:
    """Makes the nodes of expressions in ``tree`` (named ``AnalyticFog Term N``, laid out on a grid)."""

    def __init__(self, tree, x, y):
        self.tree, self.x, self.y, self.n, self.memo = tree, x, y, 0, {}

    def node(self, bl_idname, **props):
        k = self.n
        self.n += 1
        return _add(self.tree, bl_idname, f"Term {k}", (self.x + 180 * (k % 8), self.y - 180 * (k // 8)), **props)

    def feed(self, sock, v):
        """Link ``v`` (a socket) into ``sock`` or set it as its value."""
        if isinstance(v, bpy.types.NodeSocket):
            self.tree.links.new(v, sock)
        else:
            _set_value(sock, v)

    def _key(self, e):
        if isinstance(e, bpy.types.NodeSocket):
            return ("socket", e.node.name, e.identifier)
        if isinstance(e, tuple) and e and isinstance(e[0], str):
            return (e[0],) + tuple(self._key(a) for a in e[1:])
        return e

    def scalar(self, e):
        """A float or an output socket computing scalar expression ``e``."""
        if isinstance(e, float):
            return e
        if e[0] == "sock":
            return e[1]
        key = self._key(e)
        if key not in self.memo:
            args = [self.scalar(a) for a in e[1:]]
            if e[0] == "clamp":
                n = self.node("ShaderNodeClamp")
                self.feed(n.inputs["Value"], args[0])
            else:
                n = self.node("ShaderNodeMath", operation={"mul": "MULTIPLY", "sub": "SUBTRACT"}[e[0]])
                for i, a in enumerate(args):
                    self.feed(n.inputs[i], a)
            self.memo[key] = n.outputs[0]
        return self.memo[key]

    def colour(self, e):
        """A 3-tuple or an output socket computing colour expression ``e``."""
        if _const(e):
            return e
        if e[0] == "csock":
            return e[1]
        key = self._key(e)
        if key not in self.memo:
            if e[0] == "cscale":
                n = self.node("ShaderNodeVectorMath", operation="SCALE")
                self.feed(n.inputs[0], self.colour(e[1]))
                self.feed(n.inputs["Scale"], self.scalar(e[2]))
            elif e[0] == "cmax0":
                n = self.node("ShaderNodeVectorMath", operation="MAXIMUM")
                self.feed(n.inputs[0], self.colour(e[1]))
                n.inputs[1].default_value = BLACK
            else:
                n = self.node("ShaderNodeVectorMath",
                              operation={"cadd": "ADD", "csub": "SUBTRACT", "cmul": "MULTIPLY"}[e[0]])
                self.feed(n.inputs[0], self.colour(e[1]))
                self.feed(n.inputs[1], self.colour(e[2]))
            self.memo[key] = n.outputs[0]
        return self.memo[key]


# --- what a shader is made of ------------------------------------------------------

class _Kinds:
    """What the shader feeding a Material Output is made of, with each part's weight in the mix.

    ``passes``: (weight, shader socket or None for a white Transparent BSDF, colour) for the
    parts that let light through (Transparent BSDF, Holdout, Principled 1 - Alpha);
    ``emitters``: (weight, colour) for emission (colour times strength, Principled: times Alpha);
    ``reads``: the first Principled / Diffuse BSDF, with the group nodes it sits in;
    ``opaque``: some part does not let light through (every shader but Transparent BSDF and Holdout);
    ``unread``: labels of reflecting shaders the fog does not read; ``hidden``: names of
    node groups with transparency or holdouts inside.
    """

    def __init__(self):
        self.passes, self.emitters, self.unread, self.hidden = [], [], [], []
        self.reads, self.opaque = None, False

    def opacity(self):
        o = WHITE
        for w, _, c in self.passes:
            o = _csub(o, _cscale(c, w))
        return _cmax0(o)

    def pass_through_only(self):
        return not (self.opaque or self.emitters or self.hidden) and self.opacity() == BLACK


def _analyse(sock, weight, ctx, kinds, depth=0):
    """Walk the shader graph from output ``sock``; ``ctx``: the group nodes we are inside."""
    if depth > 64:
        return
    node = sock.node
    kind = node.bl_idname
    top = not ctx
    if kind == "ShaderNodeMixShader":
        f = _clamp(_value(node.inputs[0])) if top else 0.5
        for inp, w in ((node.inputs[1], _mul(weight, _sub(1.0, f))), (node.inputs[2], _mul(weight, f))):
            src = _source(inp)
            if src is not None and w != 0.0:
                _analyse(src, w, ctx, kinds, depth + 1)
    elif kind == "ShaderNodeAddShader":
        for inp in node.inputs[:2]:
            src = _source(inp)
            if src is not None:
                _analyse(src, weight, ctx, kinds, depth + 1)
    elif kind == "ShaderNodeGroup":
        tree = node.node_tree
        out = None if tree is None else next(
            (n for n in tree.nodes if n.bl_idname == "NodeGroupOutput" and n.is_active_output), None)
        inner = None if out is None else next((i for i in out.inputs if i.identifier == sock.identifier), None)
        src = None if inner is None else _source(inner)
        if src is not None:
            _analyse(src, weight, ctx + (node,), kinds, depth + 1)
        else:
            kinds.opaque = True
    elif kind in _PASS_THROUGH:
        if top:
            colour = _colour(node.inputs["Color"]) if "Color" in node.inputs else WHITE
            kinds.passes.append((weight, sock, colour))
        else:
            kinds.hidden.append(ctx[0].node_tree.name)
    elif kind == "ShaderNodeBsdfPrincipled":
        kinds.opaque = True
        if kinds.reads is None:
            kinds.reads = (node, ctx)
        alpha = _clamp(_value(node.inputs["Alpha"]))
        if alpha != 1.0:
            if top:
                kinds.passes.append((_mul(weight, _sub(1.0, alpha)), None, WHITE))
            else:
                kinds.hidden.append(ctx[0].node_tree.name)
        e = _cscale(_colour(node.inputs["Emission Color"]), _value(node.inputs["Emission Strength"]))
        if top and e != BLACK:
            kinds.emitters.append((_mul(weight, alpha), e))
    elif kind in _EMITTERS:
        kinds.opaque = True
        e = _cscale(_colour(node.inputs["Color"]), _value(node.inputs["Strength"]))
        if top and e != BLACK:
            kinds.emitters.append((weight, e))
    else:
        kinds.opaque = True
        if kind == "ShaderNodeBsdfDiffuse":
            if kinds.reads is None:
                kinds.reads = (node, ctx)
        else:
            kinds.unread.append(node.bl_label)


def _mirrored(sock, ctx):
    """(value or source socket for the fog's copy of input ``sock``, True if it could be followed)."""
    src = _source(sock)
    if src is None:
        return tuple(sock.default_value) if hasattr(sock.default_value, "__len__") else sock.default_value, True
    if src.node.bl_idname == "NodeGroupInput" and ctx:
        outer = next((i for i in ctx[-1].inputs if i.identifier == src.identifier), None)
        if outer is not None:
            return _mirrored(outer, ctx[:-1])
    if ctx:   # computed inside a group: not reachable from the material's tree
        return (tuple(sock.default_value) if hasattr(sock.default_value, "__len__") else sock.default_value), False
    return src, True


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
    if isinstance(v, bpy.types.NodeSocket):
        tree.links.new(v, dst)
    else:
        _set_value(dst, v)


def _bsdf_copies(reads):
    """[(fog input name, value or source socket, followed)] copying the BSDF ``reads`` into the fog group."""
    if reads is None:
        return []
    node, ctx = reads
    if node.bl_idname == "ShaderNodeBsdfDiffuse":   # Lambertian: rho_s = 0 at Specular IOR Level 0
        v, ok = _mirrored(node.inputs["Color"], ctx)
        return [("Base Color", v, ok), ("Metallic", 0.0, True), ("Roughness", 1.0, True),
                ("Specular IOR Level", 0.0, True)]
    return [(name, *_mirrored(node.inputs[name], ctx)) for name in _PRINCIPLED_INPUTS if name in node.inputs]


def _user_surface(tree, out, target):
    """The user's shader socket feeding output ``out`` (through the fog where the fog took the output over)."""
    if out is None:
        return None
    link = _link_into(out.inputs["Surface"])
    if link is not None and _ours(link.from_node):
        mix = tree.nodes.get(f"{PREFIX} {target} Attenuate")
        link = _link_into(mix.inputs[1]) if mix is not None and mix.bl_idname == "ShaderNodeMixShader" else None
        if link is None or _ours(link.from_node):
            return None
        return link.from_socket if _source(mix.inputs[1]) is not None else None
    return None if link is None or _source(out.inputs["Surface"]) is None else link.from_socket


def _plan(tree):
    """(effective outputs, their shader sockets, {shader key: _Kinds}) of the user's nodes."""
    outs = {t: effective_output(tree, t, users_only=True) for t in TARGETS}
    srcs = {t: _user_surface(tree, o, t) for t, o in outs.items()}
    kinds = {}
    for src in srcs.values():
        if src is not None and _skey(src) not in kinds:
            kinds[_skey(src)] = _Kinds()
            _analyse(src, 1.0, (), kinds[_skey(src)])
    return outs, srcs, kinds


def _skey(sock):
    return (sock.node.name, sock.identifier)


def _key(e):
    """A comparable, printable form of an expression, value or socket."""
    if isinstance(e, bpy.types.NodeSocket):
        return ("socket",) + _skey(e)
    if isinstance(e, tuple):
        return tuple(_key(a) for a in e)
    if isinstance(e, list):
        return [_key(a) for a in e]
    return e


def _signature(tree, outs, srcs, kinds, copies):
    """Everything of the user's the fog's nodes are built from (what a rebuild would read)."""
    parts = []
    for t in TARGETS:
        o = outs[t]
        if o is None or srcs[t] is None:
            parts.append((t, None))
            continue
        extra = [(sock.identifier, _key(_link_into(sock).from_socket)) for sock in o.inputs
                 if sock.name != "Surface" and _link_into(sock) is not None]
        parts.append((t, o.name, o.target, _key(srcs[t]), extra))
    for k, kd in kinds.items():
        reads = kd.reads and (kd.reads[0].name, [g.name for g in kd.reads[1]])
        parts.append((k, _key(kd.passes), _key(kd.emitters), reads, sorted(kd.hidden), sorted(kd.unread), kd.opaque))
    parts.append(_key(copies))
    parts.append(bpy.data.node_groups.get(groups.SURFACE) is not None)
    return repr(parts)


def _fog_links(tree):
    """The fog's own nodes and every link touching them, as text."""
    names = sorted(n.name for n in tree.nodes if _ours(n))
    links = sorted((l.from_node.name, l.from_socket.identifier, l.to_node.name, l.to_socket.identifier)
                   for l in tree.links if _ours(l.from_node) or _ours(l.to_node))
    return repr((names, links))


SIGNATURE = "analytic_fog_signature"   # on the fog's Surface node: what it was built from


def wrap_material(mat):
    """Add the fog to ``mat`` (rebuilding it if there); returns a reason or note string, else None.

    Adding twice is the same as once; adding after an edit follows the edit.
    """
    why = read_only(mat)
    if why:
        return why
    if getattr(mat, "is_grease_pencil", False):
        return "is a Grease Pencil material: left without fog"
    tree = mat.node_tree
    if tree is None:
        return "has no node tree"
    outs, srcs, kinds = _plan(tree)
    volume = any(o is not None and _source(o.inputs["Volume"]) is not None for o in outs.values())
    if not any(srcs.values()):
        unwrap(mat)
        if volume:
            return ("has only a volume shader: left without fog (the fog does not dim volumes; "
                    "what is seen through it is fogged)")
        return "has no surface shader connected to a Material Output"
    if all(k.pass_through_only() for k in kinds.values()):   # Transparent BSDF, Holdout: nothing to fog
        unwrap(mat)
        if volume:
            return ("its surface only lets light through and its volume shader is left as it is: the fog does "
                    "not dim the volume (what is seen through it is fogged)")
        return None
    first = kinds[next(iter(kinds))]
    copies = _bsdf_copies(first.reads)
    lost = [name for name, _, ok in copies if not ok]
    signature = _signature(tree, outs, srcs, kinds, copies)
    fog = tree.nodes.get(f"{PREFIX} Surface")
    if (fog is not None and fog.bl_idname == "ShaderNodeGroup"
            and fog.node_tree == bpy.data.node_groups.get(groups.SURFACE)
            and fog.get(SIGNATURE) == signature + _fog_links(tree)):
        return _notes(mat, kinds, lost) or None   # fogged, and nothing it reads has changed
    # rebuild from the user's current nodes (the sockets found above are all the user's), in the same place
    anchor = tuple(fog.location) if fog is not None else None
    unwrap(mat)
    mine = [n for n in tree.nodes if not _ours(n)]
    x0, y0 = anchor or (max((n.location.x for n in mine), default=0) + 300,
                        min((n.location.y for n in mine), default=0) - 300)
    b = _Builder(tree, x0 - 400, y0 - 900)
    fog = _add(tree, "ShaderNodeGroup", "Surface", (x0, y0))
    fog.node_tree = bpy.data.node_groups[groups.SURFACE]
    for name, v, _ in copies:
        _set_copy(tree, fog.inputs[name], v)
    transmittance = ("sock", fog.outputs["Transmittance"])

    shared = {}   # per shader source: (fog emission node, pass-through shader or None)
    for k, target in enumerate(TARGETS):
        out, src = outs[target], srcs[target]
        if src is None:
            continue
        key = _skey(src)
        kd = kinds[key]
        if key not in shared:
            tag = "" if not shared else f" {len(shared) + 1}"
            emit = _add(tree, "ShaderNodeEmission", f"Emission{tag}", (x0 + 200, y0 - 120 * len(shared)))
            b.feed(emit.inputs["Color"], b.colour(_cmul(("csock", fog.outputs["Emission"]), kd.opacity())))
            passed = None
            for w, shader, _ in kd.passes:
                if shader is None:
                    shader = tree.nodes.get(f"{PREFIX} Transparent")
                    shader = (shader or _add(tree, "ShaderNodeBsdfTransparent", "Transparent",
                                             (x0 - 200, y0 - 700))).outputs[0]
                term = shader
                if w != 1.0:
                    mix = b.node("ShaderNodeMixShader")
                    b.feed(mix.inputs[0], b.scalar(w))
                    tree.links.new(shader, mix.inputs[2])   # input 1 stays empty: w * shader
                    term = mix.outputs[0]
                if passed is None:
                    passed = term
                else:
                    add = b.node("ShaderNodeAddShader")
                    tree.links.new(passed, add.inputs[0])
                    tree.links.new(term, add.inputs[1])
                    passed = add.outputs[0]
            shared[key] = (emit, passed)
        emit, passed = shared[key]
        y = y0 - 250 * (k + 1)
        # 1 - scale of the user's shader: e^{-beta D_vp}, in EEVEE times the Direct Attenuation
        # (EEVEE ignores light node trees: direct light is attenuated here)
        mix_factor = fog.outputs[f"{'EEVEE' if target == 'EEVEE' else 'Cycles'} Mix Factor"]
        mix = _add(tree, "ShaderNodeMixShader", f"{target} Attenuate", (x0 + 500, y))
        tree.links.new(mix_factor, mix.inputs[0])
        tree.links.new(src, mix.inputs[1])
        if passed is not None:   # what lets light through keeps its weight: s P + (1 - s) P
            tree.links.new(passed, mix.inputs[2])
        last = mix.outputs[0]
        if target == "EEVEE" and kd.emitters:   # emission is dimmed by T only: give back (T - s) E
            total = BLACK
            for w, e in kd.emitters:
                total = _cadd(total, _cscale(e, w))
            back = _add(tree, "ShaderNodeEmission", f"{target} Emission Restore", (x0 + 500, y - 120))
            b.feed(back.inputs["Color"], b.colour(_cscale(total, _sub(transmittance, _sub(1.0, ("sock", mix_factor))))))
            add_back = _add(tree, "ShaderNodeAddShader", f"{target} Add Restore", (x0 + 575, y - 60))
            tree.links.new(last, add_back.inputs[0])
            tree.links.new(back.outputs[0], add_back.inputs[1])
            last = add_back.outputs[0]
        add = _add(tree, "ShaderNodeAddShader", f"{target} Add", (x0 + 650, y))
        tree.links.new(last, add.inputs[0])
        tree.links.new(emit.outputs[0], add.inputs[1])
        if out.target == target:   # the user's own output for this engine: route it through the fog
            tree.links.new(add.outputs[0], out.inputs["Surface"])
            continue
        new_out = _add(tree, "ShaderNodeOutputMaterial", f"{target} Output", (x0 + 800, y), target=target)
        tree.links.new(add.outputs[0], new_out.inputs["Surface"])
        for sock in out.inputs:
            link = _link_into(sock)
            if sock.name != "Surface" and link is not None and sock.name in new_out.inputs:
                tree.links.new(link.from_socket, new_out.inputs[sock.name])
    fog[SIGNATURE] = signature + _fog_links(tree)
    if not any(k.emitters for k in kinds.values()):
        # the fog's emission is for camera rays only: as a light it would only steal light samples
        # from the lamps (Cycles' light tree counts every emissive mesh; 16 % noise at 1 spp)
        _override(mat, "cycles.emission_sampling", "NONE")
    return _notes(mat, kinds, lost) or None


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
    outs = [effective_output(mat.node_tree, t, users_only=True) for t in TARGETS]
    vol = any(o is not None and _source(o.inputs["Volume"]) is not None for o in outs)
    if vol and any(k.passes for k in kinds.values()):
        notes.append("its volume, seen through its transparent surface, is not dimmed by the fog")
    return "; ".join(notes)


_WAS = "analytic_fog_was"   # on a material or world: {"cycles.<setting>": the user's value} the fog changed


def _override(idblock, path, value):
    """Set ``idblock``'s setting ``path`` (e.g. "cycles.sampling_method") for the fog, keeping the user's value."""
    owner, attr = path.rsplit(".", 1)
    owner = idblock.path_resolve(owner)
    was = idblock.get(_WAS, {})
    if path not in was:
        was[path] = getattr(owner, attr)
        idblock[_WAS] = was
    setattr(owner, attr, value)


def _restore_overrides(idblock):
    for path, value in dict(idblock.get(_WAS, {})).items():
        owner, attr = path.rsplit(".", 1)
        setattr(idblock.path_resolve(owner), attr, value)
    idblock.pop(_WAS, None)


def _constant_shader(sock):
    """True if nothing or an unlinked Background / Emission feeds ``sock``: a world of one colour."""
    src = _source(sock)
    return src is None or (src.node.bl_idname in _EMITTERS and not any(i.is_linked for i in src.node.inputs))


def wrap_world(world):
    """Add the fog's airlight and background extinction to ``world``.  Idempotent."""
    why = read_only(world)
    if why:
        return why
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
        # Camera rays (mix factor 1) see only the airlight, other rays only the user's world: a factor
        # of exactly 0 or 1 lets Cycles skip the other branch, so its world importance map (evaluated
        # without the camera flag) does not run the fog's nodes (~50 s per render otherwise).
        mix = _add(tree, "ShaderNodeMixShader", f"{target} Mix", (x0 + 350, y))
        tree.links.new(inv.outputs[0], mix.inputs[0])
        if out is not None and out.inputs["Surface"].is_linked:
            tree.links.new(out.inputs["Surface"].links[0].from_socket, mix.inputs[1])
        tree.links.new(bg.outputs[0], mix.inputs[2])
        new_out = _add(tree, "ShaderNodeOutputWorld", f"{target} Output", (x0 + 650, y), target=target)
        tree.links.new(mix.outputs[0], new_out.inputs["Surface"])
        if out is not None and out.inputs["Volume"].is_linked:
            tree.links.new(out.inputs["Volume"].links[0].from_socket, new_out.inputs["Volume"])
    cycles_out = effective_output(tree, "CYCLES", users_only=True)
    if cycles_out is None or _constant_shader(cycles_out.inputs["Surface"]):
        # a world of one colour needs no importance map; with the fog's nodes in it the map would be
        # baked on every Cycles render (~2.5 s), and BSDF sampling of a constant world loses nothing
        _override(world, "cycles.sampling_method", "NONE")
    return None


def unwrap(idblock):
    """Delete every node the fog added to ``idblock``'s tree; link the user's outputs it took over back."""
    tree = idblock.node_tree
    if tree is None or read_only(idblock):
        return
    _restore_overrides(idblock)
    back = []
    for link in tree.links:
        if _ours(link.from_node) and not _ours(link.to_node):
            target = link.from_node.name[len(PREFIX) + 1:].split(" ")[0]
            mix = tree.nodes.get(f"{PREFIX} {target} Attenuate")
            src = _link_into(mix.inputs[1]) if mix is not None and mix.bl_idname == "ShaderNodeMixShader" else None
            if src is not None and not _ours(src.from_node):
                back.append((src.from_node.name, src.from_socket.identifier, link.to_node.name,
                             link.to_socket.identifier))
    for n in [n for n in tree.nodes if _ours(n)]:
        tree.nodes.remove(n)
    for from_node, from_id, to_node, to_id in back:
        src = next(s for s in tree.nodes[from_node].outputs if s.identifier == from_id)
        dst = next(s for s in tree.nodes[to_node].inputs if s.identifier == to_id)
        tree.links.new(src, dst)


# --- lights: Cycles attenuates direct light in the light's own node tree ----------

_LIGHT_STATE = "analytic_fog_use_nodes"
_ACTIVE_OUTPUT = "analytic_fog_active_output"


def wrap_light(light_data):
    """Multiply the light's emission strength by e^{-beta * Ray Length} (Sun et al. 2005 Eq. 14).

    In a Cycles light shader Ray Length is the distance from the lit point to
    the light.  EEVEE ignores light node trees (see wrap_material).  Returns
    a reason string for a linked or overridden light (left as it is), else None.
    """
    why = read_only(light_data)
    if why:
        return why.replace("left without fog", "its direct light is not dimmed by the fog in Cycles")
    if _LIGHT_STATE in light_data:
        return None
    light_data[_LIGHT_STATE] = bool(light_data.use_nodes)
    light_data.use_nodes = True
    tree = light_data.node_tree
    out = next((n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputLight" and n.is_active_output), None)
    if out is None or not out.inputs["Surface"].is_linked:
        return None
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
    return None


def unwrap_light(light_data):
    if _LIGHT_STATE not in light_data or read_only(light_data):
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
