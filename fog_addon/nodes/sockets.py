"""The node backend of the shader ops: ``model.py`` formulas built as shader nodes.

``NodeOps`` mirrors ``fog_addon.precompute.core.ops.NumpyOps`` function by function;
a ``Val`` wraps an output socket (or a Python constant, folded at build time)
and overloads arithmetic so the formulas read the same in both.
"""
import math

import bpy

from ..precompute.core import fingerprint
from . import owned

COLUMN = 170.0
KERNEL_GROUP = f"{owned.PREFIX} Kernel"   # name prefix of the shared sub-program groups (``NodeOps.group``)
ROW = 140.0


class Val:
    __slots__ = ("ops", "sock", "const", "vector", "col")

    def __init__(self, ops, sock=None, const=None, vector=False, col=0):
        self.ops, self.sock, self.const, self.vector, self.col = ops, sock, const, vector, col

    def _bin(self, other, op, swap=False):
        a, b = (other, self) if swap else (self, other)
        return self.ops.binary(op, a, b)

    __add__ = lambda s, o: s._bin(o, "ADD")
    __radd__ = lambda s, o: s._bin(o, "ADD", True)
    __sub__ = lambda s, o: s._bin(o, "SUBTRACT")
    __rsub__ = lambda s, o: s._bin(o, "SUBTRACT", True)
    __mul__ = lambda s, o: s._bin(o, "MULTIPLY")
    __rmul__ = lambda s, o: s._bin(o, "MULTIPLY", True)
    __truediv__ = lambda s, o: s._bin(o, "DIVIDE")
    __rtruediv__ = lambda s, o: s._bin(o, "DIVIDE", True)

    def __neg__(self):
        return self.ops.binary("MULTIPLY", self, -1.0)


_FOLD = {
    "ADD": lambda a, b: a + b, "SUBTRACT": lambda a, b: a - b, "MULTIPLY": lambda a, b: a * b,
    "DIVIDE": lambda a, b: a / b if b != 0 else 0.0,
    "MINIMUM": min, "MAXIMUM": max, "POWER": lambda a, b: a ** b if a > 0 else 0.0,
    "ARCTAN2": math.atan2, "LESS_THAN": lambda a, b: float(a < b),
    "LOGARITHM": lambda a, b: math.log(a) / math.log(b) if a > 0 and b > 0 and b != 1 else 0.0,
}
_FOLD3 = {"MULTIPLY_ADD": lambda a, b, c: a * b + c}
_FOLD1 = {
    "EXPONENT": math.exp, "SQRT": lambda a: math.sqrt(a) if a > 0 else 0.0, "SINE": math.sin,
    "COSINE": math.cos, "FLOOR": math.floor, "ABSOLUTE": abs, "TANGENT": math.tan,
}


def quiet_default(sock, value):
    """Set input ``sock``'s default value (a number, or a sequence for a vector or colour socket) without the tree
    update a property set through RNA makes: ``foreach_set`` writes the value and tags nothing (an array value by
    its own ``foreach_set``; a number through its node's inputs when they all hold one number, else by RNA).  For
    the nodes of a tree being built, whose links update the tree afterwards."""
    current = sock.default_value
    if hasattr(current, "foreach_set"):
        current.foreach_set(tuple(float(c) for c in value))
        return
    inputs = sock.node.inputs
    if all(s.type == "VALUE" and hasattr(s, "default_value") for s in inputs):
        values = [0.0] * len(inputs)
        inputs.foreach_get("default_value", values)
        values[list(inputs).index(sock)] = float(value)
        inputs.foreach_set("default_value", values)
        return
    sock.default_value = value


class NodeOps:
    """Builds ``model.py`` formulas into ``tree``; ``images`` maps TableSpec.name -> bpy image.

    The node types of a group and its tree are class attributes, so a subclass can build the same
    formulas into another kind of node tree (the compositor's: ``comp_ops.CompOps``)."""

    GROUP_NODE = "ShaderNodeGroup"
    GROUP_TREE = "ShaderNodeTree"
    SEPARATE_COLOR = "ShaderNodeSeparateColor"
    KERNEL_PREFIX = KERNEL_GROUP

    def __init__(self, tree, images=None, x0=0.0, y0=0.0, cycles=False):
        self.tree = tree
        self.cycles = cycles   # the tree runs in Cycles alone: a table is one Linear tap (``_table``)
        self.images = images or {}
        self.x0, self.y0 = x0, y0
        self._rows = {}
        self._built = {}
        self._places = []   # (node name, x, y) of the nodes built, until ``place`` moves them there

    def place(self):
        """Move the nodes built since the last call to their columns and rows, all in one ``foreach_set``: a
        location set node by node is a tree update each (``feed``).  The builders call it once a tree is built;
        a node not yet placed only sits at the origin of the node editor."""
        if not self._places or self.tree is None:
            return
        nodes = self.tree.nodes
        index = {name: i for i, name in enumerate(nodes.keys())}
        flat = [0.0] * (2 * len(nodes))
        nodes.foreach_get("location", flat)
        for name, x, y in self._places:
            i = index.get(name)
            if i is not None:
                flat[2 * i], flat[2 * i + 1] = x, y
        nodes.foreach_set("location", flat)
        self._places.clear()

    # -- each node once ----------------------------------------------------------
    # An operation on the same inputs returns the node already built (hash-consing): the formulas repeat
    # work across terms (a light's two scatter lobes at one distance, a spot's four, a pixel's two glows).
    # Cycles merges such duplicates itself, by comparing every node of a material with every earlier one of
    # its type (quadratic: README, Many lights); Blender's compositor evaluates every node over every pixel.
    COMMUTATIVE = {"ADD", "MULTIPLY", "MINIMUM", "MAXIMUM", "DOT_PRODUCT"}

    def _once(self, key, build):
        """The value built for ``key`` (an operation and its inputs' identities), building it the first time."""
        if key not in self._built:
            self._built[key] = build()
        return self._built[key]

    def _ids(self, args, op=None):
        ids = tuple(("s", v.sock.as_pointer()) if v.sock is not None else ("c", v.const)
                    for v in (self.wrap(a) for a in args))
        return tuple(sorted(ids, key=repr)) if op in self.COMMUTATIVE else ids

    def math(self, op, *args):
        vals = [self.wrap(a) for a in args]
        if all(v.const is not None for v in vals):
            return self._new_math(op, *vals)
        return self._once(("math", op, self._ids(vals, op)), lambda: self._new_math(op, *vals))

    def vmath(self, op, *args, out=0):
        return self._once(("vmath", op, out, self._ids(args, op)), lambda: self._new_vmath(op, *args, out=out))

    def vmath_in_order(self, op, *args, out=0):
        """A Vector Math node of its own with the operands in the order given (``vmath`` shares one node among
        equal calls and sorts a commutative operation's operands)."""
        return self._new_vmath(op, *args, out=out)

    def combine(self, x, y, z):
        return self._once(("combine", self._ids((x, y, z))), lambda: self._new_combine(x, y, z))

    def clamp(self, x, lo=0.0, hi=1.0):
        if self.wrap(x).const is not None:
            return self._new_clamp(x, lo, hi)
        return self._once(("clamp", lo, hi, self._ids((x,))), lambda: self._new_clamp(x, lo, hi))

    def smoothstep(self, edge0, edge1, x):
        return self._once(("smoothstep", self._ids((edge0, edge1, x))), lambda: self._new_smoothstep(edge0, edge1, x))

    def group(self, name, fn, *args):
        return self._once(("group", name, self._ids(args)), lambda: self._new_group(name, fn, *args))

    def table(self, spec, x, y, row0=0, rows=None, channel=0, nearest=False):
        if nearest:
            return self._once(("grid", spec.name, channel, self._ids((x, y))), lambda: self._grid(spec, x, y, channel))
        return self._once(("table", spec.name, row0, rows, channel, self._ids((x, y))),
                          lambda: self._table(spec, x, y, row0, rows, channel))

    def _grid(self, spec, x, y, channel=0):
        """The texel of ``spec`` at the grid point (x, y) (each i / (n - 1), ``shaft_maps.nearest``): one Closest
        tap at its centre.  Four taps, as ``_table`` reads, keep Cycles' SVM from compiling a quadrature node by
        node: its image nodes are compiled in a later round (``closures.closure_sum`` on the rounds), so every
        node's coordinates waited on the stack together, about 16 floats a node (a shadow map's 8 nodes: 130 of
        SVM's 255); with one tap, about 5."""
        u = self.math("MULTIPLY_ADD", x, (spec.width - 1.0) / spec.width, 0.5 / spec.width)
        v = self.math("MULTIPLY_ADD", y, (spec.height - 1.0) / spec.height, 0.5 / spec.height)
        return self.tap(spec, u, v, channel)

    def texel(self, spec, node, col, channel):
        """``spec``'s ``channel`` as read by ``node`` (an image-reading node in column ``col``): its Alpha output
        (an exact float output) for A and for a one-channel table's value, else by one Separate Color node."""
        channel = 3 if spec.channels == 1 else channel
        if channel == 3 and "Alpha" in node.outputs:
            return Val(self, sock=node.outputs["Alpha"], col=col)

        def separate():
            sep = self.node(self.SEPARATE_COLOR, col + 1)
            self.tree.links.new(node.outputs[0], sep.inputs[0])
            self.inline(sep)
            return sep
        return Val(self, sock=self._once(("separate", node.as_pointer()), separate).outputs[channel], col=col + 1)

    # -- plumbing -----------------------------------------------------------
    def wrap(self, x, vector=False):
        if isinstance(x, Val):
            return x
        if isinstance(x, bpy.types.NodeSocket):
            return Val(self, sock=x, vector=vector or x.type == "VECTOR", col=0)
        if isinstance(x, tuple):   # a constant colour / vector (RGB)
            return Val(self, const=tuple(float(c) for c in x[:3]), vector=True)
        return Val(self, const=float(x))

    def node(self, bl_idname, col, **props):
        """A new node in column ``col`` (the next row down, moved there by ``place``), hidden, with ``props``
        (those that differ from the new node's: each property set is a tree update, see ``feed``)."""
        n = self.tree.nodes.new(bl_idname)
        row = self._rows.get(col, 0)
        self._rows[col] = row + 1
        self._places.append((n.name, self.x0 + col * COLUMN, self.y0 - row * ROW))
        n.hide = True
        for k, v in props.items():
            if getattr(n, k) != v:
                setattr(n, k, v)
        return n

    def feed(self, sock, v):
        """Connect Val ``v`` to input ``sock`` (or set its default value to the constant).

        A constant is written without a tree update (``quiet_default``): setting a property through RNA
        updates the whole tree (a fraction of a millisecond in a new tree, growing with its nodes, and as much
        again on Blender's other threads), and a tree being built needs none until its links are made."""
        if v.sock is not None:
            self.tree.links.new(v.sock, sock)
            return
        if isinstance(v.const, tuple):   # a constant colour / vector (a colour socket gets alpha 1)
            quiet_default(sock, (v.const + (1.0,))[:len(sock.default_value)])
        elif sock.type == "VECTOR":
            quiet_default(sock, (v.const, v.const, v.const))
        else:
            quiet_default(sock, v.const)

    @staticmethod
    def inline(node):
        """Mark the unlinked inputs of ``node`` (one of the fog's own math nodes, fed) as constants for EEVEE.

        EEVEE makes every unlinked float, vector or colour input of a material's nodes, inlined groups
        included, a uniform of the material's 64 KiB block, the inputs its operation leaves unused too
        (a link into those is invalid and ignored); with ``hide_value`` set it compiles the value into
        the shader instead.  Measured on the many-lights scene (36 to 81 lights): 4 608 bytes a light,
        under 805 with this and the tables' identity mapping (``tap``), the same pixels, and EEVEE's
        first render 2.8x faster.  Blender does not save ``hide_value``: a reopened file is back to the
        uniforms (``budgets.EEVEE_MATERIAL_BYTES`` counts them).
        """
        for sock in node.inputs:
            if not sock.is_linked and sock.type in ("VALUE", "VECTOR", "RGBA"):
                sock.hide_value = True

    def _new_math(self, op, *args):
        vals = [self.wrap(a) for a in args]
        if all(v.const is not None for v in vals):
            f = {1: _FOLD1, 2: _FOLD, 3: _FOLD3}[len(vals)].get(op)
            return Val(self, const=float(f(*(v.const for v in vals))))
        col = 1 + max(v.col for v in vals)
        n = self.node("ShaderNodeMath", col, operation=op, use_clamp=False)
        for s, v in zip(n.inputs, vals):
            self.feed(s, v)
        self.inline(n)
        return Val(self, sock=n.outputs[0], col=col)

    def _new_smoothstep(self, edge0, edge1, x):
        """One Map Range node (Float, Smooth Step) from [edge0, edge1] to [0, 1] (folded for constants)."""
        vals = [self.wrap(v) for v in (x, edge0, edge1)]
        if all(v.const is not None for v in vals):
            t = min(max((vals[0].const - vals[1].const) / (vals[2].const - vals[1].const), 0.0), 1.0)
            return Val(self, const=t * t * (3.0 - 2.0 * t))
        col = 1 + max(v.col for v in vals)
        n = self.node("ShaderNodeMapRange", col, data_type="FLOAT", interpolation_type="SMOOTHSTEP")
        for s, v in zip(n.inputs, vals):   # Value, From Min, From Max (To Min 0, To Max 1)
            self.feed(s, v)
        self.inline(n)
        return Val(self, sock=n.outputs["Result"], col=col)

    def _new_vmath(self, op, *args, out=0):
        vals = [self.wrap(a) for a in args]
        col = 1 + max(v.col for v in vals)
        n = self.node("ShaderNodeVectorMath", col, operation=op)
        if op == "SCALE":
            self.feed(n.inputs[0], vals[0])
            self.feed(n.inputs["Scale"], vals[1])
        else:
            for s, v in zip(n.inputs, vals):
                self.feed(s, v)
        self.inline(n)
        return Val(self, sock=n.outputs[out], vector=(out == 0), col=col)

    def binary(self, op, a, b):
        a, b = self.wrap(a), self.wrap(b)
        if (a.vector or b.vector) and (v := self._vector_folded(op, a, b)) is not None:
            return v
        if a.vector or b.vector:
            if op in ("ADD", "SUBTRACT") and a.vector and b.vector:
                return self.vmath(op, a, b)
            if op == "MULTIPLY" and a.vector and b.vector:
                return self.vmath("MULTIPLY", a, b)   # elementwise, as numpy and OSL
            if op == "MULTIPLY":
                return self.vmath("SCALE", a, b) if a.vector else self.vmath("SCALE", b, a)
            raise TypeError(f"unsupported vector operation {op}")
        if op == "ADD" and b.const == 0.0:
            return a
        if op == "ADD" and a.const == 0.0:
            return b
        if op == "MULTIPLY" and b.const == 1.0:
            return a
        if op == "MULTIPLY" and a.const == 1.0:
            return b
        return self.math(op, a, b)

    def _vector_folded(self, op, a, b):
        """A vector ``a op b`` needing no node (constant colours, identities) or a MAXIMUM node; None for the rest."""
        black, white = (0.0, 0.0, 0.0), (1.0, 1.0, 1.0)
        if op == "MULTIPLY" and a.vector != b.vector:   # a colour times a scalar
            v, s = (a, b) if a.vector else (b, a)
            if v.const is not None and s.const is not None:
                return self.wrap(tuple(c * s.const for c in v.const))
            if s.const == 0.0 or v.const == black:
                return self.wrap(black)
            return v if s.const == 1.0 else None
        if not (a.vector and b.vector):
            return None
        if a.const is not None and b.const is not None and op in _FOLD:
            return self.wrap(tuple(float(_FOLD[op](x, y)) for x, y in zip(a.const, b.const)))
        if (op == "ADD" and a.const == black) or (op == "MULTIPLY" and a.const == white):
            return b
        if (op in ("ADD", "SUBTRACT") and b.const == black) or (op == "MULTIPLY" and b.const == white):
            return a
        return self.vmath("MAXIMUM", a, b) if op == "MAXIMUM" else None

    # -- the ops namespace (same names as NumpyOps) ----------------------------
    def const(self, x):
        return Val(self, const=float(x))

    def exp(self, x):
        return self.math("EXPONENT", x)

    def log(self, x):
        return self.math("LOGARITHM", x, math.e)

    def sqrt(self, x):
        return self.math("SQRT", x)

    def sin(self, x):
        return self.math("SINE", x)

    def cos(self, x):
        return self.math("COSINE", x)

    def tan(self, x):
        return self.math("TANGENT", x)

    def mul_add(self, a, b, c):
        """a * b + c in one Multiply Add node (scalars)."""
        return self.math("MULTIPLY_ADD", a, b, c)

    def floor(self, x):
        return self.math("FLOOR", x)

    def abs(self, x):
        return self.math("ABSOLUTE", x)

    def minimum(self, a, b):
        return self.math("MINIMUM", a, b)

    def maximum(self, a, b):
        if self.wrap(a).vector or self.wrap(b).vector:   # elementwise, e.g. a colour with black
            return self.binary("MAXIMUM", a, b)
        return self.math("MAXIMUM", a, b)

    def atan2(self, y, x):
        return self.math("ARCTAN2", y, x)

    def power(self, x, y):
        return self.math("POWER", x, y)

    def less(self, a, b):
        return self.math("LESS_THAN", a, b)

    def select(self, cond, if_true, if_false):
        return cond * if_true + (1.0 - cond) * if_false

    def clamp01(self, x):
        return self.clamp(x)

    def _new_clamp(self, x, lo=0.0, hi=1.0):
        """``x`` clamped to [lo, hi] by one Clamp node (folded for a constant)."""
        x = self.wrap(x)
        if x.const is not None:
            return Val(self, const=min(max(x.const, lo), hi))
        n = self.node("ShaderNodeClamp", x.col + 1)
        self.feed(n.inputs["Value"], x)
        quiet_default(n.inputs["Min"], lo)
        quiet_default(n.inputs["Max"], hi)
        self.inline(n)
        return Val(self, sock=n.outputs[0], col=x.col + 1)

    def dot(self, a, b):
        return self.vmath("DOT_PRODUCT", a, b, out=1)

    def cross(self, a, b):
        return self.vmath("CROSS_PRODUCT", a, b)

    def length(self, a):
        return self.vmath("LENGTH", a, out=1)

    def scale(self, v, s):
        return self.vmath("SCALE", v, s)

    def _new_combine(self, x, y, z):
        vals = [self.wrap(v) for v in (x, y, z)]
        col = 1 + max(v.col for v in vals)
        n = self.node("ShaderNodeCombineXYZ", col)
        for s, v in zip(n.inputs, vals):
            self.feed(s, v)
        self.inline(n)
        return Val(self, sock=n.outputs[0], vector=True, col=col)

    def fori(self, count, body, state, done=None):
        """Not available: shader nodes have no loops (and unrolling a quadrature's 64 panels would blow
        Cycles' SVM stack).  Kernels with loops run in OSL: ``run`` puts them in a Script node."""
        raise NotImplementedError("shader nodes have no loops: run this kernel through NodeOps.run (OSL)")

    def _new_group(self, name, fn, *args):
        """``fn(m, *args)`` (scalar arguments; a scalar or a tuple of scalars) as one node group
        "AnalyticFog Kernel <name>" shared by every tree that calls it: built once per .blend (``name`` must
        say everything that changes what ``fn`` builds), a group node here.  Why: Blender's
        ``nodes.new`` costs time growing with the nodes already in the tree (500 nodes 0.9 s, 2 000 16 s),
        and Cycles and EEVEE inline groups, so what they compile is the same."""
        passed = self._socket_images()
        tree = self._kernel_group(f"{self.KERNEL_PREFIX} {name}", fn, len(args), [k for k, _ in passed])
        vals = [self.wrap(a) for a in args] + [v for _, v in passed]
        col = 1 + max(v.col for v in vals)
        n = self.node(self.GROUP_NODE, col)
        n.node_tree = tree
        for sock, v in zip(n.inputs, vals):
            self.feed(sock, v)
        outs = [Val(self, sock=o, col=col) for o in n.outputs]
        return outs[0] if len(outs) == 1 else tuple(outs)

    def _socket_images(self):
        """[(table name, Val)] of the tables this tree reads from an image socket, not an image of the file (a
        group shared by lights whose maps differ: ``comp_shafts.build_shaft_group``): a kernel group built here
        takes each as a colour input of its own."""
        return [(k, v) for k, v in self.images.items() if isinstance(v, Val)]

    def _kernel_group(self, name, fn, count, image_names=()):
        built = fingerprint.package_fingerprint(name)
        ng = bpy.data.node_groups.get(name)
        if ng is not None and ng.get(owned.BUILT) == built:
            return ng
        if ng is None:
            ng = bpy.data.node_groups.new(name, self.GROUP_TREE)
        ng.nodes.clear()
        ng.interface.clear()
        for k in range(count):
            ng.interface.new_socket(f"In {k}", in_out="INPUT", socket_type="NodeSocketFloat")
        for k in image_names:
            ng.interface.new_socket(f"Image {k}", in_out="INPUT", socket_type="NodeSocketColor")
        gin = ng.nodes.new("NodeGroupInput")
        gout = ng.nodes.new("NodeGroupOutput")
        sub = type(self)(ng, dict(self.images))
        sub.images.update((k, sub.wrap(gin.outputs[count + i], vector=True)) for i, k in enumerate(image_names))
        result = fn(sub, *(sub.wrap(o) for o in gin.outputs[:count]))
        result = result if isinstance(result, tuple) else (result,)
        for k, v in enumerate(result):
            ng.interface.new_socket(f"Out {k}", in_out="OUTPUT", socket_type="NodeSocketFloat")
            sub.feed(gout.inputs[k], sub.wrap(v))
        gout.location = (COLUMN * (1 + max(sub.wrap(v).col for v in result)), 0)
        sub.place()
        ng[owned.TAG] = True
        ng[owned.BUILT] = built
        return ng

    def run(self, rung, *args):
        """``rung.kernel`` as nodes if it runs in nodes, else as an OSL Script node fed with ``args``."""
        if "nodes" in rung.backends:
            return rung.kernel(self, *args)
        if "osl" not in rung.backends:
            raise ValueError(f"the {rung.name} model runs only in {', '.join(sorted(rung.backends))}")
        from . import osl
        node = osl.script_node(self.tree, rung)
        for name, v in zip(osl.kernel_inputs(rung), args):
            self.feed(node.inputs[name], self.wrap(v))
        return Val(self, sock=node.outputs[osl.OUTPUT], col=1 + max(self.wrap(v).col for v in args))

    def _table(self, spec, x, y, row0=0, rows=None, channel=0):
        """Bilinear lookup of ``channel`` from four Closest taps (EEVEE's Linear filter is not exact bilinear here).

        Few nodes, since every fogged material inlines it several times per light (Cycles' set-up grows
        with the square of a material's nodes, EEVEE's uniform block with their number): one Clamp node
        per coordinate, texel centres by Multiply Add, and each of the three interpolations in two nodes.
        """
        rows = spec.height if rows is None else rows
        if self.cycles:
            return self._linear(spec, x, y, row0, rows, channel)
        fx = self.clamp(x) * float(spec.width - 1)
        fy = self.clamp(y) * float(rows - 1)
        i = self.minimum(self.floor(fx), float(spec.width - 2))
        j = self.minimum(self.floor(fy), float(rows - 2))
        tx, ty = fx - i, fy - j
        u0 = self.math("MULTIPLY_ADD", i, 1.0 / spec.width, 0.5 / spec.width)
        u1 = u0 + 1.0 / spec.width
        v0 = self.math("MULTIPLY_ADD", j, 1.0 / spec.height, (row0 + 0.5) / spec.height)
        v1 = v0 + 1.0 / spec.height
        taps = [self.tap(spec, u, v, channel) for v in (v0, v1) for u in (u0, u1)]
        return self.lerp(self.lerp(taps[0], taps[1], tx), self.lerp(taps[2], taps[3], tx), ty)

    def _linear(self, spec, x, y, row0, rows, channel):
        """``_table``'s lookup as one Linear tap, for a tree only Cycles runs: Cycles interpolates a float image
        bilinearly between texel centres in float arithmetic, the four taps' value to 1e-6
        (docs/measurements/2026-11-29-viewport-preview.md); EEVEE's GPU filter weighs by fewer bits."""
        u = self.math("MULTIPLY_ADD", self.clamp(x), (spec.width - 1.0) / spec.width, 0.5 / spec.width)
        v = self.math("MULTIPLY_ADD", self.clamp(y), (rows - 1.0) / spec.height, (row0 + 0.5) / spec.height)
        uv = self.combine(u, v, 0.0)
        n = self._once(("linear", spec.name, self._ids((uv,))), lambda: self._new_tap(spec, uv, "Linear"))
        return self.texel(spec, n, uv.col + 1, channel)

    def lerp(self, a, b, t):
        """a + t (b - a) in two nodes (Subtract, Multiply Add).  Not a Mix node: in EEVEE its unused vector,
        colour and rotation inputs are uniforms too (16 lights: 92 464 bytes of node constants per
        material with Mix nodes, against the 65 536 EEVEE allows and 78 832 before)."""
        return self.math("MULTIPLY_ADD", t, self.wrap(b) - a, a)

    def tap(self, spec, u, v, channel):
        """The channel ``channel`` of the texel of table ``spec`` at the texture coordinates (``u``, ``v``): one
        Closest tap (the coordinates at a texel's centre)."""
        uv = self.combine(u, v, 0.0)
        n = self._once(("tap", spec.name, self._ids((uv,))), lambda: self._new_tap(spec, uv))
        return self.texel(spec, n, uv.col + 1, channel)

    def _new_tap(self, spec, uv, interpolation="Closest"):
        n = self.node("ShaderNodeTexImage", uv.col + 1, interpolation=interpolation, extension="EXTEND")
        n.image = self.images[spec.name]
        # A new node's texture mapping is not flagged as the identity until one of its values is set
        # (BKE_texture_mapping_init), so EEVEE made its matrix and bounds uniforms: 88 bytes a tap, 1 760
        # of a light's 4 610 (the flag is saved with the file).
        n.texture_mapping.translation = (0.0, 0.0, 0.0)
        self.tree.links.new(uv.sock, n.inputs["Vector"])
        self.inline(n)
        return n
