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
(``owned.BUILT``, ``code_fingerprint``: all of the add-on's source): a
saved file made by other code rebuilds it.
"""
import functools
import re

import bpy

from ..precompute import area, fingerprint, model, predict, rungs, shading, sunlight, surface
from ..precompute.medium import Medium
from . import owned, passes, sockets
from .sockets import NodeOps

PARAMS = "AnalyticFog Params"
LIGHT = "AnalyticFog Light"
BACKGROUND_LIGHT = "AnalyticFog Background Light"
SURFACE = "AnalyticFog Surface"
WORLD = "AnalyticFog World"
SURFACE_LIGHTS = SURFACE + " Lights"   # bundles: "AnalyticFog Surface Lights 1-8", ... (``_bundles``)
WORLD_LIGHTS = WORLD + " Lights"
SURFACE_TAILS = SURFACE + " Tails"     # bundles of the glows past glass and mirrors (``build_tail_bundle``)
BUNDLE = 8   # lights per bundle group (``_bundles``)
_BUNDLE_NAME = re.compile(
    rf"^({re.escape(SURFACE_LIGHTS)}|{re.escape(WORLD_LIGHTS)}|{re.escape(SURFACE_TAILS)}) \d+-\d+$")

FOG_PROP = "analytic_fog"   # custom-property key marking data the fog made or changed
BUILDING = " (building)"     # name suffix of a group being built beside the one in use


def code_fingerprint():
    """Fingerprint of the code that decides a group's content: all of the add-on's source
    (``fingerprint.package_fingerprint``: no list of modules to keep)."""
    return fingerprint.package_fingerprint()


def light_group_name(models):
    """Name of the per-light surface group for ``models`` (rungs.LightModels)."""
    return f"{LIGHT} [{models.airlight.name}, {models.scatter.name}, {models.direct.name}]"


def background_group_name(models):
    return f"{BACKGROUND_LIGHT} [{models.background.name}]"


def all_group_names():
    """Every group name the fog can make (for Remove and for merging appended copies): the light bundles
    this file has (their names without a ``.NNN`` suffix) first, as they use the per-light groups (so
    deleting unused groups in this order leaves none behind), then the fixed ones."""
    names = sorted(base for ng in bpy.data.node_groups
                   if _BUNDLE_NAME.match(base := owned.base_name(ng.name)))
    names += [PARAMS, SURFACE, WORLD]
    for pref in rungs.PREFERENCES:
        for spot in (False, True):
            models = rungs.choose(pref, spot=spot)
            names += [light_group_name(models), background_group_name(models)]
    names += sorted(base for ng in bpy.data.node_groups if ng.get(FOG_PROP)   # another anisotropy's
                    and (base := owned.base_name(ng.name)).startswith((f"{LIGHT} [", f"{BACKGROUND_LIGHT} [")))
    # the kernels' shared groups (sockets.NodeOps.group), last: the light groups use them, and the larger
    # kernels the smaller ones (deleted in the order of their size)
    kernels = [ng for ng in bpy.data.node_groups if ng.get(FOG_PROP) and ng.name.startswith(sockets.KERNEL_GROUP)]
    names += [owned.base_name(ng.name) for ng in sorted(kernels, key=lambda ng: -_kernel_depth(ng))]
    return list(dict.fromkeys(names))


def _kernel_depth(ng):
    """How deep ``ng``'s group nodes nest (0: none): a group is deleted before those it uses."""
    return max((1 + _kernel_depth(n.node_tree) for n in ng.nodes
                if n.bl_idname in ("ShaderNodeGroup", "CompositorNodeGroup") and n.node_tree is not None), default=0)


def _new_group(name, inputs, outputs, tree_type="ShaderNodeTree"):
    """An empty shader group (or ``tree_type``'s) for ``name`` with the given (name, socket type) interface.

    An unused group of that name is emptied and reused; one in use is left
    alone and a new group is built beside it, for ``_install`` to swap in:
    every node added to a group that 1 000 materials use costs ~50 ms, to a
    fresh one almost nothing.
    """
    ng = bpy.data.node_groups.get(name)
    if ng is None or ng.users:
        ng = bpy.data.node_groups.new(name + BUILDING, tree_type)
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
    ng.pop(owned.BUILT, None)
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
# renders EEVEE's fallback.  Every unlinked float, vector or colour input is such a constant, the inputs
# a node's operation leaves unused too, and a group's constants are uniforms of every instance (1 000
# Multiply-by-a-constant nodes in a group used 20 times: 240 032 bytes).  The fog's math nodes mark
# theirs as constants to compile in (``sockets.NodeOps.inline``), but Blender does not save that mark:
# a saved file, as a farm renders it, has them all again.  So the budget counts what a light's group
# costs in a saved and reopened file, by ladder step (rungs.STEPS), from the overflow messages of the
# many-lights scene in EEVEE (bpy 5.0.1, at 709fad8): full 2 848 bytes (24 and 36 lights: 68 656,
# 102 832), glow only 1 812 (40, 48, 72 lights: 72 784, 87 280, 130 768), off at most 334 (196 lights
# fit, measured before the tables' identity mapping, which off does not use); the World at most 936
# per light whose glow is on (256 lights: 239 728, before that mapping).  As built (until the file is
# reopened) a light costs 112 / 80 / 16 bytes and the World 48.  (Before the tables' identity mapping
# of ``sockets.NodeOps._tap``: 4 610 and 2 517; before the lighter table lookup: 4 910 and 2 649.)
EEVEE_ENGINE = "BLENDER_EEVEE"
EEVEE_UNIFORM_LIMIT = 65536
EEVEE_UNIFORM_RESERVE = 8192    # the material's own nodes and the Surface group's shared ones (272 measured
                                # for a bare Principled BSDF)
EEVEE_MATERIAL_BYTES = (2848, 1812, 334, 0)   # by rungs.STEPS (LEFT_OUT: not in the groups)
EEVEE_WORLD_BYTES = (936, 936, 0, 0)
# Anisotropic fog (g != 0) adds the phase weight's constants to every glow (model.hg_weight: 8 per
# segment, 1 per background tail).  Measured, saved and reopened, 36 lights fully modelled: 103 552 bytes
# at g = 0, 129 184 at g = 0.85: 712 more per full light.  Glow only keeps the same glow: taken as the
# same 712; the World's background (1 of the 8 weights, and the rows' mapping) taken as 150: estimates.
EEVEE_ANISOTROPIC_EXTRA = ((712, 712, 0, 0), (150, 150, 0, 0))


# Cycles' OSL: every node of a material becomes a layer of its OSL shader group, and liboslexec indexes
# the layers with a signed 16-bit integer: a 256-light material (53 195 nodes) crashed (SIGSEGV) while OSL
# optimised its groups (the index read as -32 763; no stack or memory exhaustion: helper's core dump, this
# stop).  Nodes a light adds to a material, inlined (counted at 16 lights; Cycles' own simplification only
# removes some): 248 full, 63 glow only, 59 off; the World 15 with the glow on.
OSL_LAYER_LIMIT = 32767
OSL_LAYER_RESERVE = 2767   # the material's own nodes and the Surface group's shared ones (48 with no light)
OSL_MATERIAL_LAYERS = (248, 63, 59, 0)
OSL_WORLD_LAYERS = (15, 15, 0, 0)


# A spot light (rungs.spot_rungs) costs more: its glow kernel (spot.py: two cone intervals, the inner segment
# and two rims of quadrature) in the material and the World, and its scatter's tables (spot.scatter: F, the
# moments, the lobe response, read once for both lobes).  Measured at bpy 5.0.1 (helper, at 99dbfcf), g = 0.85,
# files saved and reopened.  OSL, nodes a light adds with the OSL method (8 vs 4 lights): full 924 a spot
# against 249 a point, glow only 222 against 64, off 92 against 60; the World 149 against 16.  EEVEE (overflow
# messages): a fully modelled spot 13 276 bytes in a material (8 and 12 spots: 107 008, 160 112), a spot with
# its glow only 9 836 (12 and 16: 118 832, 158 176), a point 3 348 (24 and 32 points: 80 656, 107 440); the
# World 8 940 a spot (8, 12, 16: 71 632, 107 392, 143 152), 652 a point.  The extras over the budgeted point
# (EEVEE_MATERIAL_BYTES plus EEVEE_ANISOTROPIC_EXTRA) with a 3 % margin; off keeps the cone's factor (a few
# constants, estimated).
OSL_SPOT_EXTRA = ((700, 170, 40, 0), (140, 140, 0, 0))
EEVEE_SPOT_EXTRA = ((10010, 7540, 100, 0), (8960, 8960, 0, 0))


def _per_light(costs, extra, spots):
    """(K, N, STEPS) costs of lights ``spots`` (True for a spot) from the point light's ``costs`` (K, STEPS)
    and a spot's ``extra``; the (K, STEPS) costs themselves when no light is a spot."""
    if not any(spots):
        return costs
    return tuple(tuple(tuple(c + (e if spot else 0) for c, e in zip(cost, more)) for spot in spots)
                 for cost, more in zip(costs, extra))


def material_nodes(steps, spots):
    """About how many nodes the fog's lights add to each fogged material, inlined (OSL_MATERIAL_LAYERS and
    OSL_SPOT_EXTRA: Cycles' SVM sets up the same graph as OSL); ``steps``: each light's (rungs.STEPS),
    ``spots``: True for a spot."""
    return sum(OSL_MATERIAL_LAYERS[k] + (OSL_SPOT_EXTRA[0][k] if spot else 0) for k, spot in zip(steps, spots))


def osl_budget(spots=()):
    """What a fogged material and the World can hold as one OSL shader group (predict.Budget); ``spots``:
    one bool per light, True for a spot."""
    room = OSL_LAYER_LIMIT - OSL_LAYER_RESERVE
    return predict.Budget(_per_light((OSL_MATERIAL_LAYERS, OSL_WORLD_LAYERS), OSL_SPOT_EXTRA, spots), (room, room),
                          "OSL's shader group size (32 767 nodes per material)")


def eevee_budget(g=0.0, spots=()):
    """What a fogged material and the World can hold in EEVEE (predict.Budget over the lights' steps) for
    fog of anisotropy g; ``spots``: one bool per light, True for a spot."""
    room = EEVEE_UNIFORM_LIMIT - EEVEE_UNIFORM_RESERVE
    costs = (EEVEE_MATERIAL_BYTES, EEVEE_WORLD_BYTES)
    if g:
        costs = tuple(tuple(a + b for a, b in zip(c, extra)) for c, extra in zip(costs, EEVEE_ANISOTROPIC_EXTRA))
    return predict.Budget(_per_light(costs, EEVEE_SPOT_EXTRA, spots), (room, room),
                          "EEVEE's uniform block (64 KiB of node constants per material)")


def build_params(beta, albedo, world_light=False):
    ng, gin, gout = _new_group(PARAMS, [], [("Beta", F), ("Albedo", C), (WORLD_LIGHT, F)])
    for name, kind, value in (("Beta", "ShaderNodeValue", beta), ("Albedo", "ShaderNodeRGB", (*albedo, 1.0)),
                              (WORLD_LIGHT, "ShaderNodeValue", float(world_light))):
        node = ng.nodes.new(kind)
        node.name = node.label = name
        node.outputs[0].default_value = value
        ng.links.new(node.outputs[0], gout.inputs[name])
    return _install(ng, PARAMS)


WORLD_LIGHT = "World Light"   # the params group's 0/1: the World lights surfaces through the fog
ANISOTROPY_KEY = "analytic_fog_anisotropy"   # on the params group: the g the lights' models are built for


def set_anisotropy(g):
    """Store the fog's anisotropy g in the params group (which must exist)."""
    bpy.data.node_groups[PARAMS][ANISOTROPY_KEY] = float(g)


def set_params(beta, albedo, g=None, world_light=None):
    """Write the fog's settings into the shared params group (creating it if needed, or if an older
    version made it); ``g``: the anisotropy to store, ``world_light``: whether the World lights surfaces
    through the fog (``shading.shade_background``) (None: keep them)."""
    ng = bpy.data.node_groups.get(PARAMS)
    if ng is None or ng.nodes.get(WORLD_LIGHT) is None:
        kept = ng.get(ANISOTROPY_KEY) if ng is not None else None
        ng = build_params(beta, albedo, bool(world_light))
        if kept is not None:
            ng[ANISOTROPY_KEY] = kept
    if g is not None and ng.get(ANISOTROPY_KEY, 0.0) != float(g):
        set_anisotropy(g)
    ng.nodes["Beta"].outputs[0].default_value = beta
    ng.nodes["Albedo"].outputs[0].default_value = (*albedo, 1.0)
    if world_light is not None:
        ng.nodes[WORLD_LIGHT].outputs[0].default_value = float(world_light)
    return ng


def _up_to_date(name):
    """The group ``name`` if this code built it and its tables are all there (rebuilding costs seconds)."""
    ng = bpy.data.node_groups.get(name)
    if ng is None or ng.get(owned.BUILT) != code_fingerprint():
        return None
    return ng if all(n.image is not None for n in ng.nodes if n.bl_idname == "ShaderNodeTexImage") else None


def _medium(m, beta, albedo=None):
    """The Medium of a group's sockets (the per-light groups need only beta)."""
    return Medium(m.wrap(beta)) if albedo is None else Medium(m.wrap(beta), m.wrap(albedo, vector=True))


SPOT_ROWS = ("Spot X", "Spot Y", "Spot Z")   # a spot light's group inputs: its inverse matrix's rows (shading.Spot)
SPOT_COS, SPOT_BLEND = "Spot Cos Half", "Spot Blend"
AREA_HALF_X, AREA_HALF_Y = "Area Half X", "Area Half Y"   # an area light's: its rectangle's half sizes (m)


def _shape_names(models):
    """The names of the two shape inputs of a spot's or an area light's group (``shading.shape_args``)."""
    return (AREA_HALF_X, AREA_HALF_Y) if rungs.is_area(models) else (SPOT_COS, SPOT_BLEND)


def _spot_inputs(models):
    """The extra inputs of a spot's or an area light's group (``rungs.is_spot``), none for a point light's."""
    return [(n, V) for n in SPOT_ROWS] + [(n, F) for n in _shape_names(models)] if rungs.is_spot(models) else []


def _outputs(outputs, models):
    """A light group's outputs (name, socket type) for ``models``: the quantities ``outputs`` of
    ``rungs.OUTPUTS`` a light with these models has (``rungs.Output.present``)."""
    return [(o.name, C if o.colour else F) for o in outputs if o.present(models)]


def _read(m, node, outputs, kind):
    """``kind`` (shading.LightTerms or SkyTerms) from the outputs of a light group's instance ``node``."""
    return kind(**{o.field: m.wrap(node.outputs[o.name], vector=o.colour) for o in outputs if o.name in node.outputs})


def _light(g, models):
    """shading.Light from a per-light group's inputs ``g`` (name: value)."""
    cone = None
    if rungs.is_spot(models):
        kind = shading.Area if rungs.is_area(models) else shading.Spot
        cone = kind(tuple(g[n] for n in SPOT_ROWS), *(g[n] for n in _shape_names(models)))
    return shading.Light(g["Light"], g["Intensity"], cone)


def build_light(models, images):
    """Per-light surface group: ``shading.shade_point`` (Sun et al. 2005 Eq. 11, 14, 17-18) with ``models``."""
    name = light_group_name(models)
    if (ng := _up_to_date(name)) is not None:
        return ng
    ng, gin, gout = _new_group(name, [
        ("Beta", F), ("Light", V), ("Intensity", C), ("Position", V), ("Incoming", V),
        ("View Distance", F), ("Normal", V), ("Diffuse", C), ("Specular", C), ("Glossy Level", F),
        *_spot_inputs(models)], _outputs(rungs.SURFACE_OUTPUTS, models))
    m = NodeOps(ng, images)
    g = {s.name: m.wrap(s, vector=s.type in ("VECTOR", "RGBA")) for s in gin.outputs if s.name}
    pos, incoming, d_vp = g["Position"], g["Incoming"], g["View Distance"]
    geo = shading.Geometry(pos + incoming * d_vp, pos, incoming, d_vp, g["Normal"])
    material = shading.Material(g["Diffuse"], g["Specular"], g["Glossy Level"])
    light = _light(g, models)
    terms = shading.shade_point(m, geo, material, light, _medium(m, g["Beta"]), models)
    for o in rungs.SURFACE_OUTPUTS:
        if o.present(models):
            m.feed(gout.inputs[o.name], m.wrap(getattr(terms, o.field)))
    ng[owned.BUILT] = code_fingerprint()
    m.place()
    return _install(ng, name)


def build_background_light(models, images):
    """Per-light world group: ``shading.background_point`` (Sun et al. 2005 Eq. 12) with ``models``."""
    name = background_group_name(models)
    if (ng := _up_to_date(name)) is not None:
        return ng
    ng, gin, gout = _new_group(name, [
        ("Beta", F), ("Light", V), ("Intensity", C), ("Camera", V), ("Direction", V), *_spot_inputs(models),
    ], _outputs(rungs.SKY_OUTPUTS, models))
    m = NodeOps(ng, images)
    g = {s.name: m.wrap(s, vector=s.type in ("VECTOR", "RGBA")) for s in gin.outputs if s.name}
    light = _light(g, models)
    terms = shading.sky_terms(m, g["Camera"], g["Direction"], light, _medium(m, g["Beta"]), models)
    for o in rungs.SKY_OUTPUTS:
        if o.present(models):
            m.feed(gout.inputs[o.name], m.wrap(getattr(terms, o.field)))
    ng[owned.BUILT] = code_fingerprint()
    m.place()
    return _install(ng, name)


# --- scene-level sums over the fog lights -------------------------------------------

def _new_driver(sock):
    """A new driver of ``sock``'s value whose result is the value itself.  Blender 5.0's ``driver_add`` gives the
    driver's F-Curve two keyframes, (0, 0) and (1, 1), through which the result is mapped, and their evaluation
    snaps within 1e-4 of a key: a haze's density of 9.8e-5 /m came out 0 (no fog at all), 0.99995 came out 1.
    Without keyframes (or modifiers) an F-Curve passes the driver's value through."""
    sock.driver_remove("default_value")
    curve = sock.driver_add("default_value")
    curve.keyframe_points.clear()
    for modifier in list(curve.modifiers):
        curve.modifiers.remove(modifier)
    return curve.driver


def _drive_location(node, obj):
    """Inputs 0-2 of ``node`` follow ``obj``'s world location (TRANSFORMS drivers)."""
    for i, axis in enumerate("XYZ"):
        sock = node.inputs[i]
        d = _new_driver(sock)
        d.type = "SUM"
        var = d.variables.new()
        var.type = "TRANSFORMS"
        t = var.targets[0]
        t.id = obj
        t.transform_type = f"LOC_{axis}"
        t.transform_space = "WORLD_SPACE"


def _drive_expression(sock, expression, variables):
    """Drive ``sock``'s value by the simple expression ``expression`` of ``variables``: (name, ID, data path)
    of single properties (the ID's type taken from it: an object, light, camera, scene or node group).
    Simple expressions evaluate without Python, so with auto-run off and without the add-on."""
    d = _new_driver(sock)
    d.type = "SCRIPTED"
    for name, owner, path in variables:
        var = d.variables.new()
        var.name = name
        var.type = "SINGLE_PROP"
        var.targets[0].id_type = owner.id_type
        var.targets[0].id = owner
        var.targets[0].data_path = path
    d.expression = expression


def _drive_intensity(node, light_data):
    """Inputs 0-2 of ``node`` = radiant intensity P * colour * ``area.intensity_per_watt`` in W/sr
    (simple-expression drivers)."""
    for i in range(3):
        _drive_expression(node.inputs[i], f"p * c * {area.intensity_per_watt(light_data.type)!r}",
                          (("p", light_data, "energy"), ("c", light_data, f"color[{i}]")))


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
    if SPOT_ROWS[0] in node.inputs:
        _drive_spot(ng, k, light, node)
    return node


def _drive_spot(ng, k, light, node):
    """Feed a spot group ``node``'s cone inputs from ``light``: the rows of its world matrix's cofactor
    matrix (det(M) M^-1: row i is the cross product of the other two columns, j x k in cyclic order), and
    cos(spot_size / 2) and spot_blend, all by simple-expression drivers (``_drive_expression``).  The RNA
    path matrix_world[c][r] is the element of row r, column c."""
    for i, row_name in enumerate(SPOT_ROWS):
        vec = _driven_vector(ng, f"Light {k} {row_name}", -900, -300 * k - 60 * i)
        cj, ck = (i + 1) % 3, (i + 2) % 3
        for axis in range(3):
            a1, a2 = (axis + 1) % 3, (axis + 2) % 3
            _drive_expression(vec.inputs[axis], "a * b - c * e",   # (col_j x col_k)[axis]
                              [(name, light, f"matrix_world[{col}][{row}]")
                               for name, col, row in (("a", cj, a1), ("b", ck, a2), ("c", cj, a2), ("e", ck, a1))])
        ng.links.new(vec.outputs[0], node.inputs[row_name])
    for sock_name, path, expression in _shape_drivers(light):
        value = ng.nodes.new("ShaderNodeValue")
        value.name = value.label = f"Light {k} {sock_name}"
        value.location = (-900, -300 * k - 200)
        _drive_expression(value.outputs[0], expression, (("v", light.data, path),))
        ng.links.new(value.outputs[0], node.inputs[sock_name])


def _shape_drivers(light):
    """(input, light data path, expression of v) of a spot's cone or an area light's half sizes
    (``area.half_sizes`` of its shape, with the object's scale at the time of building)."""
    if light.data.type != "AREA":
        return (SPOT_COS, "spot_size", "cos(v * 0.5)"), (SPOT_BLEND, "spot_blend", "v")
    shape = light.data.shape
    per_x, _ = area.half_sizes(shape, 1.0, 1.0, max(light.matrix_world.to_scale()))
    y_path = "size_y" if shape in ("RECTANGLE", "ELLIPSE") else "size"
    return (AREA_HALF_X, "size", f"v * {per_x!r}"), (AREA_HALF_Y, y_path, f"v * {per_x!r}")


def _bundles(lights, models):
    """[(index of the first light, lights, models)] in runs of at most ``BUNDLE`` lights.

    Why bundles: Blender updates the whole node tree on every edit through its Python API (about 1 us
    per node already in the tree for each node added, link made or value set), so a Surface group
    holding every light's nodes took time growing with the square of the lights to build (64 lights:
    13 s; 256: minutes).  Each bundle is a group of its own, small while it is built, and the Surface
    and World groups hold one node per bundle.  Cycles and EEVEE inline groups, so what they compile
    is the same graph.
    """
    return [(k, lights[k:k + BUNDLE], models[k:k + BUNDLE]) for k in range(0, len(lights), BUNDLE)]


def _bundle_name(prefix, first, lights):
    return f"{prefix} {first + 1}-{first + len(lights)}"


def _name_bundles(bundles):
    """Give bundles built beside ones in use (``_new_group``'s BUILDING name) their own names, once the
    scene group that used the old ones has been replaced (``_install``), deleting the old ones.

    Not ``_install``: remapping a bundle's users while the old scene group still held it updated every
    material using that group (0.1 s a bundle with 1 000 materials)."""
    for ng in bundles:
        name = ng.name.removesuffix(BUILDING)
        if ng.name != name:
            old = bpy.data.node_groups.get(name)
            if old is not None and not old.users:
                bpy.data.node_groups.remove(old)
            ng.name = name


def _group_node(ng, tree, name, x, y, links=()):
    """A group node for ``tree`` in ``ng``, its inputs linked from ``links`` ((output socket, input name))."""
    node = ng.nodes.new("ShaderNodeGroup")
    node.node_tree = tree
    node.name = node.label = name
    node.location = (x, y)
    for src, dst in links:
        ng.links.new(src, node.inputs[dst])
    return node


def _place_bundles(ng, lights, models, build, shared, with_passes):
    """Build ``lights``' bundles with ``build`` (``build_surface_bundle`` or ``build_world_bundle``, its
    images given) and put one group node per bundle in ``ng``, its inputs linked from ``shared`` (input name:
    output socket) and, with the passes, from the bundle before's Running Sum.

    Returns ([(group node, the bundle's models)], bundle trees for ``_name_bundles``, the last Running Sum
    output or None)."""
    placed, trees, running = [], [], None
    for first, some, mods in _bundles(lights, models):
        tree = build(first, some, mods, with_passes, running is not None)
        trees.append(tree)
        node = _group_node(ng, tree, tree.name.removesuffix(BUILDING), -300, -300 * len(placed), [
            *((src, n) for n, src in shared.items()), *(((running, RUNNING),) if running is not None else ())])
        placed.append((node, mods))
        running = node.outputs[RUNNING] if with_passes else None
    return placed, trees, running


_SURFACE_SHARED = (("Beta", F), ("Position", V), ("Incoming", V), ("View Distance", F), ("Normal", V),
                   ("Diffuse", C), ("Specular", C), ("Glossy Level", F))   # a light group's inputs but its own
RUNNING = "Running Sum"   # a bundle's input and output with the fog passes: the Fog Light pass so far
GLASS_COLOR, GLASS_IOR = "Glass Color", "Glass IOR"   # the Surface group's inputs for a Glass BSDF (material.py)
SEE_THROUGH = "See Through"   # its output: the glows past glass and mirrors (Cycles; ``_place_tails``)


def build_surface_bundle(images, first, lights, models, with_passes, chained):
    """One bundle of the Surface group (``_bundles``): ``shading.sum_lights`` over ``lights``
    (Sun et al. 2005 Eq. 19's L_a) from their per-light groups (``build_light``).

    Outputs: Fog (one Emission closure per lit light, times the Opacity input), Emission (their colours'
    sum), Weighted and Weight (``shading.LightSums``).  ``with_passes``: Running Sum out is Running Sum in
    (``chained``; else nothing) plus this bundle's Fog Light (``_chained_closure_sum``).
    """
    name = _bundle_name(SURFACE_LIGHTS, first, lights)
    inputs = [*_SURFACE_SHARED, ("Albedo", C), ("View Transmittance", F), ("Is Camera", F), (passes.OPACITY, C)]
    outputs = [("Fog", "NodeSocketShader"), ("Emission", C), ("Weighted", F), ("Weight", F)]
    if with_passes:
        inputs, outputs = inputs + [(RUNNING, C)], outputs + [(RUNNING, C)]
    ng, gin, gout = _new_group(name, inputs, outputs)
    m = NodeOps(ng, {})
    g = {s.name: s for s in gin.outputs if s.name}
    terms = []
    for k, (light, mod) in enumerate(zip(lights, models)):
        node = _light_instance(ng, first + k, light, build_light(mod, images).name,
                               [(g[n], n) for n, _ in _SURFACE_SHARED])
        terms.append(_read(m, node, rungs.SURFACE_OUTPUTS, shading.LightTerms))
    sums = shading.sum_lights(m, terms, _medium(m, g["Beta"], g["Albedo"]), m.wrap(g["View Transmittance"]),
                              m.wrap(g["Is Camera"]))
    opacity = m.wrap(g[passes.OPACITY], vector=True)
    _closure_sum(m, gout.inputs["Fog"], "ShaderNodeEmission", [_times(m, e, opacity, with_passes)
                                                                for e, mod in zip(sums.emissions, models) if _lit(mod)])
    for sock, v in (("Emission", sums.emission), ("Weighted", sums.weighted), ("Weight", sums.weight)):
        m.feed(gout.inputs[sock], m.wrap(v))
    if with_passes:
        start = m.wrap(g[RUNNING], vector=True) if chained else None
        m.feed(gout.inputs[RUNNING], _chained_closure_sum(m, gout.inputs["Fog"], start))
    m.place()
    return ng


def build_surface(lights, models, images, with_passes=False, extra=None, tails=True, day=None, day_table=None,
                  day_dims=True, day_exact=True):
    """Scene group for materials: ``shading.shade_surface`` (Sun et al. 2005 Eq. 19) over ``lights``.

    ``models``: one rungs.LightModels per light.  Inputs mirror the Principled
    BSDF; outputs are the fields of ``shading.SurfaceFog``: Fog, the fog's
    light as a shader (one Emission closure per light, times the Opacity
    input), and Emission, the same as one colour (camera rays only),
    Transmittance e^{-beta D_vp} to scale the material, Direct Attenuation
    (EEVEE's stand-in for the per-light e^{-beta D_sp}) and per engine the
    Mix Factor 1 - scale of the user's shader.  ``with_passes``: it writes the
    fog passes (``passes.py``), weighted by the Opacity input (white: opaque).  ``extra(group)``: adds
    nodes of its own (the Compositor method's AOVs, ``comp_fog.add_surface_aovs``).  ``tails``: the glows
    past glass and mirrors (See Through, ``_place_tails``), only where the scene has them
    (``caveats.specular_paths``).  ``day(m, beta)``: the fog layer's ``sunlight.Daylight`` in this tree
    (``sunsky.daylight``), or None for fog that fills all space: the camera segment's transmittance is then the
    layer's, and the user's shader on every ray takes the sun's and the sky's dimming (``sunlight.direct_dimming``);
    with ``day_table`` (the fog light's TableSpec, its image in ``images``) camera rays also get the sun's and the
    sky's glow and their fog light on the surface (``daylight_light``); ``day_dims`` False leaves the sun's and the
    sky's dimming to the compositor (``comp_fog.build_fog_group``: once per pixel), ``day_exact`` False dims the
    camera segment by ``sunlight.proxy_transmittance`` (the compositor puts the exact colour on every pixel).  The
    lights sit in bundle groups (``_bundles``, ``build_surface_bundle``).

    Why closures: Cycles' SVM emits a shader's value nodes in the order of
    their ids, so one colour summed over the lights keeps every light's values
    on its stack of 255 floats at once (out of SVM stack space, every fogged
    material black, at 4 lights), while each closure's inputs are compiled
    and released before the next closure's.
    """
    ng, gin, gout = _new_group(SURFACE, [
        ("Base Color", C), ("Metallic", F), ("Roughness", F), ("Specular IOR Level", F), (passes.OPACITY, C),
        (GLASS_COLOR, C), (GLASS_IOR, F),
    ], [("Fog", "NodeSocketShader"), ("Emission", C), ("Transmittance", F), ("Direct Attenuation", F),
        ("Cycles Mix Factor", F), ("EEVEE Mix Factor", F), (SEE_THROUGH, "NodeSocketShader")])
    items = {i.name: i for i in ng.interface.items_tree if i.item_type == "SOCKET" and i.in_out == "INPUT"}
    items[passes.OPACITY].default_value = (1.0, 1.0, 1.0, 1.0)
    items[GLASS_COLOR].default_value = (0.0, 0.0, 0.0, 1.0)
    items[GLASS_IOR].default_value = 1.5
    m = NodeOps(ng, images)
    params = ng.nodes.new("ShaderNodeGroup")
    params.node_tree = bpy.data.node_groups[PARAMS]
    geo = ng.nodes.new("ShaderNodeNewGeometry")
    cam = ng.nodes.new("ShaderNodeCameraData")
    path = ng.nodes.new("ShaderNodeLightPath")
    g = {s.name: s for s in gin.outputs if s.name}
    diffuse, specular, level = surface.principled_to_phong(
        m, m.wrap(g["Base Color"], vector=True), m.wrap(g["Metallic"]), m.wrap(g["Roughness"]),
        m.wrap(g["Specular IOR Level"]), m.dot(m.wrap(geo.outputs["Incoming"], vector=True),
                                               m.wrap(geo.outputs["Normal"], vector=True)))
    is_camera = m.wrap(path.outputs["Is Camera Ray"])
    segment = specular_segment(m, path)
    fogged = is_camera + segment   # the rays the fog shades: 0 or 1
    view = m.wrap(cam.outputs["View Distance"])
    # the segment's length: from the camera on camera rays (Ray Length starts at the near clip there), from the
    # pane or mirror on a specular segment (Ray Length: the point is P + Incoming x Ray Length's end)
    length = m.select(segment, m.wrap(path.outputs["Ray Length"]), view)
    t_vp, transmit = shading.view_transmittance(m, m.wrap(params.outputs["Beta"]), length, fogged)
    if day is not None:
        daylight = day(m, m.wrap(params.outputs["Beta"]), m.wrap(params.outputs["Albedo"], vector=True))
        position, incoming = m.wrap(geo.outputs["Position"], vector=True), m.wrap(geo.outputs["Incoming"], vector=True)
        # a shader's factor is one number: with air, the mean of its colour (the Compositor takes the colour)
        t_vp = (sunlight.grey(m, sunlight.view_transmittance(m, daylight, position, incoming, length)) if day_exact
                else sunlight.proxy_transmittance(m, daylight, length))
        transmit = 1.0 + fogged * (t_vp - 1.0)
        if day_dims:
            transmit = transmit * sunlight.grey(m, sunlight.direct_dimming(
                m, daylight, position, m.wrap(geo.outputs["Normal"], vector=True)))
    glow_length = view * (1.0 - segment)   # a specular segment's glow is the tails' (``build_tail_bundle``)
    shared = {"Beta": params.outputs["Beta"], "Albedo": params.outputs["Albedo"], "Position": geo.outputs["Position"],
              "Incoming": geo.outputs["Incoming"], "View Distance": glow_length.sock,
              "Normal": geo.outputs["Normal"], "Diffuse": diffuse.sock, "Specular": specular.sock,
              "Glossy Level": level.sock, "View Transmittance": t_vp.sock, "Is Camera": fogged.sock,
              passes.OPACITY: g[passes.OPACITY]}
    placed, bundles, running = _place_bundles(
        ng, lights, models, functools.partial(build_surface_bundle, images), shared, with_passes)
    sums = None
    for node, _ in placed:
        sums = shading.merge_sums(sums, shading.LightSums(
            [], *(m.wrap(node.outputs[f], vector=f == "Emission") for f in ("Emission", "Weighted", "Weight"))))
    fogs = [node.outputs["Fog"] for node, mods in placed if any(_lit(mod) for mod in mods)]
    fog = shading.surface_fog(m, sums, transmit)
    if day is not None and day_table is not None:
        light = m.scale(daylight_light(
            m, daylight, day_table, position + m.scale(incoming, length), m.scale(incoming, -1.0), position,
            m.wrap(geo.outputs["Normal"], vector=True), diffuse + specular, length, t_vp), is_camera)
        emit = ng.nodes.new("ShaderNodeEmission")
        emit.location = (3000, -600)
        m.feed(emit.inputs["Color"], light)
        fogs.append(emit.outputs["Emission"])
        fog = fog._replace(emission=fog.emission + light)
    _shader_tree(ng, gout.inputs["Fog"], fogs)
    for sock, v in (("Emission", fog.emission), ("Transmittance", fog.transmittance),
                    ("Direct Attenuation", fog.direct_attenuation), ("Cycles Mix Factor", fog.cycles_mix),
                    ("EEVEE Mix Factor", fog.eevee_mix)):
        m.feed(gout.inputs[sock], m.wrap(v))
    if with_passes:
        light = m.wrap(running, vector=True) if running is not None else m.wrap((0.0, 0.0, 0.0))
        passes.write_group(m, ng, light, m.wrap(fog.transmittance), m.wrap(g[passes.OPACITY], vector=True),
                           light_weighted=True)
    else:
        _camera_rays_only(ng, gout.inputs["Fog"], fogged.sock)
    tails = _place_tails(m, ng, lights, models, images, geo, g, segment, is_camera, t_vp,
                         {"Beta": params.outputs["Beta"], "Albedo": params.outputs["Albedo"],
                          "Position": geo.outputs["Position"]}, len(placed)) if tails else []
    if extra is not None:   # before it replaces the group the materials use: adding a node there costs more
        extra(ng)
    m.place()
    ng = _install(ng, SURFACE)
    _name_bundles(bundles + tails)
    return ng


def specular_segment(m, path):
    """1 on a ray that leaves a glass pane or a mirror on a path of sharp bounces from the camera (Cycles'
    Light Path: not a camera ray, Is Singular Ray, Diffuse Depth 0), else 0.  Such a ray is a segment of
    its own: it starts at P + Incoming x Ray Length (Ray Length is the segment's length on every ray but
    the camera's, which Cycles measures from the near clip plane).  EEVEE traces no such rays (its Is
    Singular Ray is 0): what it refracts or reflects is its picture or its probes."""
    singular = m.wrap(path.outputs["Is Singular Ray"])
    first = m.less(m.wrap(path.outputs["Diffuse Depth"]), 0.5)
    return (1.0 - m.wrap(path.outputs["Is Camera Ray"])) * singular * first


def _place_tails(m, ng, lights, models, images, geo, g, segment, is_camera, t_vp, shared, below):
    """The Surface group's See Through shader (Cycles only: ``material.py`` adds it to the Cycles output):
    the glows of the segments past a glass pane or a mirror, by differences of tails.

    The glow of a light along a segment from a to b is G_inf(a) - e^{-beta |ab|} G_inf(b) (Sun et al. 2005
    Eq. 12's glow to infinity, ``shading.background_point``, from each end in the segment's direction; the
    sum of differences of one primitive, Biri 2006 §III.D).  So each vertex of a sharp path adds what it
    can compute without knowing where the next segment ends, the glow to infinity of the segments leaving
    it, weighted as Cycles weights them; and each vertex a sharp segment reaches takes away the tail past
    itself, dimmed by its own segment, e^{-beta Ray Length}.  A segment that escapes to the sky keeps its
    whole tail: the World, which knows no ray origin, adds nothing on those rays (``build_world``).
    Cycles multiplies by the path's throughput, so each segment's glow and extinction compose along the
    path (Eq. 19 applied at every vertex).  The leaving segments' weights:

    * a Glass BSDF (``GLASS_COLOR``, ``GLASS_IOR`` fed by ``material.py``): colour x (1 - F) straight on
      (the segment's direction through a thin pane, exact for IOR 1 and for a parallel slab up to its
      thickness) and colour x F about the mirrored direction, F the dielectric Fresnel factor (Fresnel
      node, as Cycles' glass);
    * a mirror (Principled, roughness 0): its glossy fog light (``shading.shade_point``'s Phong lobe of
      the highest exponent, which is a blurred tail to infinity) already is.

    ``below``: the Surface group's light bundles placed (their rows).  Returns the bundle groups built.
    """
    kept = [(light, mod) for light, mod in zip(lights, models)
            if any(o.computed(mod) for o in rungs.SKY_OUTPUTS if o.colour)]
    if not kept:
        return []
    fresnel = ng.nodes.new("ShaderNodeFresnel")
    fresnel.location = (-600, 600)
    ng.links.new(g[GLASS_IOR], fresnel.inputs["IOR"])
    f = m.wrap(fresnel.outputs[0])
    glass = m.wrap(g[GLASS_COLOR], vector=True)
    incoming = m.wrap(geo.outputs["Incoming"], vector=True)
    seg3 = m.combine(segment, segment, segment)
    # the tails' own copy of Position (the same value): the light groups' nodes that read Position would
    # otherwise be one node in Cycles' graph (its deduplication) with the Surface bundles' and, read by both
    # sides of the closure tree, stay on SVM's stack for both: 4 floats a light (199 floats at 24 lights)
    position = m.wrap(shared["Position"], vector=True) + _exact_zero(m, incoming)
    inputs = dict(shared, **{"Position": position.sock, "Straight": m.scale(incoming, -1.0).sock,
                             "Mirrored": shading.mirror(m, incoming, m.wrap(geo.outputs["Normal"], vector=True)).sock,
                             "Straight Weight": (m.scale(glass, 1.0 - f) - seg3).sock,
                             "Mirrored Weight": m.scale(glass, f).sock, "Transmittance": t_vp.sock})
    fogs, trees = [], []
    for first, some, mods in _bundles([light for light, _ in kept], [mod for _, mod in kept]):
        tree = build_tail_bundle(images, first, some, mods)
        trees.append(tree)
        node = _group_node(ng, tree, tree.name.removesuffix(BUILDING), -300, -300 * (below + len(fogs)),
                           [(src, n) for n, src in inputs.items()])
        fogs.append(node.outputs["Fog"])
    out = next(n for n in ng.nodes if n.bl_idname == "NodeGroupOutput").inputs[SEE_THROUGH]
    _shader_tree(ng, out, fogs)
    # only on a specular segment, or on a camera ray that meets glass: a factor of exactly 0 elsewhere, where
    # Cycles' SVM jumps over the tails (``_camera_rays_only``)
    has_glass = m.less(0.0, m.dot(glass, m.combine(1.0, 1.0, 1.0)))
    gate = m.clamp(segment + is_camera * has_glass)
    _camera_rays_only(ng, out, gate.sock, "Specular Paths Only")
    return trees


def build_tail_bundle(images, first, lights, models):
    """One bundle of the Surface group's See Through shader (``_place_tails``): for each light, the albedo
    times Transmittance times (Straight Weight x its glow to infinity from Position along Straight + Mirrored
    Weight x along Mirrored), from two instances of its World group (``build_background_light``), as one
    Emission closure (its colour may be negative: Cycles passes negative emission through)."""
    name = _bundle_name(SURFACE_TAILS, first, lights)
    ng, gin, gout = _new_group(name, [("Beta", F), ("Albedo", C), ("Position", V), ("Straight", V), ("Mirrored", V),
                                      ("Straight Weight", C), ("Mirrored Weight", C), ("Transmittance", F)],
                               [("Fog", "NodeSocketShader")])
    m = NodeOps(ng, {})
    g = {s.name: s for s in gin.outputs if s.name}
    albedo = m.wrap(g["Albedo"], vector=True)
    scale = m.scale(albedo, m.wrap(g["Transmittance"]))
    colours = []
    for k, (light, mod) in enumerate(zip(lights, models)):
        straight = _light_instance(ng, first + k, light, build_background_light(mod, images).name,
                                   [(g["Beta"], "Beta"), (g["Position"], "Camera"), (g["Straight"], "Direction")])
        mirrored = ng.nodes.new("ShaderNodeGroup")
        mirrored.node_tree = straight.node_tree
        mirrored.name = mirrored.label = f"{straight.name} (mirrored)"
        mirrored.location = (straight.location.x, straight.location.y - 150)
        for sock in straight.inputs:
            src = g["Mirrored"] if sock.name == "Direction" else (sock.links[0].from_socket if sock.is_linked
                                                                  else None)
            if src is not None:
                ng.links.new(src, mirrored.inputs[sock.name])
        tail = (m.wrap(straight.outputs[rungs.BACKGROUND_OUT.name], vector=True) * m.wrap(g["Straight Weight"],
                                                                                        vector=True)
                + m.wrap(mirrored.outputs[rungs.BACKGROUND_OUT.name], vector=True) * m.wrap(g["Mirrored Weight"],
                                                                                          vector=True))
        colours.append(tail * scale)
    _closure_sum(m, gout.inputs["Fog"], "ShaderNodeEmission", colours)
    m.place()
    return ng


def _camera_rays_only(ng, sock, is_camera, label="Camera Rays Only"):
    """Put the shader linked into ``sock`` behind a Mix Shader whose factor is Is Camera Ray (or the
    socket ``is_camera``: a factor of exactly 0 or 1).

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
    mix.name = mix.label = label
    mix.location = (sock.node.location.x - 200, sock.node.location.y)
    ng.links.new(is_camera, mix.inputs[0])
    ng.links.new(src, mix.inputs[2])
    ng.links.new(mix.outputs[0], sock)


def _exact_zero(m, v):
    """(0, 0, 0) computed from the vector ``v``: max(min(v, 0), 0), exactly 0 for any v (NaN too), which
    neither Blender's inlining nor Cycles' constant folding removes.  A data dependency on ``v`` only."""
    black = (0.0, 0.0, 0.0)
    return m.vmath("MAXIMUM", m.vmath("MINIMUM", v, black), black)


def _chained_closure_sum(m, sock, total=None):
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
    this one, ``build_surface_bundle``), or None.
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


def _lit(models):
    """False for a light whose every fog term is off (``rungs.STEPS`` "off"): it adds no fog light."""
    return any(o.computed(models) for o in rungs.SURFACE_OUTPUTS if o.colour)


def _times(m, emission, factor, flat):
    """A light's fog light (a colour or ``shading.Gated``) times the colour ``factor``; ``flat``: a Gated
    as one colour (the fog passes read every closure's colour, ``_chained_closure_sum``)."""
    if not isinstance(emission, shading.Gated):
        return m.wrap(emission, vector=True) * factor
    glow, rest = m.wrap(emission.glow, vector=True) * factor, m.wrap(emission.rest, vector=True) * factor
    return glow + rest if flat else emission._replace(glow=glow, rest=rest)


def _closure_sum(m, sock, bl_idname, colours):
    """Link into ``sock`` the sum of one ``bl_idname`` closure (Emission, Background) per colour
    (``_shader_tree``).  A ``shading.Gated`` colour gets two: its rest (if any), and its glow behind a Mix
    Shader of factor gate, whose nodes Cycles' SVM jumps over where the gate is 0 (a spot's glow where the
    ray misses its cone: most of the view for a narrow beam)."""
    ng = m.tree
    leaves = []

    def closure(k, colour, part=""):
        node = ng.nodes.new(bl_idname)
        node.name = node.label = f"Light {k} Fog{part}"
        node.location = (3600, -300 * k)
        m.feed(node.inputs["Color"], m.wrap(colour, vector=True))
        return node

    for k, colour in enumerate(colours):
        if not isinstance(colour, shading.Gated):
            leaves.append(closure(k, colour).outputs[0])
            continue
        mix = ng.nodes.new("ShaderNodeMixShader")
        mix.name = mix.label = f"Light {k} Glow Gate"
        mix.location = (3800, -300 * k)
        m.feed(mix.inputs[0], m.wrap(colour.gate))
        ng.links.new(closure(k, colour.glow, " Glow").outputs[0], mix.inputs[2])   # input 1 empty: no closure
        leaves.append(mix.outputs[0])
        if colour.rest is not None:
            leaves.append(closure(k, colour.rest).outputs[0])
    _shader_tree(ng, sock, leaves)


def _shader_tree(ng, sock, shaders):
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


def build_world_bundle(images, first, lights, models, with_passes, chained):
    """One bundle of the World group (``_bundles``): the lights' glows to infinity (Sun et al. 2005
    Eq. 12) from their per-light groups (``build_background_light``).

    Outputs: Fog (one Background closure per light: its glow times the albedo on camera rays) and
    Airlight (the glows' sum).  ``with_passes``: Running Sum out is Running Sum in (``chained``; else
    nothing) plus the glows read by the pass's own instances of the light groups
    (``_world_pass_instances``).
    """
    name = _bundle_name(WORLD_LIGHTS, first, lights)
    inputs = [("Beta", F), ("Albedo", C), ("Camera", V), ("Direction", V), ("Is Camera", F)]
    outputs = [("Fog", "NodeSocketShader"), ("Airlight", C)]
    if with_passes:
        inputs, outputs = inputs + [("Pass Direction", V), (RUNNING, C)], outputs + [(RUNNING, C)]
    ng, gin, gout = _new_group(name, inputs, outputs)
    m = NodeOps(ng, {})
    g = {s.name: s for s in gin.outputs if s.name}
    medium, is_camera = _medium(m, g["Beta"], g["Albedo"]), m.wrap(g["Is Camera"])
    nodes, airlights, colours = [], [], []
    for k, (light, mod) in enumerate(zip(lights, models)):
        node = _light_instance(ng, first + k, light, build_background_light(mod, images).name,
                               [(g[n], n) for n in ("Beta", "Camera", "Direction")])
        nodes.append(node)
        sky = _read(m, node, rungs.SKY_OUTPUTS, shading.SkyTerms)
        airlights.append(sky.background)
        colour = m.wrap(shading.shade_background(m, [airlights[-1]], medium, is_camera)[0], vector=True)
        gated = sky.seen is not None and not with_passes
        colours.append(shading.Gated(sky.seen, colour, None) if gated else colour)
    _closure_sum(m, gout.inputs["Fog"], "ShaderNodeBackground", colours)   # see build_surface for why closures
    m.feed(gout.inputs["Airlight"], shading.total(airlights))
    if with_passes:
        start = m.wrap(g[RUNNING], vector=True) if chained else None
        m.feed(gout.inputs[RUNNING], _world_pass_instances(m, ng, nodes, m.wrap(g["Pass Direction"]), start))
    m.place()
    return ng


def daylight_light(m, day, table, camera, direction, position, normal, reflectance, length, t_vp, sun_share=None,
                   surface_share=None):
    """The sun's and the sky's light in a fog layer on a camera ray that meets a surface, the layer's and the air's
    albedo included (``precompute/sunlight.py``): the glow along the ray plus the fog light the surface reflects,
    dimmed on its way (Sun et al. 2005 Eq. 19's L_a; the reflectance taken as Lambertian: the diffuse plus the
    specular albedo times the irradiance over pi).  The Compositor's per pixel (``comp_fog._daylight``) and the
    Surface group's.  ``sun_share``: ``sunlight.ray_glow``'s, ``surface_share``: ``sunlight.fog_light``'s."""
    return sunlight.ray_glow(m, day, camera, direction, length, sun_share) + sunlight.times(
        m, reflectance * sunlight.fog_light(m, table, day, position, normal, surface_share), t_vp)


def build_world(lights, models, camera, images, with_passes=False, day=None, day_table=None, day_dims=True):
    """Scene group for the World: ``shading.shade_background`` (Sun et al. 2005 Eq. 12) over ``lights``.

    Camera position by TRANSFORMS drivers on ``camera`` (no node gives it in a
    world shader).  The background itself is seen through infinite fog:
    Transmittance is 0 (1 on rays other than the camera's if the params
    group's World Light is 1: they keep the world's lighting).  With a fog layer (``day``: ``build_surface``'s) the
    World is seen through it on camera rays (``sunlight.sky_seen``) and lights surfaces on every other ray (the
    materials dim it: ``sunlight.direct_dimming``), and with ``day_table`` camera rays get the sun's and the sky's
    glow to infinity (``sunlight.ray_glow``); ``day_dims`` False leaves the World untouched on every ray (the
    compositor dims the sky it sees: ``comp_fog.build_fog_group``).  The lights whose glow is on sit in bundle groups
    (``_bundles``, ``build_world_bundle``).
    """
    ng, gin, gout = _new_group(WORLD, [], [("Fog", "NodeSocketShader"), ("Emission", C), ("Transmittance", F)])
    m = NodeOps(ng, images)   # (the daylight glow's table: ``sunlight.table_glow``)
    params = ng.nodes.new("ShaderNodeGroup")
    params.node_tree = bpy.data.node_groups[PARAMS]
    geo = ng.nodes.new("ShaderNodeNewGeometry")
    path = ng.nodes.new("ShaderNodeLightPath")
    cam = _driven_vector(ng, "Camera Location", -600, 300)
    if camera is not None:
        _drive_location(cam, camera)
    direction = m.vmath("NORMALIZE", m.wrap(geo.outputs["Position"]))
    shared = {"Beta": params.outputs["Beta"], "Albedo": params.outputs["Albedo"], "Camera": cam.outputs[0],
              "Direction": direction.sock, "Is Camera": path.outputs["Is Camera Ray"]}
    if with_passes:   # the pass's direction, given another way (``_world_pass_instances``)
        shared["Pass Direction"] = m.vmath("NORMALIZE", m.vmath("SCALE", m.wrap(geo.outputs["Incoming"]), -1.0)).sock
    kept = [(light, mod) for light, mod in zip(lights, models)
            if any(o.computed(mod) for o in rungs.SKY_OUTPUTS if o.colour)]
    placed, bundles, running = _place_bundles(
        ng, [light for light, _ in kept], [mod for _, mod in kept],
        functools.partial(build_world_bundle, images), shared, with_passes)
    fogs = [node.outputs["Fog"] for node, _ in placed]
    medium = _medium(m, params.outputs["Beta"], params.outputs["Albedo"])
    is_camera = m.wrap(path.outputs["Is Camera Ray"])
    emission, transmittance = shading.shade_background(
        m, [m.wrap(node.outputs["Airlight"], vector=True) for node, _ in placed], medium, is_camera,
        m.wrap(params.outputs[WORLD_LIGHT]))
    if day is not None:   # (``in_world``: no driver reads the World from its own group: a dependency cycle)
        daylight = day(m, m.wrap(params.outputs["Beta"]), m.wrap(params.outputs["Albedo"], vector=True),
                       in_world=True)
        camera_at = m.wrap(cam.outputs[0], vector=True)
        seen = sunlight.grey(m, sunlight.sky_seen(m, daylight, camera_at, direction))
        transmittance = 1.0 + is_camera * (seen - 1.0) if day_dims else m.const(1.0)
        if day_table is not None:
            emission = m.wrap(emission, vector=True) + m.scale(
                sunlight.ray_glow(m, daylight, camera_at, direction, model.FAR), is_camera)
        if placed or day_table is not None:   # (the compositor's World: no glow, the sky dimmed per pixel)
            # the fogged World mixes the Fog closure by 1 - Transmittance (world.py), right where the sky is not
            # seen; through a layer it is: the whole glow (the lamps' and the daylight's) as one closure over it
            emit = ng.nodes.new("ShaderNodeEmission")
            m.feed(emit.inputs["Color"], m.scale(emission, 1.0 / m.maximum(1.0 - transmittance, 1e-6)))
            fogs = [emit.outputs["Emission"]]
    m.feed(gout.inputs["Emission"], m.wrap(emission))
    _shader_tree(ng, gout.inputs["Fog"], fogs)
    m.feed(gout.inputs["Transmittance"], m.wrap(transmittance))
    if with_passes:
        light, _ = shading.shade_background(m, [] if running is None else [m.wrap(running, vector=True)], medium,
                                            is_camera)
        passes.write_group(m, ng, m.wrap(light, vector=True), m.wrap(transmittance))
    m.place()
    ng = _install(ng, WORLD)
    _name_bundles(bundles)
    return ng


def _world_pass_instances(m, ng, nodes, direction, total):
    """The World's Fog Light pass in a bundle: ``total`` (the bundles before, or None) plus the glows of
    the pass's own instances of the light groups ``nodes`` (group nodes in ``ng``); returns the sum."""
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
    for node in nodes:
        twin = ng.nodes.new("ShaderNodeGroup")
        twin.node_tree = node.node_tree
        twin.name = twin.label = f"{node.name} (passes)"
        twin.location = (node.location.x, node.location.y - 150)
        along = direction if total is None else m.vmath("ADD", direction, _exact_zero(m, total))
        for sock in node.inputs:
            src = along.sock if sock.name == "Direction" else (sock.links[0].from_socket if sock.is_linked
                                                                 else None)
            if src is not None:
                ng.links.new(src, twin.inputs[sock.name])
        airlight = m.wrap(twin.outputs[rungs.BACKGROUND_OUT.name], vector=True)
        total = airlight if total is None else total + airlight
    return total
