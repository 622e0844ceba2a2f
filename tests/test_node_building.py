"""The node builder writes constants and places nodes without tree updates (``sockets.quiet_default``,
``NodeOps.place``): the values and places must be what a plain RNA set would have given.

The snippet builds a few nodes of each kind of socket (floats only, a vector beside a float, the mixed sockets
of Map Range that take the RNA fallback) into a shader and a compositor group and reads them back through RNA: the
expected values are the constants fed, and each node at its own place on the builder's grid.
"""
import json

import pytest

from fog_scenes import render_harness as h

pytestmark = pytest.mark.render   # Blender (bpy), in a subprocess

_CODE = r"""
import json, sys
import bpy
from fog_addon.nodes import sockets
bpy.ops.wm.read_factory_settings(use_empty=True)
out = {}
for kind in ("ShaderNodeTree", "CompositorNodeTree"):
    ng = bpy.data.node_groups.new("T", kind)
    gin = ng.nodes.new("NodeGroupInput")
    ng.interface.new_socket("x", in_out="INPUT", socket_type="NodeSocketFloat")
    m = sockets.NodeOps(ng)
    x = m.wrap(gin.outputs[0])
    a = m.math("MULTIPLY_ADD", x, 2.5, -0.75)          # float sockets: the node's inputs at once
    b = m.vmath("SCALE", m.combine(x, 3.0, 4.0), 1.5)  # a vector socket's array and a float beside it
    c = m.smoothstep(0.25, 4.0, a)                     # Map Range: mixed sockets, the RNA fallback
    d = m.vmath("ADD", b, (0.5, -1.0, 2.0))            # a constant vector
    e = m.clamp(a, -1.0, 7.0)
    m.place()
    nodes = {n.name: n for n in ng.nodes}
    node = lambda v: v.sock.node
    out[kind] = {
        "mul_add": [s.default_value for s in node(a).inputs][1:],
        "combine": [s.default_value for s in node(b).inputs[0].links[0].from_node.inputs][1:],
        "scale": node(b).inputs["Scale"].default_value,
        "map_range": [node(c).inputs[k].default_value for k in (1, 2)],
        "add": list(node(d).inputs[1].default_value),
        "clamp": [node(e).inputs["Min"].default_value, node(e).inputs["Max"].default_value],
        "places": sorted({tuple(round(v, 3) for v in n.location) for n in ng.nodes if n != gin}),
        "count": len(ng.nodes) - 1,
    }
out["grid"] = [sockets.COLUMN, sockets.ROW]
print("RESULT " + json.dumps(out))
"""


def test_constants_and_places_are_set_without_updates():
    log = h.run_bpy_code(_CODE, timeout=300).stdout
    out = json.loads(next(ln for ln in log.splitlines() if ln.startswith("RESULT "))[7:])
    column, row = out.pop("grid")
    assert len(out) == 2
    for got in out.values():
        assert got["mul_add"] == pytest.approx([2.5, -0.75])
        assert got["combine"] == pytest.approx([3.0, 4.0])
        assert got["scale"] == pytest.approx(1.5)
        assert got["map_range"] == pytest.approx([0.25, 4.0])
        assert got["add"] == pytest.approx([0.5, -1.0, 2.0])
        assert got["clamp"] == pytest.approx([-1.0, 7.0])
        # every built node moved to its own grid place: none left at the origin, no two at one place
        assert len(got["places"]) == got["count"] and [0.0, 0.0] not in [list(p) for p in got["places"]]
        assert all(x % column == 0 and y % row == 0 for x, y in got["places"])
