"""Shader node groups of the fog: ``precompute/shading.py`` built as nodes via ``NodeOps``.

One shared copy of each group per .blend:

* ``AnalyticFog Params``: the fog's settings (density beta per scene unit, albedo colour).
* ``AnalyticFog Light [models]``: ``shading.shade_point`` — one light seen
  from a surface point (airlight along the camera ray, fog light scattered
  onto the surface, direct-light attenuation) with the rungs ``models``
  (``rungs.LightModels``), instanced once per light that uses those models.
* ``AnalyticFog Background Light [model]``: ``shading.background_point`` —
  one light's airlight on a ray that meets no surface (the World).

  A rung that runs only in OSL becomes a Script node (``osl.py``, Cycles only).
* ``AnalyticFog Surface`` / ``AnalyticFog World``: ``shading.shade_surface`` /
  ``shade_background`` over the scene's fog lights, their positions and
  intensities fed by drivers (no Python expression, so they evaluate with
  auto-run off and without the add-on).  Rebuilding these two when lights or
  their models change leaves every material untouched.

Each group records the fingerprint of the code that built it
(``BUILT``, from the source of the kernels, the shading and the builders): a
saved file made by other code rebuilds it.
"""
import math
import sys

import bpy

from ..precompute import fingerprint, model, ops, predict, rungs, shading, surface, tables
from ..precompute.medium import Medium
from . import osl, passes, sockets
from .sockets import NodeOps

PARAMS = "AnalyticFog Params"
LIGHT = "AnalyticFog Light"
BACKGROUND_LIGHT = "AnalyticFog Background Light"
SURFACE = "AnalyticFog Surface"
WORLD = "AnalyticFog World"

FOG_PROP = "analytic_fog"   # custom-property key marking data the fog made or changed
BUILDING = " (building)"     # name suffix of a group being built beside the one in use
BUILT = "analytic_fog_built"   # on the per-light groups: the fingerprint of the code they were built by


def code_fingerprint():
    """Fingerprint of everything that decides a group's content (kernels, tables, shading, builders)."""
    return fingerprint.source_fingerprint(model, surface, tables, shading, rungs, ops, sockets, osl, passes,
                                          sys.modules[__name__])


def light_group_name(models):
    """Name of the per-light surface group for ``models`` (rungs.LightModels)."""
    return f"{LIGHT} [{models.airlight.name}, {models.scatter.name}, {models.direct.name}]"


def background_group_name(models):
    return f"{BACKGROUND_LIGHT} [{models.background.name}]"


def all_group_names():
    """Every group name the fog can make (for Remove and for merging appended copies)."""
    names = [PARAMS, SURFACE, WORLD]
    for pref in rungs.PREFERENCES:
        models = rungs.choose(pref)
        names += [light_group_name(models), background_group_name(models)]
    return list(dict.fromkeys(names))


def _new_group(name, inputs, outputs):
    """An empty shader group for ``name`` with the given (name, socket type) interface.

    An unused group of that name is emptied and reused; one in use is left
    alone and a new group is built beside it, for ``_install`` to swap in:
    every node added to a group that 1 000 materials use costs ~50 ms, to a
    fresh one almost nothing.
    """
    ng = bpy.data.node_groups.get(name)
    if ng is None or ng.users:
        ng = bpy.data.node_groups.new(name + BUILDING, "ShaderNodeTree")
    ng.animation_data_clear()
    ng.nodes.clear()
    want = [(n, t, "INPUT") for n, t in inputs] + [(n, t, "OUTPUT") for n, t in outputs]
    have = sorted(((i.name, i.socket_type, i.in_out) for i in ng.interface.items_tree if i.item_type == "SOCKET"),
                  key=lambda s: s[2])   # Blender lists outputs first; a stable sort puts them after the inputs
    if have != want:
        ng.interface.clear()
        for n, t, io in want:
            ng.interface.new_socket(n, in_out=io, socket_type=t)
    ng[FOG_PROP] = True
    ng.pop(BUILT, None)
    gin = ng.nodes.new("NodeGroupInput")
    gout = ng.nodes.new("NodeGroupOutput")
    gin.location = (-300, 0)
    gout.location = (4000, 0)
    return ng, gin, gout


def _install(ng, name):
    """Put a group built by ``_new_group`` in place of the old ``name``: its users are remapped to it."""
    if ng.name == name:
        return ng
    old = bpy.data.node_groups.get(name)
    if old is not None:
        old.user_remap(ng)
        bpy.data.node_groups.remove(old)
    ng.name = name
    return ng


F, V, C = "NodeSocketFloat", "NodeSocketVector", "NodeSocketColor"

# EEVEE keeps a material's node constants, its inlined groups' included, in one uniform block of at most
# 64 KiB; beyond it the material fails to link ("Uniform block node_tree too big (78832/65536)") and
# renders EEVEE's fallback.  What one light's group costs there, by ladder step (rungs.STEPS), from the
# overflow messages of tests/scenes/many_lights.py in EEVEE (bpy 5.0.1): full 4 610 bytes (16 lights:
# 74 032), glow only 2 517 (36: 90 880), off at most 334 (196 lights fit); the World 936 per light whose
# glow is on (256 lights: 239 728).  About 10 bytes per node: a group's constants become uniforms of
# every instance (1 000 Multiply-by-a-constant nodes in a group used 20 times: 240 032 bytes), and
# linking them from shared Value nodes in the group changed nothing.  (Before the lighter table lookup
# of ``sockets.NodeOps.table``: 4 910 and 2 649.)
EEVEE_ENGINE = "BLENDER_EEVEE"
EEVEE_UNIFORM_LIMIT = 65536
EEVEE_UNIFORM_RESERVE = 8192    # the material's own nodes and the Surface group's shared ones (272 measured
                                # for a bare Principled BSDF)
EEVEE_MATERIAL_BYTES = (4610, 2517, 334)
EEVEE_WORLD_BYTES = (936, 936, 0)


def eevee_budget():
    """What a fogged material and the World can hold in EEVEE (predict.Budget over the lights' steps)."""
    room = EEVEE_UNIFORM_LIMIT - EEVEE_UNIFORM_RESERVE
    return predict.Budget((EEVEE_MATERIAL_BYTES, EEVEE_WORLD_BYTES), (room, room),
                          "EEVEE's uniform block (64 KiB of node constants per material)")


def build_params(beta, albedo):
    ng, gin, gout = _new_group(PARAMS, [], [("Beta", F), ("Albedo", C)])
    b = ng.nodes.new("ShaderNodeValue")
    b.name = b.label = "Beta"
    b.outputs[0].default_value = beta
    a = ng.nodes.new("ShaderNodeRGB")
    a.name = a.label = "Albedo"
    a.outputs[0].default_value = (*albedo, 1.0)
    ng.links.new(b.outputs[0], gout.inputs["Beta"])
    ng.links.new(a.outputs[0], gout.inputs["Albedo"])
    return _install(ng, PARAMS)


def get_beta():
    """The fog's density per scene unit in the params group (1/unit), 0 if there is none."""
    ng = bpy.data.node_groups.get(PARAMS)
    return float(ng.nodes["Beta"].outputs[0].default_value) if ng is not None else 0.0


def set_params(beta, albedo):
    """Write the fog's settings into the shared params group (creating it if needed)."""
    ng = bpy.data.node_groups.get(PARAMS)
    if ng is None:
        return build_params(beta, albedo)
    ng.nodes["Beta"].outputs[0].default_value = beta
    ng.nodes["Albedo"].outputs[0].default_value = (*albedo, 1.0)
    return ng


def _up_to_date(name):
    """The group ``name`` if this code built it and its tables are all there (rebuilding costs seconds)."""
    ng = bpy.data.node_groups.get(name)
    if ng is None or ng.get(BUILT) != code_fingerprint():
        return None
    return ng if all(n.image is not None for n in ng.nodes if n.bl_idname == "ShaderNodeTexImage") else None


def _medium(m, beta, albedo=None):
    """The Medium of a group's sockets (the per-light groups need only beta)."""
    return Medium(m.wrap(beta)) if albedo is None else Medium(m.wrap(beta), m.wrap(albedo, vector=True))


def build_light(models, images):
    """Per-light surface group: ``shading.shade_point`` (Sun et al. 2005 Eq. 11, 14, 17-18) with ``models``."""
    name = light_group_name(models)
    if (ng := _up_to_date(name)) is not None:
        return ng
    ng, gin, gout = _new_group(name, [
        ("Beta", F), ("Light", V), ("Intensity", C), ("Position", V), ("Incoming", V),
        ("View Distance", F), ("Normal", V), ("Diffuse", C), ("Specular", C), ("Glossy Level", F),
    ], [("Airlight", C), ("Scattered", C), ("Attenuation", F), ("Weight", F)])
    m = NodeOps(ng, images)
    g = {s.name: m.wrap(s, vector=s.type in ("VECTOR", "RGBA")) for s in gin.outputs if s.name}
    pos, incoming, d_vp = g["Position"], g["Incoming"], g["View Distance"]
    geo = shading.Geometry(pos + incoming * d_vp, pos, incoming, d_vp, g["Normal"])
    material = shading.Material(g["Diffuse"], g["Specular"], g["Glossy Level"])
    light = shading.Light(g["Light"], g["Intensity"])
    terms = shading.shade_point(m, geo, material, light, _medium(m, g["Beta"]), models)
    for key, v in terms._asdict().items():
        m.feed(gout.inputs[key.title()], v)
    ng[BUILT] = code_fingerprint()
    return _install(ng, name)


def build_background_light(models, images):
    """Per-light world group: ``shading.background_point`` (Sun et al. 2005 Eq. 12) with ``models``."""
    name = background_group_name(models)
    if (ng := _up_to_date(name)) is not None:
        return ng
    ng, gin, gout = _new_group(name, [
        ("Beta", F), ("Light", V), ("Intensity", C), ("Camera", V), ("Direction", V),
    ], [("Airlight", C)])
    m = NodeOps(ng, images)
    g = {s.name: m.wrap(s, vector=s.type in ("VECTOR", "RGBA")) for s in gin.outputs if s.name}
    air = shading.background_point(m, g["Camera"], g["Direction"], shading.Light(g["Light"], g["Intensity"]),
                                   _medium(m, g["Beta"]), models)
    m.feed(gout.inputs["Airlight"], air)
    ng[BUILT] = code_fingerprint()
    return _install(ng, name)


# --- scene-level sums over the fog lights -------------------------------------------

def _drive_location(node, obj):
    """Inputs 0-2 of ``node`` follow ``obj``'s world location (TRANSFORMS drivers)."""
    for i, axis in enumerate("XYZ"):
        sock = node.inputs[i]
        sock.driver_remove("default_value")
        d = sock.driver_add("default_value").driver
        d.type = "SUM"
        var = d.variables.new()
        var.type = "TRANSFORMS"
        t = var.targets[0]
        t.id = obj
        t.transform_type = f"LOC_{axis}"
        t.transform_space = "WORLD_SPACE"


def _drive_intensity(node, light_data):
    """Inputs 0-2 of ``node`` = radiant intensity P * colour / (4 pi) in W/sr (simple-expression drivers)."""
    for i in range(3):
        sock = node.inputs[i]
        sock.driver_remove("default_value")
        d = sock.driver_add("default_value").driver
        d.type = "SCRIPTED"
        for name, path in (("p", "energy"), ("c", f"color[{i}]")):
            var = d.variables.new()
            var.name = name
            var.type = "SINGLE_PROP"
            var.targets[0].id_type = "LIGHT"
            var.targets[0].id = light_data
            var.targets[0].data_path = path
        d.expression = f"p * c * {1.0 / (4.0 * math.pi)!r}"


def _driven_vector(ng, name, x, y):
    n = ng.nodes.new("ShaderNodeCombineXYZ")
    n.name = n.label = name
    n.location = (x, y)
    return n


def _light_instance(ng, k, light, group_name, inputs):
    """Instance ``group_name`` for the ``k``-th light, its Light and Intensity inputs driven by ``light``.

    ``inputs``: (output socket, input name) pairs for the other inputs.
    Returns the group node.
    """
    loc = _driven_vector(ng, f"Light {k} Location", -600, -300 * k)
    _drive_location(loc, light)
    inten = _driven_vector(ng, f"Light {k} Intensity", -600, -300 * k - 120)
    _drive_intensity(inten, light.data)
    node = ng.nodes.new("ShaderNodeGroup")
    node.node_tree = bpy.data.node_groups[group_name]
    node.name = node.label = f"Light {k}: {light.name}"
    node.location = (-300, -300 * k)
    for a, b in ((loc.outputs[0], "Light"), (inten.outputs[0], "Intensity"), *inputs):
        ng.links.new(a, node.inputs[b])
    return node


def build_surface(lights, models, images, with_passes=False):
    """Scene group for materials: ``shading.shade_surface`` (Sun et al. 2005 Eq. 19) over ``lights``.

    ``models``: one rungs.LightModels per light.  Inputs mirror the Principled
    BSDF; outputs are the fields of ``shading.SurfaceFog``: Fog, the fog's
    light as a shader (one Emission closure per light, times the Opacity
    input), and Emission, the same as one colour (camera rays only),
    Transmittance e^{-beta D_vp} to scale the material, Direct Attenuation
    (EEVEE's stand-in for the per-light e^{-beta D_sp}) and per engine the
    Mix Factor 1 - scale of the user's shader.  ``with_passes``: it writes the
    fog passes (``passes.py``), weighted by the Opacity input (white: opaque).

    Why closures: Cycles' SVM emits a shader's value nodes in the order of
    their ids, so one colour summed over the lights keeps every light's values
    on its stack of 255 floats at once (out of SVM stack space, every fogged
    material black, at 4 lights), while each closure's inputs are compiled
    and released before the next closure's.
    """
    ng, gin, gout = _new_group(SURFACE, [
        ("Base Color", C), ("Metallic", F), ("Roughness", F), ("Specular IOR Level", F), (passes.OPACITY, C),
    ], [("Fog", "NodeSocketShader"), ("Emission", C), ("Transmittance", F), ("Direct Attenuation", F),
        ("Cycles Mix Factor", F), ("EEVEE Mix Factor", F)])
    next(i for i in ng.interface.items_tree if i.name == passes.OPACITY).default_value = (1.0, 1.0, 1.0, 1.0)
    m = NodeOps(ng, {})
    params = ng.nodes.new("ShaderNodeGroup")
    params.node_tree = bpy.data.node_groups[PARAMS]
    geo = ng.nodes.new("ShaderNodeNewGeometry")
    cam = ng.nodes.new("ShaderNodeCameraData")
    path = ng.nodes.new("ShaderNodeLightPath")
    g = {s.name: s for s in gin.outputs if s.name}
    diffuse, specular, level = surface.principled_to_phong(
        m, m.wrap(g["Base Color"], vector=True), m.wrap(g["Metallic"]), m.wrap(g["Roughness"]),
        m.wrap(g["Specular IOR Level"]))
    terms = []
    for k, (light, mod) in enumerate(zip(lights, models)):
        node = _light_instance(ng, k, light, build_light(mod, images).name, (
            (params.outputs["Beta"], "Beta"), (geo.outputs["Position"], "Position"), (geo.outputs["Incoming"], "Incoming"),
            (cam.outputs["View Distance"], "View Distance"), (geo.outputs["Normal"], "Normal"),
            (diffuse.sock, "Diffuse"), (specular.sock, "Specular"), (level.sock, "Glossy Level")))
        terms.append(shading.LightTerms(*(m.wrap(node.outputs[f], vector=node.outputs[f].type != "VALUE")
                                          for f in ("Airlight", "Scattered", "Attenuation", "Weight"))))
    fog = shading.shade_surface(m, terms, _medium(m, params.outputs["Beta"], params.outputs["Albedo"]),
                                m.wrap(cam.outputs["View Distance"]), m.wrap(path.outputs["Is Camera Ray"]))
    opacity = m.wrap(g[passes.OPACITY], vector=True)
    _closure_sum(m, gout.inputs["Fog"], "ShaderNodeEmission", [m.wrap(e, vector=True) * opacity
                                                                for e, mod in zip(fog.emissions, models) if _lit(mod)])
    for sock, v in (("Emission", fog.emission), ("Transmittance", fog.transmittance),
                    ("Direct Attenuation", fog.direct_attenuation), ("Cycles Mix Factor", fog.cycles_mix),
                    ("EEVEE Mix Factor", fog.eevee_mix)):
        m.feed(gout.inputs[sock], m.wrap(v))
    if with_passes:
        passes.write_group(m, ng, _chained_closure_sum(m, gout.inputs["Fog"]), m.wrap(fog.transmittance), opacity,
                           light_weighted=True)
    else:
        _camera_rays_only(ng, gout.inputs["Fog"], path.outputs["Is Camera Ray"])
    return _install(ng, SURFACE)


def _camera_rays_only(ng, sock, is_camera):
    """Put the shader linked into ``sock`` behind a Mix Shader whose factor is Is Camera Ray.

    The fog's light is added on camera rays only (``shading.shade_surface``); on every other ray the
    Mix Shader's factor is exactly 0 and Cycles' SVM jumps over the nodes that feed only its second
    input (svm.cpp, NODE_JUMP_IF_ZERO): bounce rays hitting fogged surfaces then skip every light's
    glow and scattered fog light (boulevard, 45 lamps, 160x90, 4 spp: 270 -> 132 us of render CPU
    per sample).  Not with the Fog Passes: an AOV reads those nodes too, so SVM runs them on every
    ray anyway, and the Mix would undo the compile order that keeps the passes' sums off SVM's stack
    (``_chained_closure_sum``: 24 lights overflowed with it).
    """
    if not sock.is_linked:
        return
    src = sock.links[0].from_socket
    mix = ng.nodes.new("ShaderNodeMixShader")
    mix.name = mix.label = "Camera Rays Only"
    mix.location = (sock.node.location.x - 200, sock.node.location.y)
    ng.links.new(is_camera, mix.inputs[0])
    ng.links.new(src, mix.inputs[2])
    ng.links.new(mix.outputs[0], sock)


def _exact_zero(m, v):
    """(0, 0, 0) computed from the vector ``v``: max(min(v, 0), 0), exactly 0 for any v (NaN too), which
    neither Blender's inlining nor Cycles' constant folding removes.  A data dependency on ``v`` only."""
    black = (0.0, 0.0, 0.0)
    return m.vmath("MAXIMUM", m.vmath("MINIMUM", v, black), black)


def _chained_closure_sum(m, sock):
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
    compiles them (each Add Shader's first input first).
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
    total = None
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


def _lit(models):
    """False for a light whose every fog term is off (``rungs.STEPS`` "off"): it adds no fog light."""
    return models.airlight is not rungs.AIRLIGHT_OFF or models.scatter is not rungs.SCATTER_OFF


def _closure_sum(m, sock, bl_idname, colours):
    """Link into ``sock`` the sum of one ``bl_idname`` closure (Emission, Background) per colour.

    The Add Shader nodes form a balanced (pairwise) tree, depth ceil(log2 N), not a chain: Cycles' OSL
    flattens a shader's closure tree with a fixed 16-entry stack (``flatten_closure_tree``,
    intern/cycles/kernel/osl/osl.h), one entry per Add whose first input it is still walking, and
    silently drops whatever lies below once the stack is full.  A left-deep chain of N - 1 Adds kept
    the last 16 closures only (tests/scenes/closure_sum_probe.py): 25 lights rendered 25 % of the
    twin, 64 lights 2-7 %, no error in the log.  The leaves keep their order (light 0 first), which
    is the order SVM compiles them in, so SVM's stack use is the chain's (one light's values at a time).
    """
    ng = m.tree
    level = []                                  # [(output socket, y)] of the tree's current level
    for k, colour in enumerate(colours):
        node = ng.nodes.new(bl_idname)
        node.name = node.label = f"Light {k} Fog"
        node.location = (3600, -300 * k)
        m.feed(node.inputs["Color"], colour)
        level.append((node.outputs[0], -300.0 * k))
    depth = 0
    while len(level) > 1:
        depth += 1
        pairs = []
        for (a, ya), (b, yb) in zip(level[0::2], level[1::2]):
            add = ng.nodes.new("ShaderNodeAddShader")
            add.location = (3600 + 200 * depth, 0.5 * (ya + yb))
            ng.links.new(a, add.inputs[0])
            ng.links.new(b, add.inputs[1])
            pairs.append((add.outputs[0], 0.5 * (ya + yb)))
        level = pairs + level[len(pairs) * 2:]  # an odd one out goes up a level as it is
    if level:
        ng.links.new(level[0][0], sock)


def build_world(lights, models, camera, images, with_passes=False):
    """Scene group for the World: ``shading.shade_background`` (Sun et al. 2005 Eq. 12) over ``lights``.

    Camera position by TRANSFORMS drivers on ``camera`` (no node gives it in a
    world shader).  The background itself is seen through infinite fog:
    Transmittance is 0 on camera rays (1 on other rays, which keep the
    world's lighting).
    """
    ng, gin, gout = _new_group(WORLD, [], [("Fog", "NodeSocketShader"), ("Emission", C), ("Transmittance", F)])
    m = NodeOps(ng, {})
    params = ng.nodes.new("ShaderNodeGroup")
    params.node_tree = bpy.data.node_groups[PARAMS]
    geo = ng.nodes.new("ShaderNodeNewGeometry")
    path = ng.nodes.new("ShaderNodeLightPath")
    cam = _driven_vector(ng, "Camera Location", -600, 300)
    if camera is not None:
        _drive_location(cam, camera)
    direction = m.vmath("NORMALIZE", m.wrap(geo.outputs["Position"]))
    airlights, nodes = [], []
    for k, (light, mod) in enumerate(zip(lights, models)):
        if mod.background is rungs.BACKGROUND_OFF:
            continue
        node = _light_instance(ng, k, light, build_background_light(mod, images).name, (
            (params.outputs["Beta"], "Beta"), (cam.outputs[0], "Camera"), (direction.sock, "Direction")))
        nodes.append(node)
        airlights.append(m.wrap(node.outputs["Airlight"], vector=True))
    medium = _medium(m, params.outputs["Beta"], params.outputs["Albedo"])
    is_camera = m.wrap(path.outputs["Is Camera Ray"])
    emission, transmittance = shading.shade_background(m, airlights, medium, is_camera)
    m.feed(gout.inputs["Emission"], m.wrap(emission))
    _closure_sum(m, gout.inputs["Fog"], "ShaderNodeBackground",   # see build_surface for why closures
                 [m.wrap(shading.shade_background(m, [a], medium, is_camera)[0], vector=True) for a in airlights])
    m.feed(gout.inputs["Transmittance"], m.wrap(transmittance))
    if with_passes:
        _write_world_passes(m, ng, geo, nodes, medium, is_camera, transmittance)
    return _install(ng, WORLD)


def _write_world_passes(m, ng, geo, nodes, medium, is_camera, transmittance):
    """The World's fog passes (``passes.py``) from its own instances of the lights' groups ``nodes``."""
    # The fog passes.  Cycles runs whatever an AOV output reads on every evaluation of the shader
    # (svm.cpp counts AOV dependencies as shared by both sides of a Mix Shader), which would undo the
    # World's 0/1 mix: its importance map and every non-camera ray would run the fog (48x27, automatic
    # map: 1.1 s -> 7.5 s per render).  So the Fog Light pass reads a second instance of each light's
    # group, given the same direction another way (-Incoming): Cycles does not merge it with the first
    # (node deduplication) and runs it on camera rays only (after NODE_AOV_START).
    #   Cycles compiles all of the AOV outputs' nodes in one go, a sweep over them in the order of their
    # ids, a node as soon as its inputs are done.  Each table tap reads its coordinates through a
    # conversion node (vector to point, a no-op) that Cycles adds after every other node, so one sweep ran
    # every light's nodes up to its taps and kept their values (15 floats a light) on SVM's stack of 255:
    # out of SVM stack space and the whole sky black from 17 lights on.  So light k's instance reads the
    # direction plus an exact zero made from the running sum of lights 0..k-1 (``_exact_zero``): it
    # starts once the light before it is summed, and one light's values are kept at a time (the
    # World's peak: 33 floats at 4 to 64 lights, 71 at 4 before).
    aov_direction = m.vmath("NORMALIZE", m.vmath("SCALE", m.wrap(geo.outputs["Incoming"]), -1.0))
    total = None
    for k, node in enumerate(nodes):
        twin = ng.nodes.new("ShaderNodeGroup")
        twin.node_tree = node.node_tree
        twin.name = twin.label = f"{node.name} (passes)"
        twin.location = (-300, -300 * k - 150)
        direction = aov_direction if total is None else m.vmath("ADD", aov_direction, _exact_zero(m, total))
        for sock in node.inputs:
            src = direction.sock if sock.name == "Direction" else (sock.links[0].from_socket if sock.is_linked
                                                                     else None)
            if src is not None:
                ng.links.new(src, twin.inputs[sock.name])
        airlight = m.wrap(twin.outputs["Airlight"], vector=True)
        total = airlight if total is None else total + airlight
    light, _ = shading.shade_background(m, [] if total is None else [total], medium, is_camera)
    passes.write_group(m, ng, m.wrap(light, vector=True), m.wrap(transmittance))
