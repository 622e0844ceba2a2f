"""Shader node groups of the fog, built from ``precompute/model.py`` via ``NodeOps``.

One shared copy of each group per .blend:

* ``AnalyticFog Params``: the fog's settings (density beta in 1/m, albedo colour).
* ``AnalyticFog Light``: one point light seen from a surface point (airlight
  along the camera ray, light scattered onto the surface, direct-light
  attenuation), instanced once per light.
* ``AnalyticFog Background Light``: one point light's airlight on a ray that
  meets no surface (the World).

  These two hold the fog's method: with "nodes" the airlight comes from the N
  table (Cycles and EEVEE), with "osl" from the Script node of ``osl.py``
  (quadrature, Cycles only).  Switching rebuilds just these two.
* ``AnalyticFog Surface`` / ``AnalyticFog World``: the sum over the scene's fog
  lights, their positions and intensities fed by drivers (no Python expression,
  so they evaluate with auto-run off and without the add-on).  Rebuilding these
  two when lights change leaves every material untouched.
"""
import math

import bpy

from ..precompute import model, surface
from . import images as table_images, osl
from .sockets import NodeOps

METHODS = ("nodes", "osl")

PARAMS = "AnalyticFog Params"
LIGHT = "AnalyticFog Light"
BACKGROUND_LIGHT = "AnalyticFog Background Light"
SURFACE = "AnalyticFog Surface"
WORLD = "AnalyticFog World"

FOG_PROP = "analytic_fog"   # custom-property key marking data the fog made or changed
BUILDING = " (building)"     # name suffix of a group being built beside the one in use
BUILT = "analytic_fog_built"   # on the per-light groups: the method and version they were built for
VERSION = 2                    # bump when a group's content changes: files made by older versions rebuild it


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


def set_params(beta, albedo):
    """Write the fog's settings into the shared params group (creating it if needed)."""
    ng = bpy.data.node_groups.get(PARAMS)
    if ng is None:
        return build_params(beta, albedo)
    ng.nodes["Beta"].outputs[0].default_value = beta
    ng.nodes["Albedo"].outputs[0].default_value = (*albedo, 1.0)
    return ng


def _colour_times(m, colour_sock, scalar):
    """colour (socket) * scalar (Val) as a vector Val."""
    return m.vmath("SCALE", m.wrap(colour_sock, vector=True), scalar)


def _airlight_osl(m, beta, light, camera, direction, distance=None):
    """The airlight Script node (``osl.airlight_source``) fed with these Vals; distance None: the background."""
    node = osl.script_node(m.tree)
    for name, v in (("Beta", beta), ("Light", light), ("Camera", camera), ("Direction", direction),
                    ("Distance", distance)):
        if v is not None:
            m.feed(node.inputs[name], m.wrap(v))
    return m.wrap(node.outputs["Airlight"])


def _built_key(method):
    return f"{method}/{VERSION}/tables {table_images.TABLE_VERSION}"


def _up_to_date(name, method):
    """The group ``name`` if it was built for ``method`` by this version and its tables are all there
    (rebuilding costs seconds)."""
    ng = bpy.data.node_groups.get(name)
    if ng is None or ng.get(BUILT) != _built_key(method):
        return None
    return ng if all(n.image is not None for n in ng.nodes if n.bl_idname == "ShaderNodeTexImage") else None


def build_light(images, method="nodes"):
    """Per-light surface group: Sun et al. 2005 Eq. 11 (airlight), 14 (direct), 17-18 (scattered)."""
    if (ng := _up_to_date(LIGHT, method)) is not None:
        return ng
    ng, gin, gout = _new_group(LIGHT, [
        ("Beta", F), ("Light", V), ("Intensity", C), ("Position", V), ("Incoming", V),
        ("View Distance", F), ("Normal", V), ("Diffuse", C), ("Specular", C), ("Glossy Level", F),
    ], [("Airlight", C), ("Scattered", C), ("Attenuation", F), ("Weight", F)])
    m = NodeOps(ng, images)
    g = {s.name: m.wrap(s) for s in gin.outputs if s.name}
    beta, light, pos, incoming = g["Beta"], g["Light"], g["Position"], g["Incoming"]
    d_vp = g["View Distance"]
    camera = pos + incoming * d_vp
    to_light = light - pos
    d_sp = m.length(to_light)
    if method == "osl":
        air = _airlight_osl(m, beta, light, camera, -1.0 * incoming, d_vp)
    else:
        d_sv, along, h = model.ray_light_geometry(m, camera, -1.0 * incoming, light)
        air = model.airlight_segment(m, beta, d_sv, along, h, d_vp, d_sp)
    att = model.transmittance(m, beta, d_sp)
    cos_n = m.dot(to_light, g["Normal"]) / m.maximum(d_sp, model.MIN_DISTANCE)
    weight = m.maximum(cos_n, 0.0) / m.maximum(d_sp * d_sp, model.MIN_DISTANCE ** 2)
    # mirror of the view direction about the normal: the axis of the glossy lobe (Sun App. B)
    nrm = g["Normal"]
    refl = nrm * (2.0 * m.dot(incoming, nrm)) - incoming
    cos_r = m.dot(to_light, refl) / m.maximum(d_sp, model.MIN_DISTANCE)
    diff = surface.surface_scatter(m, beta, d_sp, cos_n, 0.0)
    gloss = surface.surface_scatter(m, beta, d_sp, cos_r, g["Glossy Level"])
    scattered = (m.vmath("MULTIPLY", m.wrap(g["Diffuse"].sock, vector=True), m.combine(diff, diff, diff))
                 + m.vmath("MULTIPLY", m.wrap(g["Specular"].sock, vector=True), m.combine(gloss, gloss, gloss)))
    intensity = m.wrap(g["Intensity"].sock, vector=True)
    ng.links.new(_colour_times(m, g["Intensity"].sock, air).sock, gout.inputs["Airlight"])
    ng.links.new(m.vmath("MULTIPLY", intensity, scattered).sock, gout.inputs["Scattered"])
    ng.links.new(att.sock, gout.inputs["Attenuation"])
    ng.links.new(weight.sock, gout.inputs["Weight"])
    ng[BUILT] = _built_key(method)
    return _install(ng, LIGHT)


def build_background_light(images, method="nodes"):
    """Per-light world group: Sun et al. 2005 Eq. 12 (airlight of a ray to infinity)."""
    if (ng := _up_to_date(BACKGROUND_LIGHT, method)) is not None:
        return ng
    ng, gin, gout = _new_group(BACKGROUND_LIGHT, [
        ("Beta", F), ("Light", V), ("Intensity", C), ("Camera", V), ("Direction", V),
    ], [("Airlight", C)])
    m = NodeOps(ng, images)
    g = {s.name: m.wrap(s) for s in gin.outputs if s.name}
    if method == "osl":
        air = _airlight_osl(m, g["Beta"], g["Light"], g["Camera"], g["Direction"])
    else:
        d_sv, along, h = model.ray_light_geometry(m, g["Camera"], g["Direction"], g["Light"])
        air = model.airlight_background(m, g["Beta"], d_sv, along, h)
    ng.links.new(_colour_times(m, g["Intensity"].sock, air).sock, gout.inputs["Airlight"])
    ng[BUILT] = _built_key(method)
    return _install(ng, BACKGROUND_LIGHT)


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
    Returns (group node, intensity node).
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
    return node, inten


def build_surface(lights):
    """Scene group for materials: Sun et al. 2005 Eq. 19, L = e^{-T_vp} L_p + L_a, summed over ``lights``.

    Inputs mirror the Principled BSDF; outputs: Emission (airlight plus the
    fog light the surface reflects, camera rays only), Transmittance
    e^{-beta D_vp} to scale the material, Direct Attenuation (EEVEE's
    stand-in for the per-light e^{-beta D_sp}: their average weighted by each
    light's unshadowed irradiance), and per engine the Mix Factor 1 - scale
    of the user's shader (Cycles: 1 - Transmittance; EEVEE: 1 - Transmittance
    * Direct Attenuation).
    """
    ng, gin, gout = _new_group(SURFACE, [
        ("Base Color", C), ("Metallic", F), ("Roughness", F), ("Specular IOR Level", F),
    ], [("Emission", C), ("Transmittance", F), ("Direct Attenuation", F),
        ("Cycles Mix Factor", F), ("EEVEE Mix Factor", F)])
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
    beta = m.wrap(params.outputs["Beta"])
    air_sum = scat_sum = num = den = None
    for k, light in enumerate(lights):
        node, inten = _light_instance(ng, k, light, LIGHT, (
            (params.outputs["Beta"], "Beta"), (geo.outputs["Position"], "Position"),
            (geo.outputs["Incoming"], "Incoming"), (cam.outputs["View Distance"], "View Distance"),
            (geo.outputs["Normal"], "Normal"), (diffuse.sock, "Diffuse"), (specular.sock, "Specular"),
            (level.sock, "Glossy Level")))
        out = {s.name: m.wrap(s, vector=s.type != "VALUE") for s in node.outputs}
        w = out["Weight"] * m.dot(m.wrap(inten.outputs[0]), m.const(1.0 / 3.0) * m.combine(1.0, 1.0, 1.0))
        air_sum = out["Airlight"] if air_sum is None else air_sum + out["Airlight"]
        scat_sum = out["Scattered"] if scat_sum is None else scat_sum + out["Scattered"]
        num = w * out["Attenuation"] if num is None else num + w * out["Attenuation"]
        den = w if den is None else den + w
    is_cam = m.wrap(path.outputs["Is Camera Ray"])
    t_vp = model.transmittance(m, beta, m.wrap(cam.outputs["View Distance"]))
    albedo = m.wrap(params.outputs["Albedo"], vector=True)
    if lights:
        fog = m.vmath("MULTIPLY", albedo, air_sum + scat_sum * t_vp) * is_cam
        direct = (num + 1e-30) / (den + 1e-30)
    else:
        fog, direct = m.combine(0.0, 0.0, 0.0), m.const(1.0)
    ng.links.new(fog.sock, gout.inputs["Emission"])
    transmit = 1.0 + is_cam * (t_vp - 1.0)
    ng.links.new(transmit.sock, gout.inputs["Transmittance"])
    if direct.sock is None:
        gout.inputs["Direct Attenuation"].default_value = direct.const
    else:
        ng.links.new(direct.sock, gout.inputs["Direct Attenuation"])
    # the factors of the materials' Mix Shaders (1 - scale of the user's shader), computed once here
    # rather than by two Math nodes per engine in each of a scene's materials
    ng.links.new((1.0 - transmit).sock, gout.inputs["Cycles Mix Factor"])
    ng.links.new((1.0 - transmit * direct).sock, gout.inputs["EEVEE Mix Factor"])
    return _install(ng, SURFACE)


def build_world(lights, camera):
    """Scene group for the World: airlight to infinity (Sun et al. 2005 Eq. 12) summed over ``lights``.

    Camera position by TRANSFORMS drivers on ``camera`` (no node gives it in a
    world shader).  The background itself is seen through infinite fog:
    Transmittance is 0 on camera rays (1 on other rays, which keep the
    world's lighting).
    """
    ng, gin, gout = _new_group(WORLD, [], [("Emission", C), ("Transmittance", F)])
    m = NodeOps(ng, {})
    params = ng.nodes.new("ShaderNodeGroup")
    params.node_tree = bpy.data.node_groups[PARAMS]
    geo = ng.nodes.new("ShaderNodeNewGeometry")
    path = ng.nodes.new("ShaderNodeLightPath")
    cam = _driven_vector(ng, "Camera Location", -600, 300)
    if camera is not None:
        _drive_location(cam, camera)
    direction = m.vmath("NORMALIZE", m.wrap(geo.outputs["Position"]))
    total = None
    for k, light in enumerate(lights):
        node, _ = _light_instance(ng, k, light, BACKGROUND_LIGHT, (
            (params.outputs["Beta"], "Beta"), (cam.outputs[0], "Camera"), (direction.sock, "Direction")))
        a = m.wrap(node.outputs["Airlight"], vector=True)
        total = a if total is None else total + a
    is_cam = m.wrap(path.outputs["Is Camera Ray"])
    albedo = m.wrap(params.outputs["Albedo"], vector=True)
    fog = m.vmath("MULTIPLY", albedo, total) * is_cam if lights else m.combine(0.0, 0.0, 0.0)
    ng.links.new(fog.sock, gout.inputs["Emission"])
    ng.links.new((1.0 - is_cam).sock, gout.inputs["Transmittance"])
    return _install(ng, WORLD)
