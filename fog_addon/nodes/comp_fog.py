"""The Compositor method: the fog's light computed once per pixel in Blender's compositor.

With the node-group methods every fogged material evaluates every light's fog on every sample: the
cost grows with lights x samples x materials (issue 8's overhead: 4x the fog-free render at one light,
29x at 16).  Here the materials keep only what depends on the surface's depth along each sample:

* each light dims its own direct light through the fog (``light.py``: O(1) in the number of lights);
* every fogged material is scaled by e^{-beta D_vp} (the Surface group built without lights), and the
  Surface group writes the pixel's inputs as shader AOVs (``AOVS``): coverage, position, normal and the
  Principled inputs, each averaged over the pixel's samples;
* the World is black (the fog hides it);
* the compositor's ``AnalyticFog Compositor Fog`` group adds, per pixel, ``shading.shade_point`` at the
  pixel's mean surface point and the glows along the pixel's ray to it and to the sky
  (``shading.glow_pair``) over the lights, built by ``CompOps`` (the same formulas and tables as the
  materials' groups, each node once), plus the peak factor of ``pixel.py`` where a light is seen in the
  picture.

Everything the graph reads from the scene reaches it by simple-expression drivers (the camera's matrix,
lens, sensor and shift, the render's size, each light's position, power, colour and cone, the fog's
density and colour in the params group): a saved file renders any frame on a farm without the add-on.

In EEVEE, which writes AOVs as half floats accumulated with a loss and clamps negatives, the surface point
is the Depth pass's (float32) on the pixel's ray (``EEVEE_AOVS``), and the materials keep the lights' shared
dimming of direct light (EEVEE has no light node trees: ``apply.dimming_lights``).

Limits (README "The Compositor method"): one surface point per pixel, so a pixel that sees two surfaces
gets the fog light of one point (Cycles: their mean position; EEVEE: the one its centre sees); perspective
cameras; no fog passes (the fog's light is the compositor's).
"""
import bpy

from ..precompute import model, pixel, shading, surface
from . import compositor, groups, images as images_, owned
from .sockets import KERNEL_GROUP, NodeOps, Val

FOG_GROUP = f"{owned.PREFIX} Compositor Fog"     # the compositor group that adds the fog's light
LIGHT_GROUP = f"{owned.PREFIX} Compositor Light"  # per-light compositor groups: "<LIGHT_GROUP> [models]"
BUNDLE = f"{owned.PREFIX} Compositor Bundle"     # the scene's lights by BUNDLE_SIZE: "<BUNDLE> 1-8", ...
BUNDLE_SIZE = 8   # lights a bundle: Blender's node and link editing grows with a tree's size (one tree of 256
#                   lights with their drivers took over 15 min to build; ``build_fog_group``)
KERNEL_PREFIX = f"{KERNEL_GROUP} Compositor"   # the kernels' compositor groups (``sockets.NodeOps.group``)
AOVS = (("Fog Coverage", "VALUE"), ("Fog Position", "COLOR"), ("Fog Normal", "COLOR"),
        ("Fog Base Color", "COLOR"), ("Fog Metallic", "VALUE"), ("Fog Roughness", "VALUE"),
        ("Fog Specular IOR Level", "VALUE"))
# EEVEE writes AOVs as half floats accumulated with a loss (a constant 37.123 read back 37.03-37.09 at 16
# samples, README "The Compositor method") and clamps negatives: its surface point is the Depth pass's (float32,
# the sample nearest the pixel's centre) along the pixel's ray, with the mean View Z Depth where they disagree
EEVEE_AOVS = tuple(("Fog Depth", "VALUE") if name == "Fog Position" else (name, kind) for name, kind in AOVS)
DEPTH_AGREE = 0.02     # the Depth pass is the pixel's surface where within 2 % of the mean View Z Depth
AOV_ROLE = "Compositor AOV"   # the Surface group's AOV Output nodes: "<AOV_ROLE> <AOV name>"
PRINCIPLED = ("Base Color", "Metallic", "Roughness", "Specular IOR Level")
V, C, F = "NodeSocketVector", "NodeSocketColor", "NodeSocketFloat"
# what every light's group reads of the pixel (the same for all lights), and the terms it returns
SHARED = (("Beta", F), ("Camera", V), ("Position", V), ("Incoming", V), ("View Distance", F), ("Normal", V),
          ("Diffuse", V), ("Specular", V), ("Level", F), ("Direction", V), ("Pixel", V), ("Corner", V),
          ("Across", V), ("Up", V), ("Size", V))
TERMS = (("Airlight", V), ("Scattered", V), ("Background", V))


class CompOps(NodeOps):
    """NodeOps building into a compositor tree: compositor groups, tables read by Map UV, no EEVEE flags.

    Each node is built once per tree (``NodeOps``): Blender's compositor evaluates every node it is given,
    over every pixel."""

    GROUP_NODE = "CompositorNodeGroup"
    GROUP_TREE = "CompositorNodeTree"
    KERNEL_PREFIX = KERNEL_PREFIX
    inline = staticmethod(lambda node: None)

    def _table(self, spec, x, y, row0=0, rows=None):
        """One bilinear Map UV (the compositor's interpolation is exact bilinear between texel centres):
        x, y in [0, 1] span the texel centres of rows row0 .. row0 + rows - 1."""
        rows = spec.height if rows is None else rows
        u = self.clamp(x) * ((spec.width - 1.0) / spec.width) + 0.5 / spec.width
        v = self.clamp(y) * ((rows - 1.0) / spec.height) + (row0 + 0.5) / spec.height
        uv = self.combine(u, v, 1.0)   # Map UV takes the third component as the UV's alpha: 0 gives black
        im = self.node("CompositorNodeImage", uv.col + 1)
        im.image = self.images[spec.name]
        mu = self.node("CompositorNodeMapUV", uv.col + 1)
        mu.inputs["Interpolation"].default_value = "Bilinear"
        self.tree.links.new(im.outputs["Image"], mu.inputs["Image"])
        self.tree.links.new(uv.sock, mu.inputs["UV"])
        sep = self.node("CompositorNodeSeparateColor", uv.col + 2)
        self.tree.links.new(mu.outputs[0], sep.inputs[0])
        return Val(self, sock=sep.outputs["Alpha"], col=uv.col + 2)


def light_group_name(models, peak):
    return f"{LIGHT_GROUP} [{models.airlight.name}, {models.scatter.name}, {models.background.name}]" + (
        " Peak" if peak else "")


def all_group_names():
    """The compositor groups the fog can make in this file, users first: the fog group, the bundles, the
    per-light groups (their kernels are among ``groups.all_group_names``, which must come after these)."""
    names = {owned.base_name(ng.name) for ng in bpy.data.node_groups
             if ng.get(groups.FOG_PROP) and ng.name.startswith((LIGHT_GROUP, BUNDLE))}
    return [FOG_GROUP] + sorted(names, key=lambda name: (not name.startswith(BUNDLE), name))


def build_light_group(models, images, peak):
    """One light's fog light at a pixel (compositor group), shared by every light with these models:
    Airlight (the glow up to the surface, Sun et al. 2005 Eq. 12 through ``shading.shade_point``),
    Scattered (the fog light the surface reflects, Eq. 17-18) and Background (the glow of a ray that
    meets no surface).  ``peak``: times the peak factor (``pixel.peak_factor``) where the ray passes
    the light, seen in the picture at ``pixel.picture_position`` (Corner, Across, Up: the image plane,
    Size: the picture's, ``camera_frame`` and ``_picture_scale``)."""
    name = light_group_name(models, peak)
    if (ng := groups._up_to_date(name)) is not None:
        return ng
    ng, gin, gout = groups._new_group(name, [*SHARED, ("Light", V), ("Intensity", V), *groups._spot_inputs(models)],
                                      TERMS, tree_type="CompositorNodeTree")
    m = CompOps(ng, images)
    g = {s.name: m.wrap(s, vector=s.type in ("VECTOR", "RGBA")) for s in gin.outputs if s.name}
    geo = shading.Geometry(g["Camera"], g["Position"], g["Incoming"], g["View Distance"], g["Normal"])
    light = groups._light(g, models)
    medium = groups._medium(m, g["Beta"])
    material = shading.Material(g["Diffuse"], g["Specular"], g["Level"])
    # the glows to the surface and to the sky at once, both along the pixel's ray (``shading.glow_pair``)
    air_unit, back_unit = shading.glow_pair(m, g["Camera"], g["Direction"], g["View Distance"], light, medium,
                                            models)
    terms = shading.shade_point(m, geo, material, light, medium, models, air=air_unit)
    air = terms.airlight
    back = m.scale(light.intensity, back_unit)
    if peak:   # the sky's rays pass every light before the end of the world: its factor is 1 + excess
        to_light = g["Light"] - g["Camera"]
        seen_at = pixel.picture_position(m, to_light, g["Corner"], g["Across"], g["Up"], g["Size"])
        excess = pixel.peak_excess(m, g["Pixel"], seen_at)
        along = m.dot(to_light, -1.0 * g["Incoming"])
        air = m.scale(air, pixel.peak_factor(m, excess, along, g["View Distance"]))
        back = m.scale(back, 1.0 + excess)
    m.feed(gout.inputs["Airlight"], air)
    m.feed(gout.inputs["Scattered"], m.wrap(terms.scattered))
    m.feed(gout.inputs["Background"], back)
    ng[owned.BUILT] = groups.code_fingerprint()
    return groups._install(ng, name)


def aovs(engine):
    """The AOVs (name, kind) the Compositor method reads in ``engine`` (a ``render.engine``)."""
    return EEVEE_AOVS if engine == groups.EEVEE_ENGINE else AOVS


def add_surface_aovs(surface_group, engine="CYCLES"):
    """AOV Output nodes in the Surface group: the compositor's inputs per sample (``aovs(engine)``), the
    normal as (1 + n) / 2 (EEVEE clamps negatives), the Principled inputs as the fog reads them
    (``surface.principled_to_phong`` runs in the compositor)."""
    m = NodeOps(surface_group)
    gin = next(n for n in surface_group.nodes if n.bl_idname == "NodeGroupInput")
    geo = surface_group.nodes.new("ShaderNodeNewGeometry")
    cam = surface_group.nodes.new("ShaderNodeCameraData")
    normal = m.wrap(geo.outputs["Normal"], vector=True)
    values = {"Fog Coverage": m.wrap(1.0), "Fog Position": m.wrap(geo.outputs["Position"], vector=True),
              "Fog Depth": m.wrap(cam.outputs["View Z Depth"]), "Fog Normal": m.scale(normal, 0.5) + (0.5, 0.5, 0.5),
              **{f"Fog {k}": m.wrap(gin.outputs[k], vector=k == "Base Color") for k in PRINCIPLED}}
    for k, (name, kind) in enumerate(aovs(engine)):
        node = owned.add(surface_group, "ShaderNodeOutputAOV", f"{AOV_ROLE} {name}", (4000, -300 - 150 * k))
        node.aov_name = name
        m.feed(node.inputs["Color" if kind == "COLOR" else "Value"], values[name])


def _value(m, label, expression, variables):
    """A Value node driven by ``expression`` (``groups._drive_expression``)."""
    node = m.node("ShaderNodeValue", 0)
    node.label = label
    groups._drive_expression(node.outputs[0], expression, variables)
    return m.wrap(node.outputs[0])


def _vector(m, label, expressions, variables, col=0):
    """A vector whose components are driven by ``expressions`` (one per axis; ``variables`` may be a
    function of the axis)."""
    node = m.node("ShaderNodeCombineXYZ", col)
    node.label = label
    for i, expression in enumerate(expressions):
        groups._drive_expression(node.inputs[i], expression, variables(i) if callable(variables) else variables)
    return m.wrap(node.outputs[0], vector=True)


def horizontal_fit(scene):
    """True if the camera's sensor spans the picture's width (Blender's Auto fit on a landscape picture,
    or Horizontal), False if its height."""
    fit, r = scene.camera.data.sensor_fit, scene.render
    wide = r.resolution_x * r.pixel_aspect_x >= r.resolution_y * r.pixel_aspect_y
    return fit == "HORIZONTAL" or (fit == "AUTO" and wide)


def camera_frame(m, scene):
    """(corner, across, up) of the perspective camera's image plane at unit distance, in world space (m):
    the bottom-left corner's direction and the vectors to the bottom-right and top-left corners (a pixel at
    normalised (u, v) looks along corner + u across + v up), as Blender's ``Camera.view_frame``, driven by
    the camera's matrix, lens, sensor and shift and the render's size (square pixels)."""
    cam = scene.camera
    data = cam.data
    sensor = "sensor_height" if data.sensor_fit == "VERTICAL" else "sensor_width"
    common = [("l", data, "lens"), ("s", data, sensor), ("x", data, "shift_x"), ("y", data, "shift_y"),
              ("rx", scene, "render.resolution_x"), ("ry", scene, "render.resolution_y")]
    # w, h: the frame's width and height at unit distance; the shifts are in units of the fitted side
    w, h = ("s/l", "s*ry/(l*rx)") if horizontal_fit(scene) else ("s*rx/(l*ry)", "s/l")
    axes = lambda i: common + [(n, cam, f"matrix_world[{col}][{i}]") for n, col in (("a", 0), ("b", 1), ("c", 2))]
    corner = f"(x*s/l - {w}/2)*a + (y*s/l - {h}/2)*b - c"
    return [_vector(m, f"Camera {label}", [e] * 3, axes)
            for label, e in (("corner", corner), ("across", f"{w}*a"), ("up", f"{h}*b"))]


def _location(m, label, obj, col=0):
    """``obj``'s world location, driven as the shader groups drive theirs (``groups._drive_location``)."""
    node = m.node("ShaderNodeCombineXYZ", col)
    node.label = label
    groups._drive_location(node, obj)
    return m.wrap(node.outputs[0], vector=True)


def _picture_scale(m, scene, peak):
    """(w, h, 0): the picture's size in the filter table's pixels (``pixel.filter_scale``), driven by the
    render's resolution and percentage and the filter's width."""
    r = [("rx", scene, "render.resolution_x"), ("ry", scene, "render.resolution_y"),
         ("pc", scene, "render.resolution_percentage"), ("fw", scene, "cycles.filter_width")]
    k = f"pc/100*{pixel.DEFAULT_FILTER_WIDTH!r}/fw" if peak else "0"
    return _vector(m, "Picture Size", [f"rx*{k}", f"ry*{k}", "0"], r)


def _sum_terms(m, node, *sums):
    """``sums`` (Airlight, Scattered, Background so far, or None) plus ``node``'s outputs of those names."""
    terms = [m.wrap(node.outputs[name], vector=True) for name, _ in TERMS]
    return terms if sums[0] is None else [a + b for a, b in zip(sums, terms)]


def build_bundle(first, lights, models, images, peak):
    """The compositor group of the scene's lights ``first`` + 1 .. ``first`` + len(lights) (at most
    BUNDLE_SIZE): SHARED in, each light's group (``build_light_group``) with its position, intensity and
    cone driven by the light (``groups._drive_intensity``, ``_drive_spot``), TERMS summed out."""
    name = f"{BUNDLE} {first + 1}-{first + len(lights)}"
    ng, gin, gout = groups._new_group(name, SHARED, TERMS, tree_type="CompositorNodeTree")
    m = CompOps(ng, images)
    sums = [None] * 3
    for k, (light, mod) in enumerate(zip(lights, models), start=first):
        node = m.node("CompositorNodeGroup", 5)
        node.node_tree = build_light_group(mod, images, peak)
        node.label = f"Light {k}: {light.name}"
        for socket, _ in SHARED:
            ng.links.new(gin.outputs[socket], node.inputs[socket])
        position = _location(m, f"Light {k} Location", light, col=4)
        intensity = m.node("ShaderNodeCombineXYZ", 4)
        groups._drive_intensity(intensity, light.data)
        m.feed(node.inputs["Light"], position)
        ng.links.new(intensity.outputs[0], node.inputs["Intensity"])
        if groups.SPOT_COS in node.inputs:
            groups._drive_spot(ng, k, light, node)
        sums = _sum_terms(m, node, *sums)
    for (term, _), v in zip(TERMS, sums):
        m.feed(gout.inputs[term], v)
    return groups._install(ng, name)


def _params(m):
    """(beta 1/m, albedo) of the params group, driven (a density or colour change needs no rebuild)."""
    params = bpy.data.node_groups[groups.PARAMS]
    beta = _value(m, "Beta", "b", [("b", params, 'nodes["Beta"].outputs[0].default_value')])
    albedo = _vector(m, "Albedo", ["a"] * 3,
                     lambda i: [("a", params, f'nodes["Albedo"].outputs[0].default_value[{i}]')])
    return beta, albedo


def build_fog_group(scene, lights, models, images):
    """(Re)build the compositor group ``FOG_GROUP``: Image (the render) and the AOVs in; Image (the render
    plus the fog's light) and Fog Light out.  ``lights``: the fog's lights, ``models``: each light's
    rungs.LightModels.  Rebuilt in place, so the scene's compositor keeps its group node.  Returns the table
    images it reads (``images`` and the pixel filter's)."""
    peak = scene.render.engine == "CYCLES" and pixel.filter_scale(
        scene.cycles.pixel_filter_type, scene.cycles.filter_width) is not None
    if peak:
        images = dict(images, **{pixel.FILTER.name: images_.table_image(pixel.FILTER, pixel.bake_filter)})
    eevee = scene.render.engine == groups.EEVEE_ENGINE
    inputs = (("Image", "COLOR"),) + aovs(scene.render.engine) + (((compositor.DEPTH, "VALUE"),) if eevee else ())
    ng = bpy.data.node_groups.get(FOG_GROUP)
    if ng is None:
        ng = bpy.data.node_groups.new(FOG_GROUP, "CompositorNodeTree")
        ng[groups.FOG_PROP] = True
    if [(i.name, i.in_out) for i in ng.interface.items_tree] != [(n, "INPUT") for n, _ in inputs] + [
            ("Image", "OUTPUT"), ("Fog Light", "OUTPUT")]:   # new, or another engine's: the chain links it anew
        ng.interface.clear()
        for name, kind in inputs:
            ng.interface.new_socket(name, in_out="INPUT", socket_type=C if kind == "COLOR" else F)
        for name in ("Image", "Fog Light"):
            ng.interface.new_socket(name, in_out="OUTPUT", socket_type=C)
    ng.animation_data_clear()
    ng.nodes.clear()
    gin, gout = ng.nodes.new("NodeGroupInput"), ng.nodes.new("NodeGroupOutput")
    gout.location = (6000, 0)
    m = CompOps(ng, images)
    p = {s.name: m.wrap(s, vector=s.type == "RGBA") for s in gin.outputs if s.name}
    cover = p["Fog Coverage"]
    inv = 1.0 / m.maximum(cover, 1e-6)
    cam = _location(m, "Camera", scene.camera)
    beta, albedo = _params(m)
    coords = m.node("CompositorNodeImageCoordinates", 0)
    ng.links.new(gin.outputs["Image"], coords.inputs[0])
    uv = m.wrap(coords.outputs["Normalized"], vector=True)
    corner, across, up = camera_frame(m, scene)
    ray = corner + m.scale(across, m.dot(uv, (1.0, 0.0, 0.0))) + m.scale(up, m.dot(uv, (0.0, 1.0, 0.0)))
    direction = m.scale(ray, 1.0 / m.length(ray))
    if eevee:   # ray is the pixel's ray at unit view depth
        mean_depth, depth = p["Fog Depth"] * inv, p[compositor.DEPTH]
        agree = m.less(m.abs(depth - mean_depth), DEPTH_AGREE * mean_depth)
        pos = cam + m.scale(ray, m.select(agree, depth, mean_depth))
    else:
        pos = m.scale(p["Fog Position"], inv)
    to_cam = cam - pos
    d_vp = m.length(to_cam)
    incoming = m.scale(to_cam, 1.0 / m.maximum(d_vp, 1e-9))
    summed = m.scale(p["Fog Normal"], 2.0) - m.scale(m.wrap((1.0, 1.0, 1.0)), cover)   # written as (1 + n) / 2
    normal = m.scale(summed, 1.0 / m.maximum(m.length(summed), 1e-9))
    size = _picture_scale(m, scene, peak)
    pix = uv * size if peak else m.wrap((0.0, 0.0, 0.0))
    diffuse, specular, level = surface.principled_to_phong(
        m, m.scale(p["Fog Base Color"], inv), p["Fog Metallic"] * inv, p["Fog Roughness"] * inv,
        p["Fog Specular IOR Level"] * inv, m.dot(incoming, normal))
    shared = {"Beta": beta, "Camera": cam, "Position": pos, "Incoming": incoming, "View Distance": d_vp,
              "Normal": normal, "Diffuse": diffuse, "Specular": specular, "Level": level,
              "Direction": direction, "Pixel": pix, "Corner": corner, "Across": across, "Up": up, "Size": size}
    air = scat = back = None
    for first in range(0, len(lights), BUNDLE_SIZE):
        node = m.node("CompositorNodeGroup", 5)
        node.node_tree = build_bundle(first, lights[first:first + BUNDLE_SIZE], models[first:first + BUNDLE_SIZE],
                                      images, peak)
        for name, v in shared.items():
            m.feed(node.inputs[name], v)
        air, scat, back = _sum_terms(m, node, air, scat, back)
    if air is None:
        fog = m.wrap((0.0, 0.0, 0.0))
    else:
        t_vp = model.transmittance(m, beta, d_vp)
        fog = albedo * (m.scale(air + m.scale(scat, t_vp), cover) + m.scale(back, 1.0 - cover))
    m.feed(gout.inputs["Fog Light"], fog)
    m.feed(gout.inputs["Image"], fog + p["Image"])
    ng[owned.BUILT] = groups.code_fingerprint()
    return images
