"""The OSL backend of the shader ops: ``model.py`` formulas printed as an OSL shader (Cycles only).

``OslOps`` mirrors ``fog_addon.precompute.core.ops.NumpyOps`` function by function,
but each operation appends a line of OSL instead of computing a value, so
the shader is the very code the numpy model runs.  Loops (``fori``) print as
``for`` loops; tables are not available (OSL's ``texture()`` cannot read images
packed into the .blend), so only table-free rungs (``rungs.py``) run here:
the OSL method takes the airlight by quadrature (``model.airlight_quadrature``)
rather than from the N table.  Each such rung becomes one shader whose float
inputs are its kernel's arguments.

The shader's text is an internal text data-block, compiled into the Script
node (bytecode saved in the .blend): a saved file renders on a farm without
the add-on.
"""
import inspect
import re
import sys

import bpy

from ..precompute.core import fingerprint
from ..precompute.model import rungs
from . import owned

PREFIX = "AnalyticFog"
SHADER_PREFIX = "analytic_fog_"
OUTPUT = "result"


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

    def log(self, x):
        return self.select(self.less(0.0, x), self.call("log", self.maximum(x, 1e-37)), 0.0)

    def sqrt(self, x):
        return self.call("sqrt", self.maximum(x, 0.0))

    def sin(self, x):
        return self.call("sin", x)

    def cos(self, x):
        return self.call("cos", x)

    def tan(self, x):
        return self.call("tan", x)

    def mul_add(self, a, b, c):
        return self.wrap(a) * b + c

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
        return cond * if_true + (1.0 - cond) * if_false

    def clamp01(self, x):
        return self.call("clamp", x, 0.0, 1.0)

    def smoothstep(self, edge0, edge1, x):
        return self.call("smoothstep", edge0, edge1, x)

    def dot(self, a, b):
        return self.call("dot", a, b)

    def cross(self, a, b):
        return self.call("cross", a, b, vector=True)

    def length(self, a):
        return self.call("length", a)

    def scale(self, v, s):
        return self.wrap(v) * s

    def combine(self, x, y, z):
        return self.call("vector", x, y, z, vector=True)

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

    def table(self, spec, x, y, row0=0, rows=None, nearest=False):
        """Not available: OSL's texture() cannot read images packed into the .blend (and a farm file
        must not depend on files beside it), so OSL runs only table-free rungs."""
        raise NotImplementedError("OSL cannot read packed images: only table-free models run in OSL")

    def group(self, name, fn, *args):
        """``fn(self, *args)`` printed inline (the node backend shares it as a node group)."""
        return fn(self, *args)

    def run(self, rung, *args):
        """``rung.kernel`` printed into this shader (it must run in OSL)."""
        if "osl" not in rung.backends:
            raise ValueError(f"the {rung.name} model does not run in OSL")
        return rung.kernel(self, *args)


def kernel_inputs(rung):
    """The names of ``rung.kernel``'s arguments after ``m``: the Script node's float inputs, in order."""
    return [p.name for p in inspect.signature(rung.kernel).parameters.values()
            if p.default is p.empty][1:]   # not the anisotropy g (a default, or bound per g: rungs.anisotropic_rungs)


def text_name(rung):
    return f"{PREFIX} {rung.name}.osl"


def kernel_source(rung):
    """OSL source of ``rung.kernel``, printed by OslOps: one float output ``OUTPUT`` from float inputs."""
    m = OslOps()
    names = kernel_inputs(rung)
    result = m.wrap(rung.kernel(m, *(OslVal(m, n) for n in names)))
    body = "\n".join(m.lines)
    params = "".join(f"    float {n} = 0.0,\n" for n in names)
    fn = getattr(rung.kernel, "func", rung.kernel)   # a kernel with g bound (rungs.anisotropic_rungs)
    version = fingerprint.package_fingerprint()   # of all the add-on's source
    return (f"{HEADER} {version}: {rung.name} ({rung.term}), {fn.__module__}.{fn.__name__}\n"
            f"// Printed by fog_addon/nodes/osl.py from fog_addon/precompute; do not edit.\n"
            f"shader {SHADER_PREFIX}{re.sub(r'[^A-Za-z0-9_]', '_', rung.name)}(\n"
            f"{params}"
            f"    output float {OUTPUT} = 0.0)\n"
            f"{{\n{body}\n    {OUTPUT} = {result.expr};\n}}\n")


def kernel_text(rung):
    """The internal text holding ``rung``'s shader, (re)written when missing or outdated."""
    src = kernel_source(rung)
    text = bpy.data.texts.get(text_name(rung))
    if text is None:
        text = bpy.data.texts.new(text_name(rung))
    if text.as_string() != src:
        text.from_string(src)
    return text


HEADER = "// Analytic Fog"   # every text kernel_source writes starts with this


def text_names():
    """Names of the texts of every rung that runs in OSL (what ``remove`` and ``dedupe`` look for): the
    isotropic rungs' and those of anisotropic rungs (``rungs.anisotropic_rungs``) in the file."""
    names = [text_name(r) for r in rungs.RUNGS if "osl" in r.backends]
    return names + sorted({owned.base_name(t.name) for t in bpy.data.texts
                           if t.name.startswith(PREFIX) and t.as_string().startswith(HEADER)} - set(names))


def _oslquery_path():
    """oslquery (needed to compile script nodes) sits in bpy's bundled site-packages."""
    import glob
    import os
    lib = os.path.join(bpy.utils.resource_path("LOCAL"), "python", "lib")
    for p in glob.glob(os.path.join(lib, "python3*", "site-packages")):
        if p not in sys.path:
            sys.path.append(p)


def script_node(tree, rung):
    """A compiled Script node running ``rung``'s shader, added to ``tree``."""
    _oslquery_path()   # setting the script below makes Cycles compile it (when Cycles is the engine)
    node = tree.nodes.new("ShaderNodeScript")
    node.mode = "INTERNAL"
    node.script = kernel_text(rung)
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
