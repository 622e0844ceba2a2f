"""The OSL backend of the shader ops: ``model.py`` formulas printed as an OSL shader (Cycles only).

``OslOps`` mirrors ``fog_addon.precompute.ops.NumpyOps`` function by function,
but each operation appends a line of OSL instead of computing a value, so
the shader is the very code the numpy model runs.  Loops (``fori``) print as
``for`` loops; tables are not available (OSL's ``texture()`` cannot read images
packed into the .blend), which is why the OSL method takes the airlight by
quadrature (``model.airlight_quadrature``) rather than from the N table.

The shader's text is an internal text data-block, compiled into the Script
node (bytecode saved in the .blend): a saved file renders on a farm without
the add-on.
"""
import sys

import bpy

from ..precompute import model

TEXT = "AnalyticFog Airlight.osl"
SHADER = "analytic_fog_airlight"
VERSION = 1   # bump when the printed shader changes: existing texts are then rewritten


class OslVal:
    """An OSL expression: a variable name or a literal; arithmetic appends lines to ``ops``."""
    __slots__ = ("ops", "expr", "vector")

    def __init__(self, ops, expr, vector=False):
        self.ops, self.expr, self.vector = ops, expr, vector

    def _bin(self, other, op, swap=False):
        a, b = self, self.ops.wrap(other)
        if swap:
            a, b = b, a
        return self.ops.emit(f"{a.expr} {op} {b.expr}", a.vector or b.vector)

    __add__ = lambda s, o: s._bin(o, "+")
    __radd__ = lambda s, o: s._bin(o, "+", True)
    __sub__ = lambda s, o: s._bin(o, "-")
    __rsub__ = lambda s, o: s._bin(o, "-", True)
    __mul__ = lambda s, o: s._bin(o, "*")
    __rmul__ = lambda s, o: s._bin(o, "*", True)
    __truediv__ = lambda s, o: s._bin(o, "/")
    __rtruediv__ = lambda s, o: s._bin(o, "/", True)

    def __neg__(self):
        return self.ops.emit(f"-{self.expr}", self.vector)


def _literal(x):
    s = repr(float(x))
    return f"({s})" if s.startswith("-") else s


class OslOps:
    """Collects the lines of a shader body; same function names as NumpyOps."""

    def __init__(self):
        self.lines = []
        self.indent = 1
        self._count = 0

    def wrap(self, x):
        return x if isinstance(x, OslVal) else OslVal(self, _literal(x))

    def emit(self, expr, vector=False):
        name = f"t{self._count}"
        self._count += 1
        self.lines.append("    " * self.indent + f"{'vector' if vector else 'float'} {name} = {expr};")
        return OslVal(self, name, vector)

    def call(self, fn, *args, vector=False):
        return self.emit(f"{fn}({', '.join(self.wrap(a).expr for a in args)})", vector)

    # -- the ops namespace (same names and semantics as NumpyOps) --------------
    def const(self, x):
        return self.wrap(x)

    def exp(self, x):
        return self.call("exp", x)

    def sqrt(self, x):
        return self.call("sqrt", self.maximum(x, 0.0))

    def sin(self, x):
        return self.call("sin", x)

    def cos(self, x):
        return self.call("cos", x)

    def floor(self, x):
        return self.call("floor", x)

    def abs(self, x):
        return self.call("fabs", x)

    def minimum(self, a, b):
        return self.call("min", a, b)

    def maximum(self, a, b):
        return self.call("max", a, b)

    def atan2(self, y, x):
        return self.call("atan2", y, x)

    def power(self, x, y):
        return self.call("pow", x, y)

    def less(self, a, b):
        a, b = self.wrap(a), self.wrap(b)
        return self.emit(f"{a.expr} < {b.expr} ? 1.0 : 0.0")

    def select(self, cond, if_true, if_false):
        return if_false + cond * (if_true - if_false)

    def clamp01(self, x):
        return self.call("clamp", x, 0.0, 1.0)

    def dot(self, a, b):
        return self.call("dot", a, b)

    def cross(self, a, b):
        return self.call("cross", a, b, vector=True)

    def length(self, a):
        return self.call("length", a)

    def scale(self, v, s):
        return self.wrap(v) * s

    def fori(self, count, body, state, done=None):
        """A ``for`` loop of ``count`` passes over ``body``, leaving it once ``done`` is 1 (see NumpyOps.fori)."""
        state = [self.wrap(s) for s in state]
        names = []
        for s in state:
            v = self.emit(s.expr, s.vector)
            names.append(v)
        pad = "    " * self.indent
        self.lines.append(pad + f"for (int i = 0; i < {int(count)}; i++) {{")
        self.indent += 1
        new = [self.wrap(v) for v in body(*names)]
        for v, n in zip(new, names):
            self.lines.append("    " * self.indent + f"{n.expr} = {v.expr};")
        if done is not None:
            self.lines.append("    " * self.indent + f"if ({self.wrap(done(*names)).expr} > 0.5) break;")
        self.indent -= 1
        self.lines.append(pad + "}")
        return tuple(names)

    def table(self, spec, x, y, row0=0, rows=None):
        raise NotImplementedError("OSL cannot read packed images: the OSL method uses no tables")


def airlight_source():
    """OSL source of the per-light airlight: Sun et al. 2005 Eq. 5 by ``model.airlight_quadrature``.

    Inputs: Beta (1/m), Light and Camera positions (m), the ray's unit
    Direction, Distance to the surface (m; model.FAR for the background).
    Output: Airlight per unit intensity (1/m^2).
    """
    m = OslOps()
    beta, light, camera, direction, distance = (
        OslVal(m, n, v) for n, v in (("Beta", False), ("Light", True), ("Camera", True),
                                     ("Direction", True), ("Distance", False)))
    d_sv, along, h = model.ray_light_geometry(m, camera, direction, light)
    air = model.airlight_quadrature(m, beta, d_sv, along, h, distance)
    body = "\n".join(m.lines)
    return (f"// Analytic Fog v{VERSION}: airlight of one point light by quadrature of Sun et al. 2005 Eq. 5.\n"
            f"// Printed by fog_addon/nodes/osl.py from fog_addon/precompute/model.py; do not edit.\n"
            f"shader {SHADER}(\n"
            f"    float Beta = 0.0,\n"
            f"    vector Light = vector(0.0),\n"
            f"    vector Camera = vector(0.0),\n"
            f"    vector Direction = vector(0.0, 0.0, 1.0),\n"
            f"    float Distance = {_literal(model.FAR)},\n"
            f"    output float Airlight = 0.0)\n"
            f"{{\n{body}\n    Airlight = {air.expr};\n}}\n")


def airlight_text():
    """The internal text holding the shader, (re)written when missing or outdated."""
    src = airlight_source()
    text = bpy.data.texts.get(TEXT)
    if text is None:
        text = bpy.data.texts.new(TEXT)
    if text.as_string() != src:
        text.from_string(src)
    return text


def _oslquery_path():
    """oslquery (needed to compile script nodes) sits in bpy's bundled site-packages."""
    import glob
    import os
    lib = os.path.join(bpy.utils.resource_path("LOCAL"), "python", "lib")
    for p in glob.glob(os.path.join(lib, "python3*", "site-packages")):
        if p not in sys.path:
            sys.path.append(p)


def script_node(tree):
    """A compiled Script node running the airlight shader, added to ``tree``."""
    _oslquery_path()   # setting the script below makes Cycles compile it (when Cycles is the engine)
    node = tree.nodes.new("ShaderNodeScript")
    node.mode = "INTERNAL"
    node.script = airlight_text()
    if not node.bytecode:   # not compiled yet, or it failed: compile here to get the error
        compile_node(node)
    return node


def compile_node(node):
    """Compile ``node``'s script (Cycles' own compiler); raises RuntimeError with OSL's message on failure."""
    _oslquery_path()
    from cycles import osl as cycles_osl
    errors = []

    def report(kind, msg):
        if "ERROR" in kind:
            errors.append(msg)

    cycles_osl.update_script_node(node, report)
    if errors or not node.bytecode:
        raise RuntimeError("could not compile the fog's OSL shader: " + "; ".join(errors))
