"""``CompOps``, the ops protocol (``sockets.NodeOps``) building into the compositor's trees, and the image
operations the compositor's groups share: images moved, scaled, cropped to a window and put back in place, sums
kept on their domain, Value and vector nodes driven from the scene, and groups built once for every light."""
from ..precompute.model import footprint
from . import drivers, groups, owned
from .groups import V
from .sockets import KERNEL_GROUP, NodeOps, Val

KERNEL_PREFIX = f"{KERNEL_GROUP} Compositor"   # the kernels' compositor groups (``sockets.NodeOps.group``)
WINDOW = "Fog Window"   # ID properties (u0, u1, v0, v1) of the windows (``footprint.py``): a bundle's "<WINDOW> <k>"
#                         for its k-th light's glow, the fog group's "<WINDOW> Surface" for the fog light on surfaces


class CompOps(NodeOps):
    """NodeOps building into a compositor tree: compositor groups, tables read by Map UV, no EEVEE flags.

    Each node is built once per tree (``NodeOps``): Blender's compositor evaluates every node it is given,
    over every pixel."""

    GROUP_NODE = "CompositorNodeGroup"
    GROUP_TREE = "CompositorNodeTree"
    SEPARATE_COLOR = "CompositorNodeSeparateColor"
    KERNEL_PREFIX = KERNEL_PREFIX
    inline = staticmethod(lambda node: None)

    def select(self, cond, if_true, if_false):
        """One Mix node (Float) for the four Math nodes of ``NodeOps.select``: (1 - cond) if_false + cond if_true,
        exact for cond in {0, 1} as theirs (a Mix node's unused inputs cost EEVEE uniforms, not the compositor)."""
        vals = [self.wrap(v) for v in (cond, if_false, if_true)]
        if any(v.vector for v in vals) or vals[0].const is not None:
            return super().select(cond, if_true, if_false)
        return self._once(("select", self._ids(vals)), lambda: self._new_select(*vals))

    def _new_select(self, cond, if_false, if_true):
        col = 1 + max(v.col for v in (cond, if_false, if_true))
        n = self.node("ShaderNodeMix", col, data_type="FLOAT", clamp_factor=False)
        for name, v in (("Factor_Float", cond), ("A_Float", if_false), ("B_Float", if_true)):
            self.feed(next(s for s in n.inputs if s.identifier == name), v)
        return Val(self, sock=next(s for s in n.outputs if s.identifier == "Result_Float"), col=col)

    def _grid(self, spec, x, y, channel=0):
        """A texel at a grid point: the bilinear Map UV there (``_table``; the compositor has no rounds to keep)."""
        return self._table(spec, x, y, 0, None, channel)

    def _table(self, spec, x, y, row0=0, rows=None, channel=0):
        """``channel`` of one bilinear Map UV (the compositor's interpolation is exact bilinear between texel
        centres; the channels of a texel share it): x, y in [0, 1] span the texel centres of rows row0 ..
        row0 + rows - 1."""
        mu, col = self._once(("map uv", spec.name, row0, rows, self._ids((x, y))),
                             lambda: self._map_uv(spec, x, y, row0, rows))
        return self.texel(spec, mu, col, channel)

    def _map_uv(self, spec, x, y, row0, rows):
        rows = spec.height if rows is None else rows
        u = self.clamp(x) * ((spec.width - 1.0) / spec.width) + 0.5 / spec.width
        v = self.clamp(y) * ((rows - 1.0) / spec.height) + (row0 + 0.5) / spec.height
        uv = self.combine(u, v, 1.0)   # Map UV takes the third component as the UV's alpha: 0 gives black
        mu = self.node("CompositorNodeMapUV", uv.col + 1)
        mu.inputs["Interpolation"].default_value = "Bilinear"
        source = self.images[spec.name]   # an image of the file, or a group's image input (``_socket_images``)
        if isinstance(source, Val):
            self.tree.links.new(source.sock, mu.inputs["Image"])
        else:
            im = self.node("CompositorNodeImage", uv.col + 1)
            im.image = source
            self.tree.links.new(im.outputs["Image"], mu.inputs["Image"])
        self.tree.links.new(uv.sock, mu.inputs["UV"])
        return mu, uv.col + 1


def shared_group(m, name, inputs, output, build):
    """A group node in ``m``'s tree of the compositor group ``name``, built once for every light and bundle (a
    tree's node creation slows as it grows): ``inputs`` its ((name, socket type, value) ...), fed here;
    ``output`` (name, socket type) of its one output, ``build(sub, ins)`` its value from its inputs' Vals by
    name.  Returns the output's Val."""
    if (ng := groups.up_to_date(name)) is None:
        ng, gin, gout = groups.new_group(name, [(n, t) for n, t, _ in inputs], [output],
                                         tree_type="CompositorNodeTree")
        sub = CompOps(ng, {})
        ins = {s.name: sub.wrap(s, vector=s.type in ("VECTOR", "RGBA")) for s in gin.outputs if s.name}
        sub.feed(gout.inputs[output[0]], sub.wrap(build(sub, ins)))
        ng[owned.BUILT] = groups.code_fingerprint()
        sub.place()
        ng = groups.install(ng, name)
    vals = [m.wrap(v) for _, _, v in inputs]
    node = m.node("CompositorNodeGroup", max(v.col for v in vals) + 1)
    node.node_tree = ng
    for (socket, _, _), v in zip(inputs, vals):
        m.feed(node.inputs[socket], v)
    return m.wrap(node.outputs[output[0]], vector=output[1] == V)


def driven_value(m, label, expression, variables):
    """A Value node driven by ``expression`` (``drivers.drive_expression``)."""
    node = m.node("ShaderNodeValue", 0)
    node.label = label
    drivers.drive_expression(node.outputs[0], expression, variables)
    return m.wrap(node.outputs[0])


def driven_vector(m, label, expressions, variables, col=0):
    """A vector whose components are driven by ``expressions`` (one per axis; ``variables`` may be a
    function of the axis)."""
    node = m.node("ShaderNodeCombineXYZ", col)
    node.label = label
    for i, expression in enumerate(expressions):
        drivers.drive_expression(node.inputs[i], expression, variables(i) if callable(variables) else variables)
    return m.wrap(node.outputs[0], vector=True)


def driven_location(m, label, obj, col=0):
    """``obj``'s world location, driven as the shader groups drive theirs (``drivers.drive_location``)."""
    node = m.node("ShaderNodeCombineXYZ", col)
    node.label = label
    drivers.drive_location(node, obj)
    return m.wrap(node.outputs[0], vector=True)


def window_crop(m, scene, label, win):
    """The crop of the window ``win`` (u0, u1, v0, v1: ``footprint.py``) as nodes, ((start, extent, shift) in x,
    the same in y) px: Value nodes driven by ``footprint.START``, ``EXTENT`` and ``SIZE`` of the tree's ID
    property "<WINDOW> <label>" (the window: ``comp_fog.set_windows`` sets it) and of the render's size."""
    key = f"{WINDOW} {label}"
    m.tree[key] = list(win)
    crops = []
    for axis, name in enumerate("xy"):
        variables = [("l", m.tree, f'["{key}"][{2 * axis}]'), ("h", m.tree, f'["{key}"][{2 * axis + 1}]'),
                     ("r", scene, f"render.resolution_{name}"), ("p", scene, "render.resolution_percentage")]
        start, extent, size = (driven_value(m, f"{key} {part} {name}", expression, variables) for part, expression in
                               (("start", footprint.START), ("extent", footprint.EXTENT), ("size", footprint.SIZE)))
        crops.append((start, extent, start + 0.5 * (extent - size)))
    return crops


def crop(m, value, window):
    """``value`` (an image) cropped to ``window`` (``window_crop``'s): the compositor evaluates what reads it over
    those pixels only."""
    node = m.node("CompositorNodeCrop", value.col + 1)
    m.feed(node.inputs["Image"], value)
    (x, w, _), (y, h, _) = window
    for sock, v in (("X", x), ("Width", w), ("Y", y), ("Height", h)):
        m.feed(node.inputs[sock], v)
    return m.wrap(node.outputs[0], vector=True)


def uncrop(m, value, window):
    """An image cropped by ``crop`` moved back to its place in the picture (the compositor centres it)."""
    node = m.node("CompositorNodeTranslate", value.col + 1)
    node.inputs["Interpolation"].default_value = "Nearest"   # whole pixels
    m.feed(node.inputs["Image"], value)
    m.feed(node.inputs["X"], window[0][2])
    m.feed(node.inputs["Y"], window[1][2])
    return m.wrap(node.outputs[0], vector=True)


def translated(m, value, dx, dy):
    """``value`` (an image) moved by (dx, dy) whole pixels, numbers or Vals (Translate, nearest); a scalar comes
    back in every channel of an image."""
    node = m.node("CompositorNodeTranslate", value.col + 1)
    node.inputs["Interpolation"].default_value = "Nearest"
    m.feed(node.inputs["Image"], value if value.vector else m.combine(value, value, value))
    m.feed(node.inputs["X"], m.wrap(dx))
    m.feed(node.inputs["Y"], m.wrap(dy))
    return m.wrap(node.outputs[0], vector=True)


def scaled(m, value, factor):
    """``value`` (an image) at ``factor`` (a number or a Val) times its resolution (Scale, relative, nearest): the
    compositor evaluates what reads it over that many pixels.  A scalar comes back in every channel of an image."""
    node = m.node("CompositorNodeScale", value.col + 1)
    node.inputs["Type"].default_value = "Relative"
    node.inputs["Interpolation"].default_value = "Nearest"
    for axis in ("X", "Y"):   # a size not a multiple of the factor: the edge pixels take the nearest, not zero
        node.inputs[f"Extension {axis}"].default_value = "Extend"
    m.feed(node.inputs["Image"], value if value.vector else m.combine(value, value, value))
    for axis in ("X", "Y"):
        m.feed(node.inputs[axis], m.wrap(factor))
    return m.wrap(node.outputs[0], vector=True)


def first(m, value):
    """A scalar image: ``value`` itself, or an image's first channel (a cropped or scaled scalar comes back an
    image)."""
    return m.dot(value, (1.0, 0.0, 0.0)) if value.vector else value


def accumulate(m, total, term):
    """total + term, the result on ``total``'s domain (the compositor takes a node's domain from its first
    image input and places the others on it; the hash-consing's sorted operands could swap them)."""
    return m.vmath_in_order("ADD", total, term)


def in_step(m, sums, terms):
    """``sums`` (key -> image) with ``terms`` (key -> image) added, each new sum tied to another sum of the step
    before (a ring over the keys) by adding 0 times that sum (0: the sums are finite; two nodes, Blender's node
    editing slows as a tree grows, ``comp_bundles.BUNDLE_SIZE``): every sum of a step then depends on all
    the sums two steps back, and a step's terms are computed within two steps of each other.  The compositor
    schedules each output's inputs depth first, one output after another (Blender's
    ``compositor/intern/scheduler.cc``), so untied sums over N lights (the glows' Airlight and Background, the
    surfaces' Scattered) keep every buffer of each light that two sums share (its shafts' shares, its glow's lookups)
    from the first sum's pass to the last: memory that grows with lights x pixels."""
    keys = [k for k in terms if sums.get(k) is not None]
    out = dict(sums)
    for key, term in terms.items():
        total = sums.get(key)
        out[key] = term if total is None else accumulate(m, total, term)
    if len(keys) > 1:
        for key, other in zip(keys, keys[1:] + keys[:1]):
            out[key] = accumulate(m, out[key], zero(m, sums[other]))
    return out


def zero(m, image):
    """Black on ``image``'s domain (a sum's first operand: ``accumulate``)."""
    return m.vmath_in_order("MULTIPLY", image, (0.0, 0.0, 0.0))
