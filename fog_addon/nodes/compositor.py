"""Keeping Cycles' denoiser off the fog: a compositor set-up that denoises only what is noisy.

The fog is noise-free, but Cycles' denoiser (on in every new scene) takes its
sharp glows for noise: on a one-lamp scene at 64x48 and 16 spp it made the
lamp's peak pixel 35 % too dark and brightened its neighbours.  While the fog
is on, a scene that Cycles renders with its denoiser on gets instead, after
each of the scene's Render Layers nodes (view layers that denoise):

    Image - Emitted -> Denoise (Denoising Albedo - Emitted and Denoising
    Normal, as the scene's denoiser uses them) -> + Emitted -> what the Image fed

and the render denoiser off, so only the rest of the picture is denoised and
the light emitted toward the camera is added back as rendered.  Emitted is
Cycles' own Emission plus Environment passes: every fogged material's fog
light is emission on camera rays, and the World's glow is the background the
camera sees, so Emitted holds the fog's light (plus the user's own emitters
and sky seen directly, which are noise-free too).  Built-in passes cost
nothing to render, unlike the shader AOVs of ``passes.py`` (+26 % render
time on the street lamps), which stay the artist's choice.  The Denoise node
takes the scene's prefilter, quality and input passes.  Cycles' Denoising
Albedo counts emission, so the fog's light too (a black ground reads as
bright as its airlight); the guide is that minus Emitted, the albedo of the
picture being denoised (on tests/scenes/passes_probe.py it left the noise of
a sphere at 0.26 of the raw render's, against 0.41 with the albedo as Cycles
writes it).

* A scene without a compositor node group gets the fog's own
  (``AnalyticFog Compositor``: Render Layers -> chain -> Group Output), with
  Compositing switched on; Remove unassigns and deletes it.
* A scene with one of the user's has the chain spliced in front of it: the
  Render Layers node's Image links go through the fog's nodes (tagged as its
  own, ``owned.py``), nothing of the user's is edited, and Remove links the
  Image back.  The user's graph is left alone (and the denoiser on, with a
  note saying why) when it is linked from a library, Compositing is off,
  Render Layers of the scene sit inside a nested group, a link reads Noisy
  Image (gone with the render denoiser off).
* The denoiser's chain is not for EEVEE (Cycles' denoiser flag does not apply).  ``follow`` sets the
  set-up up or takes it down as the engine and the denoiser flag change.

With the Compositor method (``comp_fog.py``) the render holds no fog light: Cycles' denoiser stays on,
and the chain after each Render Layers node is instead one group node, the fog's ``AnalyticFog
Compositor Fog``, fed with the Image and the method's AOVs, which adds the fog's light.  It is spliced
into a user's compositor the same way, for every view layer that renders, denoised or not, in Cycles and
EEVEE (where the group also reads the Depth pass, switched on and restored like the passes below).  With the
fog passes a File Output node of the fog's after it writes the group's Fog Light and Fog Transmittance
(``passes_directory``: beside the render's output, a multilayer EXR per view layer and frame,
``passes_file_name``): the view layers' own
passes cannot take what the compositor computes.

The settings changed (the scene's denoiser and Compositing flags, each view
layer's Emission, Environment, Denoising Data and Depth passes) are recorded by ``overrides.py`` and restored
exactly by ``teardown``; the scene's ``STATE`` names the tree the fog edited.
"""
import json
import os

import bpy

from . import overrides, owned, passes

EMISSION, ENVIRONMENT = "Emission", "Environment"   # the Render Layers outputs of Cycles' Emit and Env passes
DEPTH = "Depth"   # the Render Layers output of the Z pass (``use_pass_z``), which the fog group reads in EEVEE
STATE = "analytic_fog_compositor"   # on the scene: {"tree": the compositor tree the fog edited or made,
#                                      "fog": True for the Compositor method's chain, else the denoiser's}
LINKS = "links"   # in STATE: JSON [[Render Layers node, node, input identifier], ...], the user's links from each
#                   spliced Render Layers' Image, which ``teardown`` gives back whatever became of the chain
GROUP = "AnalyticFog Compositor"
PASSES_SUFFIX = "Fog Passes"
_PREFILTER = {"NONE": "None", "FAST": "Fast", "ACCURATE": "Accurate"}
_QUALITY = {"HIGH": "High", "BALANCED": "Balanced", "FAST": "Fast"}
_MIX_A, _MIX_B, _MIX_OUT = "A_Color", "B_Color", "Result_Color"   # ShaderNodeMix (RGBA) socket identifiers


def _sock(sockets, identifier):
    return next(s for s in sockets if s.identifier == identifier)


def is_set_up(scene):
    return scene.get(STATE) is not None


def wanted(scene, fog=None):
    """True if ``scene`` should have the set-up: Cycles with its denoiser on (or set up already), or with
    the Compositor method's ``fog`` group."""
    if fog is not None:
        return True
    if scene.render.engine != "CYCLES":
        return False
    return scene.cycles.use_denoising or (is_set_up(scene) and not scene[STATE].get("fog"))


def follow(scene, rebuild=False, fog=None):
    """Set the set-up up or take it down as ``scene`` needs; returns [(name, note)].

    Cheap when nothing changed (the depsgraph handler calls it).  ``rebuild``:
    rebuild a set-up in place (it takes the scene's current denoiser settings).  ``fog``: the
    Compositor method's group (``comp_fog.FOG_GROUP``), None for the other methods.
    """
    if not wanted(scene, fog):
        teardown(scene)
        return []
    if is_set_up(scene):
        if not rebuild and bool(scene[STATE].get("fog")) == (fog is not None) and (
                fog is None or scene[STATE].get("engine") == scene.render.engine):   # the fog group's inputs
            if fog is None and scene.cycles.use_denoising:   # switched back on by hand: the fog's Denoise does it
                scene.cycles.use_denoising = False
            return []
        teardown(scene)
    return setup(scene, fog)


# --- which Render Layers nodes -------------------------------------------------------------

def _renders(scene, node):
    return (node.bl_idname == "CompositorNodeRLayers" and not node.mute and not owned.is_ours(node)
            and (node.scene is None or node.scene == scene))


def _layer(scene, node):
    return scene.view_layers.get(node.layer)


def _denoised(scene, vl):
    return vl is not None and vl.use and vl.cycles.use_denoising


def _nested(tree, scene, seen=()):
    """Names of node groups inside ``tree`` holding a Render Layers node of ``scene``."""
    found = []
    for n in tree.nodes:
        g = getattr(n, "node_tree", None) if n.bl_idname == "CompositorNodeGroup" else None
        if g is None or g in seen:
            continue
        if any(_renders(scene, m) for m in g.nodes) or _nested(g, scene, seen + (g,)):
            found.append(g.name)
    return found


def _why_not(scene, tree, nodes, fog):
    """Why the user's compositor ``tree`` (with Render Layers ``nodes`` to splice) is left alone, or None."""
    why = owned.read_only(tree)
    if why:
        return f"its compositor node group {tree.name!r} {why.split(':')[0]}"
    if any(owned.is_ours(n) for n in tree.nodes):
        return f"{tree.name!r} has the fog's set-up for another scene already"
    if not scene.render.use_compositing:
        return f"Compositing is off (Output properties > Post Processing) and {tree.name!r} is yours"
    nested = _nested(tree, scene)
    if nested:
        return f"Render Layers inside node group {', '.join(map(repr, nested))} of {tree.name!r} cannot be spliced"
    if fog is None and any(n.outputs.get("Noisy Image") is not None and n.outputs["Noisy Image"].is_linked
                           for n in tree.nodes if _renders(scene, n)):
        return f"{tree.name!r} reads Noisy Image, which Cycles writes only with its denoiser on"
    return None


# --- building and taking apart ------------------------------------------------------------------

def _chain(scene, tree, rl, k):
    """Image - Emitted -> Denoise -> + Emitted after Render Layers ``rl``; returns the last output."""
    rl.update()   # the view layer's Emission, Environment and Denoising Data passes become outputs
    c = scene.cycles
    x, y = rl.location.x + 300, rl.location.y - 40 - 360 * k
    role = f"Compositor {k}"
    emitted = owned.add(tree, "ShaderNodeMix", f"{role} Emitted", (x, y + 160), data_type="RGBA", blend_type="ADD")
    emitted.inputs[0].default_value = 1.0
    tree.links.new(rl.outputs[EMISSION], _sock(emitted.inputs, _MIX_A))
    tree.links.new(rl.outputs[ENVIRONMENT], _sock(emitted.inputs, _MIX_B))
    fog_light = _sock(emitted.outputs, _MIX_OUT)
    sub = owned.add(tree, "ShaderNodeMix", f"{role} Subtract", (x, y), data_type="RGBA", blend_type="SUBTRACT")
    sub.inputs[0].default_value = 1.0
    tree.links.new(rl.outputs["Image"], _sock(sub.inputs, _MIX_A))
    tree.links.new(fog_light, _sock(sub.inputs, _MIX_B))
    den = owned.add(tree, "CompositorNodeDenoise", f"{role} Denoise", (x + 200, y))
    den.inputs["HDR"].default_value = True
    den.inputs["Prefilter"].default_value = _PREFILTER.get(c.denoising_prefilter, "Accurate")
    den.inputs["Quality"].default_value = _QUALITY.get(c.denoising_quality, "High")
    tree.links.new(_sock(sub.outputs, _MIX_OUT), den.inputs["Image"])
    if c.denoising_input_passes in ("RGB_ALBEDO", "RGB_ALBEDO_NORMAL"):
        # Cycles' Denoising Albedo counts emission, so the fog's light too (the black ground and the sky
        # get an albedo equal to the fog light): the picture denoised has no fog light, nor should its guide
        alb = owned.add(tree, "ShaderNodeMix", f"{role} Albedo", (x, y - 200), data_type="RGBA",
                        blend_type="SUBTRACT", clamp_result=True)
        alb.inputs[0].default_value = 1.0
        tree.links.new(rl.outputs["Denoising Albedo"], _sock(alb.inputs, _MIX_A))
        tree.links.new(fog_light, _sock(alb.inputs, _MIX_B))
        tree.links.new(_sock(alb.outputs, _MIX_OUT), den.inputs["Albedo"])
    if c.denoising_input_passes == "RGB_ALBEDO_NORMAL":
        tree.links.new(rl.outputs["Denoising Normal"], den.inputs["Normal"])
    add = owned.add(tree, "ShaderNodeMix", f"{role} Add", (x + 400, y), data_type="RGBA", blend_type="ADD")
    add.inputs[0].default_value = 1.0
    tree.links.new(den.outputs["Image"], _sock(add.inputs, _MIX_A))
    tree.links.new(fog_light, _sock(add.inputs, _MIX_B))
    return _sock(add.outputs, _MIX_OUT)


def _fog_chain(scene, tree, rl, k, fog):
    """The Compositor method's chain after Render Layers ``rl``: the ``fog`` group node, fed with the Image
    and the AOVs of the same names; returns its Image output."""
    rl.update()   # the view layer's AOVs become outputs
    node = owned.add(tree, "CompositorNodeGroup", f"Compositor {k} Fog", (rl.location.x + 300, rl.location.y - 360 * k))
    node.node_tree = fog
    for sock in node.inputs:
        if rl.outputs.get(sock.name) is not None:
            tree.links.new(rl.outputs[sock.name], sock)
    if node.outputs.get(passes.TRANSMITTANCE) is not None:   # the fog passes: written beside the render
        out = owned.add(tree, "CompositorNodeOutputFile", f"Compositor {k} Fog Passes",
                        (node.location.x + 300, node.location.y - 250), directory=passes_directory(scene),
                        file_name=passes_file_name(rl.layer))
        out.file_output_items.clear()
        for name in (passes.FOG_LIGHT, passes.TRANSMITTANCE):
            out.file_output_items.new("RGBA", name)
            tree.links.new(node.outputs[name], out.inputs[name])
    return node.outputs["Image"]


def passes_file_name(layer):
    """The fog passes' file name (without the frame's digits and extension) of the view layer ``layer``."""
    return f"{layer} {PASSES_SUFFIX}_####"


def passes_directory(scene):
    """Where the fog passes are written: the folder of the scene's render output (Output Properties), as the user
    wrote it ("//" relative to the .blend), or the .blend's folder when the output names none."""
    folder = os.path.dirname(scene.render.filepath)
    if not folder.strip("/\\"):   # "", "//" or "/"
        return folder or "//"
    return folder.rstrip("/\\") + "/"


def follow_passes_directory(scene):
    """The fog passes' File Output nodes write where the render does now (before a render, before saving)."""
    folder = passes_directory(scene)
    for node in passes_outputs(scene):
        if node.directory != folder:
            node.directory = folder


def passes_outputs(scene):
    """The Compositor method's File Output nodes of the fog passes in ``scene``'s compositor."""
    tree = scene.compositing_node_group
    return [] if tree is None else [n for n in tree.nodes if owned.is_ours(n)
                                    and n.bl_idname == "CompositorNodeOutputFile"]


def _store_passes(scene, layers, fog=None):
    """The passes the chain reads on for ``layers``: with the Compositor method's ``fog`` group the Depth
    pass if it reads it (EEVEE), else the Emission and Environment passes, and Cycles' Denoising Data passes
    if the Denoise node reads them."""
    for vl in layers:
        if fog is not None:
            names = {i.name for i in fog.interface.items_tree if i.in_out == "INPUT"}
            if DEPTH in names:
                overrides.override(vl, "use_pass_z", True)
            if EMISSION in names:   # the glowing objects' light (comp_emitters.EMITTERS)
                overrides.override(vl, "use_pass_emit", True)
            continue
        overrides.override(vl, "use_pass_emit", True)
        overrides.override(vl, "use_pass_environment", True)
        if scene.cycles.denoising_input_passes != "RGB":
            overrides.override(vl, "cycles.denoising_store_passes", True)


def setup(scene, fog=None):
    """Build the set-up on ``scene`` (see the module), the Compositor method's with its ``fog`` group;
    returns [(name, note)] if it was left out."""
    tree = scene.compositing_node_group
    chain = (lambda tree, rl, k: _fog_chain(scene, tree, rl, k, fog)) if fog is not None else (
        lambda tree, rl, k: _chain(scene, tree, rl, k))
    needs = (lambda vl: vl is not None and vl.use) if fog is not None else (lambda vl: _denoised(scene, vl))
    spliced = None   # the user's links the chain took over ([Render Layers node, node, input identifier]), if spliced
    if tree is None:
        vl = next((v for v in scene.view_layers if v.use), None)
        if not needs(vl):
            return []
        _store_passes(scene, [vl], fog)
        tree = bpy.data.node_groups.new(GROUP, "CompositorNodeTree")
        tree[owned.TAG] = "Compositor"   # the fog's own group
        tree.interface.new_socket("Image", in_out="OUTPUT", socket_type="NodeSocketColor")
        rl = owned.add(tree, "CompositorNodeRLayers", "Render Layers", (0, 0))
        rl.scene, rl.layer = scene, vl.name
        out = owned.add(tree, "NodeGroupOutput", "Group Output", (1000, 0))
        tree.links.new(chain(tree, rl, 0), out.inputs["Image"])
        scene.compositing_node_group = tree
        overrides.override(scene, "render.use_compositing", True)
    else:
        nodes = [n for n in tree.nodes if _renders(scene, n) and n.outputs["Image"].is_linked
                 and needs(_layer(scene, n))]
        if not nodes:
            return []   # the compositor does not read the (denoised) picture
        why = _why_not(scene, tree, nodes, fog)
        if why and fog is not None:
            return [(scene.name, f"{why}: the compositor is left as it is, so the fog's light, which the "
                                 "Compositor method adds there, is missing (use the Node Groups method)")]
        if why:
            return [(scene.name, f"{why}: the compositor is left as it is and Cycles' denoiser on, which "
                                 "smears the fog's glows (turn it off, or see README 'Fog passes')")]
        _store_passes(scene, {_layer(scene, n) for n in nodes}, fog)
        spliced = []
        for k, rl in enumerate(nodes):
            users = [link.to_socket for link in rl.outputs["Image"].links]
            spliced += [[rl.name, sock.node.name, sock.identifier] for sock in users]
            last = chain(tree, rl, k)
            for sock in users:
                tree.links.new(last, sock)
    if fog is None:
        overrides.override(scene, "cycles.use_denoising", False)
    state = {"tree": tree.name, "fog": fog is not None, "engine": scene.render.engine}
    if spliced is not None:   # (a tree of the user's)
        state[LINKS] = json.dumps(spliced)
    scene[STATE] = state
    return []


def teardown_denoiser(scene):
    """Take the denoiser's set-up off ``scene`` (the Compositor method's chain stays: it adds the fog)."""
    if is_set_up(scene) and not scene[STATE].get("fog"):
        teardown(scene)


def teardown(scene):
    """Take the set-up off ``scene``: the fog's compositor nodes (or group) go, the settings come back."""
    state = scene.get(STATE)
    if state is None:
        return
    trees = [t for t in (scene.compositing_node_group, bpy.data.node_groups.get(state.get("tree", "")))
             if t is not None and t.bl_idname == "CompositorNodeTree" and not owned.read_only(t)]
    for tree in dict.fromkeys(trees):   # the one the scene uses now, and the one set up (renamed: found anyway)
        if tree.get(owned.TAG) is not None:   # the fog's own group
            if scene.compositing_node_group == tree:
                scene.compositing_node_group = None
            if tree.users == 0:
                bpy.data.node_groups.remove(tree)
        elif any(owned.is_ours(n) for n in tree.nodes) or state.get(LINKS):
            _unsplice(tree, json.loads(state.get(LINKS) or "[]"))
    del scene[STATE]
    overrides.restore(scene)
    for vl in scene.view_layers:
        overrides.restore(vl)


def _unsplice(tree, spliced=()):
    """Delete the fog's nodes from the user's ``tree``, linking each Render Layers Image back to where
    the chain fed: the links ``spliced`` recorded ([Render Layers node, node, input identifier], ``setup``),
    so that a chain cut since (a group node whose links Blender dropped, a node deleted) still gives the
    user's links back, and those the chain's nodes still show (set-ups recorded before ``LINKS``).  An input
    the user has linked to something else of theirs since is left as it is."""
    back = [tuple(entry[:1]) + ("Image",) + tuple(entry[1:]) for entry in spliced]
    for link in tree.links:
        if owned.is_ours(link.from_node) and not owned.is_ours(link.to_node):
            role = owned.role_of(link.from_node).rsplit(" ", 1)[0]   # "Compositor k"
            src = next((l.from_socket for l in tree.links if owned.is_ours(l.to_node)
                        and owned.role_of(l.to_node).rsplit(" ", 1)[0] == role
                        and not owned.is_ours(l.from_node) and l.from_socket.identifier == "Image"), None)
            if src is not None:
                back.append((src.node.name, src.identifier, link.to_node.name, link.to_socket.identifier))
    owned.remove_ours(tree)
    for from_node, from_id, to_node, to_id in dict.fromkeys(back):
        src, dst = tree.nodes.get(from_node), tree.nodes.get(to_node)
        if src is None or dst is None or owned.is_ours(src) or owned.is_ours(dst):
            continue
        to_sock = next((s for s in dst.inputs if s.identifier == to_id), None)
        from_sock = next((s for s in src.outputs if s.identifier == from_id), None)
        if to_sock is None or from_sock is None or (to_sock.is_linked and not to_sock.is_multi_input):
            continue
        tree.links.new(from_sock, to_sock)
