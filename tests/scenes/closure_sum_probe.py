"""The fog's per-light closure sum (``closures.closure_sum``) renders every closure, in SVM and OSL.

    python tests/scenes/closure_sum_probe.py OUT_DIR N [N ...]

For each N: a plane whose material is the sum of N Emission closures and a
World that is the sum of N Background closures, both built by
``_closure_sum`` from N different constant colours, rendered by Cycles SVM
and OSL (4x4 px, 1 spp, pixel centres).  Cycles' OSL flattens a closure tree
with a 16-entry stack and silently drops what lies deeper (a left-deep chain
of Add Shader nodes kept 16 of 64 closures); the sum must come out whole.

Prints one line ``CLOSURE_SUM_JSON {...}``: per N, the tree's OSL flattening
depth (``osl_stack_depth``: the most Add nodes whose second input is waiting
on the stack, Cycles' limit is 16) and, per shading system and target
(surface, world), the rendered RGB over the expected sum.
"""
import json
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import bpy  # noqa: E402
import numpy as np  # noqa: E402

from fog_addon import imageio, measure  # noqa: E402
from fog_addon.nodes import closures  # noqa: E402
from fog_addon.nodes.sockets import NodeOps  # noqa: E402


def colours(n):
    return [(1.0, (k + 1.0) / n, 0.25 + 0.5 * (k % 3)) for k in range(n)]


def _varying(m, cols):
    """The colours times Is Camera Ray (1 here): computed, as the fog's are; a constant World would take
    Cycles' constant-background shortcut and never run the closure tree."""
    one = m.wrap(m.tree.nodes.new("ShaderNodeLightPath").outputs["Is Camera Ray"])
    return [one * m.wrap(c) for c in cols]


def osl_stack_depth(sock):
    """Entries Cycles' OSL ``flatten_closure_tree`` pushes at most for the closure linked into ``sock``:
    at an Add it walks the first input with the second one pushed."""
    if not sock.is_linked:
        return 0
    node = sock.links[0].from_node
    if node.bl_idname == "ShaderNodeAddShader":
        return max(osl_stack_depth(node.inputs[0]) + 1, osl_stack_depth(node.inputs[1]))
    return 0


def build(n):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    s = bpy.context.scene
    s.render.engine = "CYCLES"
    measure.set_cycles_cpu(s)
    measure.set_resolution(s, 4, 4)
    measure.set_samples(s, 1)
    measure.set_pixel_centre_filter(s)
    s.cycles.max_bounces = 0
    cols = colours(n)

    mat = bpy.data.materials.new("sum")
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    m = NodeOps(nt, {})
    closures.closure_sum(m, out.inputs["Surface"], "ShaderNodeEmission", _varying(m, cols))
    depth = osl_stack_depth(out.inputs["Surface"])
    bpy.ops.mesh.primitive_plane_add(size=2.0)
    plane = bpy.context.object
    plane.data.materials.append(mat)

    world = bpy.data.worlds.new("sum")
    s.world = world
    wt = world.node_tree
    wt.nodes.clear()
    wout = wt.nodes.new("ShaderNodeOutputWorld")
    wm = NodeOps(wt, {})
    closures.closure_sum(wm, wout.inputs["Surface"], "ShaderNodeBackground", _varying(wm, cols))

    cam = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    s.collection.objects.link(cam)
    s.camera = cam
    return s, plane, cam, depth, np.sum(np.array(cols), axis=0)


def render(s, path):
    return imageio.read_rgb(measure.render_to_file(s, path))


def main(out_dir, *ns):
    res = {}
    for n in map(int, ns):
        s, plane, cam, depth, want = build(n)
        r = {"osl_stack_depth": depth}
        for osl in (False, True):
            s.cycles.shading_system = osl
            for target, z in (("surface", 1.0), ("world", -1.0)):   # looking down: the plane / the sky
                cam.location = (0.0, 0.0, z)
                img = render(s, str(pathlib.Path(out_dir) / f"sum_{n}_{int(osl)}_{target}.exr"))
                got = img.reshape(-1, 3).mean(axis=0)
                r[f"{'osl' if osl else 'svm'}_{target}"] = [float(g / w) for g, w in zip(got, want)]
        res[n] = r
    print("CLOSURE_SUM_JSON " + json.dumps(res), flush=True)


if __name__ == "__main__":
    main(*sys.argv[1:])
