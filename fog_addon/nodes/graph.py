"""Reading the user's shader graph: which output renders, what its shader is made of, what the fog copies.

Nothing here changes a node tree.  The analysis is plain data (sockets,
floats and tuples); ``material.py`` builds the fog's nodes from it.

* Several Material Outputs (ALL plus CYCLES or EEVEE): each engine renders
  its effective output (exact target over ALL, then the active one).
* The weight of each part of a shader is read through Mix Shader factors
  (values or links), Add Shader, reroutes and muted nodes.  A weight is a
  tuple of factors, each a float or ``(socket, inverted)``: the socket's
  value clamped to [0, 1] (or 1 minus that), so constant parts fold here
  and need no nodes.  Transparency inside a user's node group cannot be
  weighted from outside it and is reported (``hidden``).
* Node-group shaders: a Principled (or Diffuse) BSDF inside a group is read
  through the group's inputs.
* Only Principled and Diffuse BSDFs are read for the fog light the surface
  reflects (Sun Eq. 17-18); other reflecting shaders are listed (``unread``).

``built_from`` lists everything of the user's the fog's nodes are built from;
``stamp`` hashes it with the fog's own nodes and links (SHA-256 of canonical
JSON), so the fog can tell whether a material changed since it was fogged.
"""
import hashlib
import json
import math

import bpy

from .. import caveats
from . import groups, owned

TARGETS = ("CYCLES", "EEVEE")
WHITE = (1.0, 1.0, 1.0)
BLACK = (0.0, 0.0, 0.0)
_PRINCIPLED_INPUTS = ("Base Color", "Metallic", "Roughness", "Specular IOR Level", "Transmission Weight")
EMITTERS = ("ShaderNodeEmission", "ShaderNodeBackground")
_PASS_THROUGH = ("ShaderNodeBsdfTransparent", "ShaderNodeHoldout")


def effective_output(tree, target, users_only=False):
    """The output node ``target``'s engine renders (``caveats.effective_output``); ``users_only``: among the
    user's outputs (the fog's own ignored)."""
    return caveats.effective_output(tree, target, skip=owned.is_ours if users_only else None)


def link_into(sock):
    """The first enabled link into input ``sock``, or None."""
    if not sock.is_linked:
        return None
    return next((link for link in sock.links if link.is_valid and not link.is_muted), None)


def source(sock):
    """The output socket that really feeds input ``sock`` (through reroutes and muted nodes), or None."""
    for _ in range(256):
        link = link_into(sock)
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


def _value(sock):
    """A scalar input: its source socket, or its value as a float."""
    src = source(sock)
    return src if src is not None else float(sock.default_value)


def _colour(sock):
    """A colour input: its source socket, or its value as an RGB 3-tuple."""
    src = source(sock)
    return src if src is not None else tuple(float(v) for v in tuple(sock.default_value)[:3])


def _fraction(sock):
    """Input ``sock`` clamped to [0, 1] as a weight factor: a float, or (its source socket, False)."""
    v = _value(sock)
    return min(max(v, 0.0), 1.0) if isinstance(v, float) else (v, False)


def _complement(f):
    """The factor 1 - ``f``."""
    return 1.0 - f if isinstance(f, float) else (f[0], not f[1])


def is_zero(weight):
    """True if the weight (a tuple of factors) is 0 for sure."""
    return any(f == 0.0 for f in weight if isinstance(f, float))


def _is_black(c, strength):
    """True if emission colour ``c`` times ``strength`` is black for sure."""
    return strength == 0.0 or c == BLACK


# --- what a shader is made of ------------------------------------------------------

class Kinds:
    """What the shader feeding a Material Output is made of, with each part's weight in the mix.

    ``passes``: (weight, shader socket or None for a white Transparent BSDF, colour) for the
    parts that let light through (Transparent BSDF, Holdout, Principled 1 - Alpha);
    ``emitters``: (weight, colour, strength) for emission (Principled: weighted by Alpha);
    ``reads``: the first Principled / Diffuse BSDF, with the group nodes it sits in;
    ``opaque``: some part does not let light through (every shader but Transparent BSDF and Holdout);
    ``unread``: labels of reflecting shaders the fog does not read; ``hidden``: names of
    node groups with transparency or holdouts inside; ``glass``: (weight, node) of the first glass in the mix, not
    inside a group (``caveats.is_glass``), or None.
    Colours are sockets or 3-tuples, strengths sockets or floats, weights tuples of factors.
    """

    def __init__(self):
        self.passes, self.emitters, self.unread, self.hidden = [], [], [], []
        self.reads, self.opaque, self.glass = None, False, None

    def constant_passes(self):
        """True if every pass-through weight and colour is a constant."""
        return all(isinstance(f, float) for w, _, _ in self.passes for f in w) and not any(
            isinstance(c, bpy.types.NodeSocket) for _, _, c in self.passes)


def _analyse(sock, weight, ctx, kinds, depth=0):
    """Walk the shader graph from output ``sock`` with ``weight``; ``ctx``: the group nodes we are inside."""
    if depth > 64:
        return
    node = sock.node
    kind = node.bl_idname
    top = not ctx
    if kind == "ShaderNodeMixShader":
        f = _fraction(node.inputs[0]) if top else 0.5
        for inp, w in ((node.inputs[1], weight + (_complement(f),)), (node.inputs[2], weight + (f,))):
            src = source(inp)
            if src is not None and not is_zero(w):
                _analyse(src, w, ctx, kinds, depth + 1)
    elif kind == "ShaderNodeAddShader":
        for inp in node.inputs[:2]:
            src = source(inp)
            if src is not None:
                _analyse(src, weight, ctx, kinds, depth + 1)
    elif kind == "ShaderNodeGroup":
        tree = node.node_tree
        out = None if tree is None else next(
            (n for n in tree.nodes if n.bl_idname == "NodeGroupOutput" and n.is_active_output), None)
        inner = None if out is None else next((i for i in out.inputs if i.identifier == sock.identifier), None)
        src = None if inner is None else source(inner)
        if src is not None:
            _analyse(src, weight, ctx + (node,), kinds, depth + 1)
        else:
            kinds.opaque = True
    elif kind in _PASS_THROUGH:
        if top:
            kinds.passes.append((weight, sock, _colour(node.inputs["Color"]) if "Color" in node.inputs else WHITE))
        else:
            kinds.hidden.append(ctx[0].node_tree.name)
    elif kind == "ShaderNodeBsdfPrincipled":
        kinds.opaque = True
        if kinds.reads is None:
            kinds.reads = (node, ctx)
        if top and kinds.glass is None and caveats.is_glass(node):
            kinds.glass = (weight, node)
        alpha = _fraction(node.inputs["Alpha"])
        if alpha != 1.0:
            if top:
                kinds.passes.append((weight + (_complement(alpha),), None, WHITE))
            else:
                kinds.hidden.append(ctx[0].node_tree.name)
        c, s = _colour(node.inputs["Emission Color"]), _value(node.inputs["Emission Strength"])
        if top and not _is_black(c, s):
            kinds.emitters.append((weight + (alpha,), c, s))
    elif kind in EMITTERS:
        kinds.opaque = True
        c, s = _colour(node.inputs["Color"]), _value(node.inputs["Strength"])
        if top and not _is_black(c, s):
            kinds.emitters.append((weight, c, s))
    else:
        kinds.opaque = True
        if top and kinds.glass is None and caveats.is_glass(node):
            kinds.glass = (weight, node)
        if kind == "ShaderNodeBsdfDiffuse":
            if kinds.reads is None:
                kinds.reads = (node, ctx)
        else:
            kinds.unread.append(node.bl_label)


def weight_key(weight):
    """A weight (a tuple of factors) as plain data: a stamp's (``stamp``) and a memo's key."""
    return tuple(f if isinstance(f, float) else (skey(f[0]), f[1]) for f in weight)


def skey(sock):
    """A socket's key: (node name, socket identifier)."""
    return (sock.node.name, sock.identifier)


def user_surface(tree, out, target):
    """The user's shader socket feeding output ``out`` (through the fog where the fog took the output over)."""
    if out is None:
        return None
    link = link_into(out.inputs["Surface"])
    if link is not None and owned.is_ours(link.from_node):
        mix = owned.find(tree, f"{target} Attenuate")
        link = link_into(mix.inputs[1]) if mix is not None and mix.bl_idname == "ShaderNodeMixShader" else None
        if link is None or owned.is_ours(link.from_node):
            return None
        return link.from_socket if source(mix.inputs[1]) is not None else None
    return None if link is None or source(out.inputs["Surface"]) is None else link.from_socket


def plan(tree):
    """(effective outputs, their shader sockets, {shader key: Kinds}) of the user's nodes."""
    outs = {t: effective_output(tree, t, users_only=True) for t in TARGETS}
    srcs = {t: user_surface(tree, o, t) for t, o in outs.items()}
    kinds = {}
    for src in srcs.values():
        if src is not None and skey(src) not in kinds:
            kinds[skey(src)] = Kinds()
            _analyse(src, (), (), kinds[skey(src)])
    return outs, srcs, kinds


def emits(material):
    """True if ``material``'s effective shader holds emission that is not black for sure (an Emission shader,
    a Principled BSDF's emission): a glowing object (``comp_fog``'s emitters' glow)."""
    if material is None or material.node_tree is None:
        return False
    return any(not is_zero(e[0]) for k in plan(material.node_tree)[2].values() for e in k.emitters)


def emitted_radiance(material):
    """RGB W/(m^2 sr): the radiance ``material``'s emission adds (each emitter's colour x strength x its weight in
    the mix, summed), or None where a part of it is not a plain value (a procedural texture, a driven strength):
    what the predictor takes a glowing object to shine with (``ops/left_out.emitters_fog``).  A colour read from
    an Image Texture counts as the image's mean (``image_mean``: the surface's mean where its UVs cover the image
    once)."""
    if material is None or material.node_tree is None:
        return None
    total = [0.0, 0.0, 0.0]
    for kinds in plan(material.node_tree)[2].values():
        for weight, colour, strength in kinds.emitters:
            if not isinstance(colour, tuple):
                colour = image_mean(colour)
            if not all(isinstance(f, float) for f in weight) or not isinstance(strength, float) or colour is None:
                return None
            w = strength * math.prod(weight)
            total = [t + w * c for t, c in zip(total, colour)]
    return tuple(total)


MEAN_PIXELS = 1024 * 1024   # pixels an image's mean reads at most (``image_mean``: 16 MiB); a larger one is scaled
MEAN_SIZE = 1024              # to this many pixels a side, in a copy
_means = {}                   # (image name, size, file, generated colour, dirty) -> its mean, per session


def image_mean(sock):
    """The linear RGB mean of the image an Image Texture node's Color output ``sock`` reads, or None for any other
    source (or no pixels).  8-bit sRGB pixels are made linear.  An image of more than MEAN_PIXELS is scaled in a
    copy of its file first (Blender's box filter: a float image's mean kept; an 8-bit one's stored values averaged
    before they are made linear, which darkens detail finer than a box a little; edits not saved are not seen).
    Kept per image while its name, size, file, generated colour and unsaved state stay."""
    node = getattr(sock, "node", None)
    img = getattr(node, "image", None) if getattr(node, "bl_idname", "") == "ShaderNodeTexImage" else None
    if img is None or sock.name != "Color":
        return None
    key = (img.name_full, tuple(img.size), img.filepath_raw, tuple(img.generated_color), img.is_dirty)
    if key not in _means:
        if len(_means) > 64:
            _means.clear()
        _means[key] = _pixels_mean(img)
    return _means[key]


def _pixels_mean(img):
    import numpy as np   # (numpy: only when an image is read)
    w, h = img.size[:]
    if w * h == 0:
        return None
    source = img if w * h <= MEAN_PIXELS else img.copy()
    try:
        if source is not img:
            source.scale(min(w, MEAN_SIZE), min(h, MEAN_SIZE))
        px = np.empty(len(source.pixels), np.float32)
        source.pixels.foreach_get(px)
        rgb = px.reshape(-1, source.channels)[:, :3].astype(np.float64)
    finally:
        if source is not img:
            bpy.data.images.remove(source)
    if not img.is_float and img.colorspace_settings.name == "sRGB":
        rgb = np.where(rgb <= 0.04045, rgb / 12.92, ((rgb + 0.055) / 1.055) ** 2.4)
    return tuple(float(c) for c in rgb.mean(axis=0)) if len(rgb) else None


# --- the BSDF values the fog copies ------------------------------------------------

def _mirrored(sock, ctx):
    """(value or source socket for the fog's copy of input ``sock``, True if it could be followed)."""
    src = source(sock)
    if src is None:
        return own_value(sock), True
    if src.node.bl_idname == "NodeGroupInput" and ctx:
        outer = next((i for i in ctx[-1].inputs if i.identifier == src.identifier), None)
        if outer is not None:
            return _mirrored(outer, ctx[:-1])
    if ctx:   # computed inside a group: not reachable from the material's tree
        return own_value(sock), False
    return src, True


def own_value(sock):
    """Input ``sock``'s own value: a float or a tuple."""
    return tuple(sock.default_value) if hasattr(sock.default_value, "__len__") else sock.default_value


def bsdf_copies(reads):
    """[(fog input name, value or source socket, followed)] copying the BSDF ``reads`` into the fog group."""
    if reads is None:
        return []
    node, ctx = reads
    if node.bl_idname == "ShaderNodeBsdfDiffuse":   # Lambertian: rho_s = 0 at Specular IOR Level 0
        v, ok = _mirrored(node.inputs["Color"], ctx)
        return [("Base Color", v, ok), ("Metallic", 0.0, True), ("Roughness", 1.0, True),
                ("Specular IOR Level", 0.0, True)]
    return [(name, *_mirrored(node.inputs[name], ctx)) for name in _PRINCIPLED_INPUTS if name in node.inputs]


# --- what the fog was built from -------------------------------------------------

def _plain(x):
    """``x`` (sockets, tuples, lists, numbers, strings) as JSON-ready data."""
    if isinstance(x, bpy.types.NodeSocket):
        return ["socket", *skey(x)]
    if isinstance(x, (tuple, list)):
        return [_plain(a) for a in x]
    return x


def built_from(outs, srcs, kinds, copies):
    """Everything of the user's the fog's nodes are built from (what a rebuild would read), as plain data."""
    targets = {}
    for t in TARGETS:
        o = outs[t]
        if o is None or srcs[t] is None:
            targets[t] = None
            continue
        extra = [(sock.identifier, link_into(sock).from_socket) for sock in o.inputs
                 if sock.name != "Surface" and link_into(sock) is not None]
        targets[t] = _plain((o.name, o.target, srcs[t], extra))
    shaders = [_plain((key, kd.passes, kd.emitters,
                       kd.reads and (kd.reads[0].name, [g.name for g in kd.reads[1]]),
                       sorted(kd.hidden), sorted(kd.unread), kd.opaque)) for key, kd in kinds.items()]
    return {"targets": targets, "shaders": shaders, "copies": _plain(copies),
            "surface_group": bpy.data.node_groups.get(groups.SURFACE) is not None}


def _fog_links(tree):
    """The fog's own nodes and every link touching them."""
    names = sorted(n.name for n in tree.nodes if owned.is_ours(n))
    links = sorted((l.from_node.name, l.from_socket.identifier, l.to_node.name, l.to_socket.identifier)
                   for l in tree.links if owned.is_ours(l.from_node) or owned.is_ours(l.to_node))
    return {"nodes": names, "links": links}


def stamp(built, tree):
    """SHA-256 (hex) of the canonical JSON of ``built`` (see ``built_from``) and the fog's nodes in ``tree``."""
    text = json.dumps({"built_from": built, "fog": _fog_links(tree)}, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()
