"""The fog's light as closures: a closure per light summed by a balanced tree of Add Shader nodes, the Fog Light
pass's running sum over them, and the Mix Shader that keeps the fog to the rays it is for.

Each shapes what Cycles compiles, whose limits a sum over many lights meets first: SVM's stack of 255 floats,
OSL's closure stack of 16 entries, and the nodes SVM jumps over where a Mix Shader's factor is 0, which also lets a
sample take one light of several (``drawn``).
"""
from ..precompute.model import sampling, shading


def closure_sum(m, sock, bl_idname, colours, gates=True):
    """Link into ``sock`` the sum of one ``bl_idname`` closure (Emission, Background) per colour
    (``shader_tree``).  A ``shading.Gated`` colour gets two: its rest (if any), and its glow behind a Mix
    Shader of factor gate, whose nodes Cycles' SVM jumps over where the gate is 0 (a spot's glow where the
    ray misses its cone: most of the view for a narrow beam); a glow that is a Gated itself gets its gate within
    (a cheap gate outside a dear one: SVM computes a gate before it jumps).

    ``gates`` False (the Surface group with the fog passes): the glow gets a closure of its own without the
    Mix Shader.  An AOV reads the glow's colour there (``chained_closure_sum``), so SVM computes its nodes
    before the jump anyway (svm.cpp ``generate_multi_closure``: an AOV's dependencies are shared by both
    sides), and ``chained_closure_sum`` takes the Emission closures' colours.  The glow and the rest stay two
    closures, never one of their sum: SVM compiles each closure's inputs' nodes as one set, in rounds over
    the nodes in id order (``generate_svm_nodes``), so the sum's closure had a spot's glow and its fog light
    on the surface computed side by side, every half-done value of both on its stack at once: 255 floats
    (out of SVM stack space, black) at one spot with a Fog Top, 232 without it; as two closures 153, what
    the material takes without the passes (155)."""
    ng = m.tree
    leaves = []

    def closure(k, colour, part=""):
        node = ng.nodes.new(bl_idname)
        node.name = node.label = f"Light {k} Fog{part}"
        node.location = (3600, -300 * k)
        m.feed(node.inputs["Color"], m.wrap(colour, vector=True))
        return node

    def parts(k, colour, part=""):   # a Gated's glow may be a Gated itself: a gate within a gate
        if not isinstance(colour, shading.Gated):
            return [closure(k, colour, part).outputs[0]]
        inner = parts(k, colour.glow, part + " Glow")
        if gates:
            if len(inner) > 1:
                add = ng.nodes.new("ShaderNodeAddShader")
                ng.links.new(inner[0], add.inputs[0])
                ng.links.new(inner[1], add.inputs[1])
                inner = [add.outputs[0]]
            mix = ng.nodes.new("ShaderNodeMixShader")
            mix.name = mix.label = f"Light {k}{part} Glow Gate"
            mix.location = (3800, -300 * k)
            m.feed(mix.inputs[0], m.wrap(colour.gate))
            ng.links.new(inner[0], mix.inputs[2])   # input 1 empty: no closure
            inner = [mix.outputs[0]]
        return inner + ([] if colour.rest is None else parts(k, colour.rest, part))

    for k, colour in enumerate(colours):
        leaves += parts(k, colour)
    shader_tree(ng, sock, leaves)


def shader_tree(ng, sock, shaders):
    """Link into ``sock`` the sum of the shader outputs ``shaders`` by Add Shader nodes.

    The Add Shader nodes form a balanced (pairwise) tree, depth ceil(log2 N), not a chain: Cycles' OSL
    flattens a shader's closure tree with a fixed 16-entry stack (``flatten_closure_tree``,
    intern/cycles/kernel/osl/osl.h), one entry per Add whose first input it is still walking, and
    silently drops whatever lies below once the stack is full.  A left-deep chain of N - 1 Adds kept
    the last 16 closures only (tests/scenes/closure_sum_probe.py): 25 lights rendered 25 % of the
    twin, 64 lights 2-7 %, no error in the log.  (Bundles of 8 lights under a tree of bundles: depth
    3 + log2 of the bundles.)  The leaves keep their order (light 0 first), which is the order SVM
    compiles them in, so SVM's stack use is the chain's (one light's values at a time).
    """
    x = max((s.node.location.x for s in shaders), default=3400.0) + 200
    level = [(s, -300.0 * k) for k, s in enumerate(shaders)]   # [(output socket, y)] of the tree's current level
    depth = 0
    while len(level) > 1:
        depth += 1
        pairs = []
        for (a, ya), (b, yb) in zip(level[0::2], level[1::2]):
            add = ng.nodes.new("ShaderNodeAddShader")
            add.location = (x + 200 * depth, 0.5 * (ya + yb))
            ng.links.new(a, add.inputs[0])
            ng.links.new(b, add.inputs[1])
            pairs.append((add.outputs[0], 0.5 * (ya + yb)))
        level = pairs + level[len(pairs) * 2:]  # an odd one out goes up a level as it is
    if level:
        ng.links.new(level[0][0], sock)


def camera_rays_only(ng, sock, is_camera, label="Camera Rays Only"):
    """Put the shader linked into ``sock`` behind a Mix Shader whose factor is Is Camera Ray (or the
    socket ``is_camera``: a factor of exactly 0 or 1).

    The fog's light is added on camera rays only (``shading.shade_surface``); on every other ray the
    Mix Shader's factor is exactly 0 and Cycles' SVM jumps over the nodes that feed only its second
    input (svm.cpp, NODE_JUMP_IF_ZERO): bounce rays hitting fogged surfaces then skip every light's
    glow and scattered fog light (boulevard, 45 lamps, 160x90, 4 spp: 270 -> 132 us of render CPU
    per sample).  Not with the Fog Passes: an AOV reads those nodes too, so SVM runs them on every
    ray anyway, and the Mix would undo the compile order that keeps the passes' sums off SVM's stack
    (``chained_closure_sum``: 24 lights overflowed with it).
    """
    if not sock.is_linked:
        return
    src = sock.links[0].from_socket
    mix = ng.nodes.new("ShaderNodeMixShader")
    mix.name = mix.label = label
    mix.location = (sock.node.location.x - 200, sock.node.location.y)
    ng.links.new(is_camera, mix.inputs[0])
    ng.links.new(src, mix.inputs[2])
    ng.links.new(mix.outputs[0], sock)


def exact_zero(m, v):
    """(0, 0, 0) computed from the vector ``v``: max(min(v, 0), 0), exactly 0 for any v (NaN too), which
    neither Blender's inlining nor Cycles' constant folding removes.  A data dependency on ``v`` only."""
    black = (0.0, 0.0, 0.0)
    return m.vmath("MAXIMUM", m.vmath("MINIMUM", v, black), black)


def chained_closure_sum(m, sock, total=None):
    """The Fog Light pass of the Surface group: the sum of the colours of the closures linked into ``sock``
    (the Fog shader's Emission closures under their Add Shader tree), each closure's Strength made to
    depend on the running sum up to it (a Strength of exactly 1).

    Why: Cycles' SVM compiles each closure with its own inputs' nodes, and the AOV outputs' nodes after
    all closures (svm.cpp ``compile_type``).  A colour every closure computes and the AOV pass still
    needs stays on SVM's stack of 255 floats until then: the pass's sum over the lights kept each
    light's colour there, 3 floats a light (a glossy material of tests/scenes/passes_many_lights.py:
    118 floats at 4 lights, 178 at 24, out of SVM stack space and black at 64).  With each closure's
    Strength reading the running sum, the sum's Add of light k is compiled with closure k and only
    the running sum is kept: 115 floats at 4 to 64 lights.  The leaves are taken in the order SVM
    compiles them (each Add Shader's first input first).  ``total``: the sum so far (the bundles before
    this one, ``surface_group.build_surface_bundle``), or None.
    """
    leaves, todo = [], [sock]
    while todo:
        s = todo.pop()
        if not s.is_linked:
            continue
        node = s.links[0].from_node
        if node.bl_idname == "ShaderNodeAddShader":
            todo += [node.inputs[1], node.inputs[0]]   # the first input is popped (compiled) first
        else:
            leaves.append(node)
    for node in leaves:
        colour = m.wrap(node.inputs["Color"].links[0].from_socket if node.inputs["Color"].is_linked
                        else tuple(node.inputs["Color"].default_value), vector=True)
        if total is None:
            total = colour
            continue
        total = total + colour
        # Strength = max(min(sum, 0), 1) = 1 (the sum's grey, implicitly converted)
        if total.sock is not None and "Strength" in node.inputs:
            one = m.math("MAXIMUM", m.math("MINIMUM", m.wrap(total.sock), 0.0), 1.0)
            m.feed(node.inputs["Strength"], one)
    return total if total is not None else m.wrap((0.0, 0.0, 0.0))


def pick_noise(ng, position, w=3.17, label="Tail Pick"):
    """A uniform number in [0, 1) a sample, its own (not the shares' jitter): a White Noise of ``position`` (an output
    socket), which the pixel filter moves at every sample; its output socket."""
    noise = ng.nodes.new("ShaderNodeTexWhiteNoise")
    noise.noise_dimensions, noise.name, noise.label = "4D", label, label
    noise.inputs["W"].default_value = w   # (another W: numbers independent of another draw's)
    ng.links.new(position, noise.inputs["Vector"])
    return noise.outputs["Value"]


def drawn(m, colour, pick, chances, k):
    """Light ``k``'s colour (a colour or ``shading.Gated``) on the samples that take it (``sampling.picked``): a
    ``shading.Gated`` of that gate, times 1 / p_k; a Gated colour's own gate (a lit share: a quadrature) within it,
    so that SVM computes it only on those samples."""
    taken, weight = sampling.picked(m, pick, chances, k)
    times = lambda c: None if c is None else m.scale(m.wrap(c, vector=True), weight)
    if isinstance(colour, shading.Gated):
        return shading.Gated(taken, shading.Gated(colour.gate, times(colour.glow), times(colour.rest)), None)
    return shading.Gated(taken, times(colour), None)
