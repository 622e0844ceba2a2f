"""The fog's light computed in Blender's compositor from render passes, once per pixel (a prototype).

    .venv/bin/python benchmarks/compositor_fog/build.py N MODE OUT.exr
MODE: nofog   the many-lights scene without fog;
      ratio   nofog, then comp in the same process (the issue's protocol: fog over no fog, one run);
      (CF_SPOTS=1: every light a spot as in benchmarks/overhead.py --spots; CF_ANISOTROPY=g: the fog's g)
      exact   the fog in the materials (Quality Exact, Fog Passes: the Fog Light AOV is the reference)
              plus the compositor's fog light as the Composite;
      comp    what would ship: the lights dim their own direct light (their node trees), the materials
              only scale by e^{-beta D_vp} and write the compositor's inputs as AOVs, the World is black
              (the fog hides it), and the compositor adds the fog's light.
Prints one JSON line: render CPU and wall seconds (best of REPS), set-up seconds.

The compositor's graph is ``shading.shade_point`` / ``background_point`` built by ``CompOps``, the node
backend with compositor groups and Map UV taps: the same formulas as the materials' groups.
Inputs per pixel (AOVs averaged over the pixel's samples): coverage by surfaces, position, normal, the
material's Principled inputs (``surface.principled_to_phong`` runs in the compositor); the camera rays'
directions and the lights' positions in the picture come from the camera's image plane (``camera_frame``).
"""
import json
import math
import os
import pathlib
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path[:0] = [str(ROOT), str(ROOT / "tests" / "scenes")]

import bpy  # noqa: E402
import numpy as np  # noqa: E402

import many_lights  # noqa: E402
from fog_addon import measure  # noqa: E402
from fog_addon.nodes import groups, images, sockets  # noqa: E402
from fog_addon.ops import apply, view  # noqa: E402
from fog_addon.precompute import model, rungs, shading, surface, tables  # noqa: E402

W, H, SPP = 320, 180, 16
AOVS = (("CF Cover", "VALUE"), ("CF Position", "COLOR"), ("CF Normal", "COLOR"), ("CF Base Color", "COLOR"),
        ("CF Metallic", "VALUE"), ("CF Roughness", "VALUE"), ("CF Specular IOR Level", "VALUE"),
        ("CF U1", "VALUE"), ("CF U2", "VALUE"), ("CF U3", "VALUE"))
MOMENTS = os.environ.get("CF_MOMENTS") == "1"   # the fog light at two depths per pixel (``two_depths``)
V, C, F = "NodeSocketVector", "NodeSocketColor", "NodeSocketFloat"
FILTER_WIDTH = 3.0    # px: Cycles' default Blackman-Harris filter, width 1.5, which its filter table doubles
FILTER_REACH = 6.0    # px: the filter table covers offsets |dx|, |dy| up to this
FILTER = tables.TableSpec("CF Pixel Filter", 97, 97)


def blackman_harris(x, width=FILTER_WIDTH):
    """Cycles' Blackman-Harris pixel filter (unnormalised) at offset x px from the pixel centre."""
    t = 2.0 * np.pi * (x / width + 0.5)
    value = 0.35875 - 0.48829 * np.cos(t) + 0.14128 * np.cos(2 * t) - 0.01168 * np.cos(3 * t)
    return np.where(np.abs(x) <= width / 2, value, 0.0)


def bake_filter():
    """E[1 / |delta + s|] (1/px) over the offsets s of a pixel's samples (x and y drawn independently from
    the filter, as Cycles does), for delta = (dx, dy) on FILTER's grid: the pixel's mean of a glow c / r
    about a light r px away, per unit c.  In polar coordinates about the light the 1/r cancels the area
    element, so the integrand is smooth: midpoint rule in (rho, phi)."""
    g = np.linspace(0.0, FILTER_REACH, FILTER.width)
    nr, nphi, reach = 240, 256, FILTER_REACH * 1.5 + FILTER_WIDTH
    rho = (np.arange(nr) + 0.5) / nr * reach
    phi = (np.arange(nphi) + 0.5) / nphi * 2 * np.pi
    x1 = np.linspace(-FILTER_WIDTH / 2, FILTER_WIDTH / 2, 20001)
    norm = np.trapz(blackman_harris(x1), x1) ** 2
    cr, sr = rho[None, :] * np.cos(phi)[:, None], rho[None, :] * np.sin(phi)[:, None]
    wx = blackman_harris(cr[None] - g[:, None, None]).reshape(len(g), -1)
    wy = blackman_harris(sr[None] - g[:, None, None]).reshape(len(g), -1)
    return wy @ wx.T * ((reach / nr) * (2 * np.pi / nphi) / norm)


def peak_excess(m, pixel, light_pixel):
    """r A(delta) - 1, tapered to 0 over the table's last pixel: how much a pixel's mean glow exceeds its
    centre's near a light seen in the picture, where the glow is c / r (r px from the light; Sun Eq. 12 as
    gamma -> 0, any phase function).  One per light and pixel: ``peak_factor`` applies it."""
    delta = pixel - light_pixel
    dx, dy = m.abs(m.dot(delta, (1.0, 0.0, 0.0))), m.abs(m.dot(delta, (0.0, 1.0, 0.0)))
    r = m.sqrt(dx * dx + dy * dy)
    a = m.table(FILTER, dx * (1.0 / FILTER_REACH), dy * (1.0 / FILTER_REACH))
    return m.clamp01(FILTER_REACH - r) * (r * a - 1.0)


def peak_factor(m, excess, along, d_vp):
    """The factor on a light's glow along a ray that ends at ``d_vp``: 1 + ``peak_excess`` where the ray
    passes the light (``along`` before ``d_vp``), 1 where a surface hides it."""
    return 1.0 + m.less(along, d_vp) * excess


class CompOps(sockets.NodeOps):
    """NodeOps building into a compositor tree: compositor groups, tables read by Map UV, no EEVEE flags."""

    GROUP_NODE = "CompositorNodeGroup"
    GROUP_TREE = "CompositorNodeTree"
    KERNEL_PREFIX = "CF Kernel"
    inline = staticmethod(lambda node: None)

    def table(self, spec, x, y, row0=0, rows=None):
        """One bilinear Map UV (the compositor's interpolation is exact bilinear between texel centres):
        x, y in [0, 1] span the texel centres of rows row0 .. row0 + rows - 1."""
        if os.environ.get("CF_TAPS") == "1":
            return super().table(spec, x, y, row0, rows)
        rows = spec.height if rows is None else rows
        u = self.clamp(x) * ((spec.width - 1.0) / spec.width) + 0.5 / spec.width
        v = self.clamp(y) * ((rows - 1.0) / spec.height) + (row0 + 0.5) / spec.height
        return self._tap(spec, u, v, "Bilinear")

    def _tap(self, spec, u, v, interpolation="Nearest"):
        uv = self.combine(u, v, 1.0)   # Map UV takes the third component as the UV's alpha
        im = self.node("CompositorNodeImage", uv.col + 1)
        im.image = self.images[spec.name]
        mu = self.node("CompositorNodeMapUV", uv.col + 1)
        mu.inputs["Interpolation"].default_value = interpolation
        self.tree.links.new(im.outputs["Image"], mu.inputs["Image"])
        self.tree.links.new(uv.sock, mu.inputs["UV"])
        sep = self.node("CompositorNodeSeparateColor", uv.col + 2)
        self.tree.links.new(mu.outputs[0], sep.inputs[0])
        return sockets.Val(self, sock=sep.outputs["Alpha"], col=uv.col + 2)


def _group(name, inputs, outputs):
    ng = bpy.data.node_groups.new(name, "CompositorNodeTree")
    for n, t in inputs:
        ng.interface.new_socket(n, in_out="INPUT", socket_type=t)
    for n, t in outputs:
        ng.interface.new_socket(n, in_out="OUTPUT", socket_type=t)
    return ng, ng.nodes.new("NodeGroupInput"), ng.nodes.new("NodeGroupOutput")


def light_group(models, imgs, peak, cache={}):
    """One light's fog light at a pixel, for every light with these models (compositor group)."""
    key = groups.light_group_name(models) + (" peak" if peak else "")
    if key in cache:
        return cache[key]
    ng, gin, gout = _group("CF " + key, [
        ("Beta", F), ("Light", V), ("Intensity", V), ("Camera", V), ("Position", V), ("Incoming", V),
        ("View Distance", F), ("Normal", V), ("Diffuse", V), ("Specular", V), ("Level", F), ("Direction", V),
        ("Pixel", V), ("Light Pixel", V), ("D1", F), ("D2", F), ("W1", F), *groups._spot_inputs(models)],
        [("Airlight", V), ("Scattered", V), ("Background", V)])
    m = CompOps(ng, imgs)
    g = {s.name: m.wrap(s, vector=s.type in ("VECTOR", "RGBA")) for s in gin.outputs if s.name}
    geo = shading.Geometry(g["Camera"], g["Position"], g["Incoming"], g["View Distance"], g["Normal"])
    light = groups._light(g, models)
    medium = groups._medium(m, g["Beta"])
    material = shading.Material(g["Diffuse"], g["Specular"], g["Level"])
    excess = peak_excess(m, g["Pixel"], g["Light Pixel"]) if peak else None
    if MOMENTS:   # the glow and the fog light the surfaces reflect at each of the two depths (the sky: FAR)
        d_sv, along, h = model.ray_light_geometry(m, g["Camera"], g["Direction"], g["Light"])
        glow, lit = [], []
        for d, w in ((g["D1"], g["W1"]), (g["D2"], 1.0 - g["W1"])):
            a = m.run(models.airlight, medium.beta, d_sv, along, h, d,
                      *shading.spot_ray(m, light, models.airlight, g["Camera"], g["Direction"]))
            glow.append(w * (a * peak_factor(m, excess, along, d) if peak else a))
            at = shading.Geometry(g["Camera"], g["Camera"] + m.scale(g["Direction"], d), -1.0 * g["Direction"], d,
                                  g["Normal"])
            surface_weight = w * m.less(d, 0.5 * model.FAR) * model.transmittance(m, medium.beta, d)
            lit.append(m.scale(shading.shade_point(m, at, material, light, medium, models).scattered,
                               surface_weight))
        air = m.scale(g["Intensity"], glow[0] + glow[1])
        scattered = lit[0] + lit[1]
        back = m.wrap((0.0, 0.0, 0.0))
    else:
        geo = shading.Geometry(g["Camera"], g["Position"], g["Incoming"], g["View Distance"], g["Normal"])
        terms = shading.shade_point(m, geo, material, light, medium, models)
        air, scattered = terms.airlight, terms.scattered
        back = shading.background_point(m, g["Camera"], g["Direction"], light, medium, models)
        if peak:   # the sky's rays pass every light before FAR: its factor is 1 + excess
            along = m.dot(g["Light"] - g["Camera"], -1.0 * g["Incoming"])
            air = m.scale(air, peak_factor(m, excess, along, g["View Distance"]))
            back = m.scale(back, 1.0 + excess)
    m.feed(gout.inputs["Airlight"], air)
    m.feed(gout.inputs["Scattered"], m.wrap(scattered))
    m.feed(gout.inputs["Background"], back)
    cache[key] = ng
    return ng


def light_pixel(scene, light):
    """The light's position in the picture, px from the bottom-left corner (far away behind the camera)."""
    from bpy_extras.object_utils import world_to_camera_view
    p = world_to_camera_view(scene, scene.camera, light.matrix_world.translation)
    w, h = view.render_size(scene)
    return (p.x * w, p.y * h, 0.0) if p.z > 0 else (1e6, 1e6, 0.0)


def write_light_pixels(scene, path):
    """``path``.json: the fog lights' positions in the picture (``light_pixel``), for ``compare.py``."""
    pixels = [light_pixel(scene, o) for o in apply.fog_lights(scene)[0]]
    pathlib.Path(str(path) + ".json").write_text(json.dumps({"light_pixels": pixels}))


def filter_scale(scene):
    """What pixel offsets are multiplied by to use FILTER (baked for Blackman-Harris of width 1.5: the
    mean of c / r scales as 1 / width, so r A(delta) depends on delta / width only); None where the peak
    factor does not apply (another filter: Gaussian pixel-centre sampling needs none)."""
    c = scene.cycles
    return 1.5 / c.filter_width if c.pixel_filter_type == "BLACKMAN_HARRIS" else None


def camera_frame(scene):
    """(corner, across, up): the perspective camera's image plane in world space, at the distance where
    Blender's view frame lies: the bottom-left corner's direction and the vectors to the bottom-right and
    top-left corners.  A pixel at normalised (u, v) looks along corner + u across + v up."""
    cam = scene.camera
    if cam.data.type != "PERSP":
        raise ValueError("the compositor's fog light needs a perspective camera")
    top_right, bottom_right, bottom_left, top_left = [cam.matrix_world.to_3x3() @ v
                                                      for v in cam.data.view_frame(scene=scene)]
    return bottom_left, bottom_right - bottom_left, top_left - bottom_left


def _drive(sock, expression, variables):
    """Drive ``sock`` by a simple expression (no Python at render time) of (name, ID, ID type, data path)."""
    d = sock.driver_add("default_value").driver
    d.type = "SCRIPTED"
    for name, owner, id_type, path in variables:
        var = d.variables.new()
        var.name, var.type = name, "SINGLE_PROP"
        var.targets[0].id_type = id_type
        var.targets[0].id = owner
        var.targets[0].data_path = path
    d.expression = expression


def driven_camera_frame(m, scene):
    """``camera_frame`` as three vectors driven by the camera's matrix, lens, sensor and shift and the
    render's size (sensor fit Auto or Horizontal, a picture at least as wide as it is tall)."""
    cam = scene.camera
    r = scene.render
    if cam.data.sensor_fit == "VERTICAL" or r.resolution_x < r.resolution_y:
        raise ValueError("the prototype drives a horizontal sensor fit only")
    common = [("l", cam.data, "CAMERA", "lens"), ("s", cam.data, "CAMERA", "sensor_width"),
              ("x", cam.data, "CAMERA", "shift_x"), ("y", cam.data, "CAMERA", "shift_y"),
              ("rx", scene, "SCENE", "render.resolution_x"), ("ry", scene, "SCENE", "render.resolution_y")]
    out = []
    for label, expression in (("corner", "(x*s/l - s/(2*l))*a + (y*s/l - s*ry/(2*l*rx))*b - c"),
                              ("across", "s/l*a"), ("up", "s*ry/(l*rx)*b")):
        vec = m.node("ShaderNodeCombineXYZ", 0)
        vec.label = f"Camera {label}"
        for i in range(3):
            _drive(vec.inputs[i], expression, common + [(n, cam, "OBJECT", f"matrix_world[{col}][{i}]")
                                                         for n, col in (("a", 0), ("b", 1), ("c", 2))])
        out.append(m.wrap(vec.outputs[0], vector=True))
    return out


def picture_position(m, to_light, corner, across, up, size):
    """Where the point ``to_light`` (from the camera, m) appears in the picture, in the units of
    ``size`` (its width and height), from the bottom-left corner; far outside when behind the camera."""
    normal = m.cross(across, up)
    t = m.dot(corner, normal) / m.dot(to_light, normal)
    q = m.scale(to_light, t) - corner
    u = m.dot(q, across) * (size[0] / m.dot(across, across))
    v = m.dot(q, up) * (size[1] / m.dot(up, up))
    behind = m.less(t, 0.0) * 1e6
    return m.combine(u + behind, v + behind, 0.0)


def build_compositor(scene, lights, models, imgs, beta, albedo, drive=False):
    """The compositor graph: Image + the fog's light (``comp``) or the fog's light alone (``exact``).
    ``drive``: the camera's and the lights' values by drivers (a saved file renders any frame without the
    add-on), else constants of the current frame."""
    tree = bpy.data.node_groups.new("CF Compositor", "CompositorNodeTree")
    tree.interface.new_socket("Image", in_out="OUTPUT", socket_type=C)
    m = CompOps(tree, imgs)
    rl = tree.nodes.new("CompositorNodeRLayers")
    out = tree.nodes.new("NodeGroupOutput")
    p = {n: m.wrap(rl.outputs[n], vector=t == "COLOR") for n, t in AOVS}
    cover = p["CF Cover"]
    inv = 1.0 / m.maximum(cover, 1e-6)
    if drive:
        cam_node = m.node("ShaderNodeCombineXYZ", 0)
        groups._drive_location(cam_node, scene.camera)
        cam = m.wrap(cam_node.outputs[0], vector=True)
    else:
        cam = m.wrap(tuple(scene.camera.matrix_world.translation))
    pos = m.scale(p["CF Position"], inv)
    to_cam = cam - pos
    d_vp = m.length(to_cam)
    incoming = m.scale(to_cam, 1.0 / m.maximum(d_vp, 1e-9))
    normal = m.scale(p["CF Normal"], 1.0 / m.maximum(m.length(p["CF Normal"]), 1e-9))
    coords = tree.nodes.new("CompositorNodeImageCoordinates")
    tree.links.new(rl.outputs["Image"], coords.inputs[0])
    uv = m.wrap(coords.outputs["Normalized"], vector=True)
    corner, across, up = (driven_camera_frame(m, scene) if drive else
                          [m.wrap(tuple(v)) for v in camera_frame(scene)])
    ray = corner + m.scale(across, m.dot(uv, (1.0, 0.0, 0.0))) + m.scale(up, m.dot(uv, (0.0, 1.0, 0.0)))
    direction = m.scale(ray, 1.0 / m.length(ray))
    w, h = view.render_size(scene)
    scale = filter_scale(scene)
    peak = scale is not None and os.environ.get("CF_PEAK", "1") == "1"
    scale = scale or 0.0
    pixel = uv * m.wrap((w * scale, h * scale, 0.0))
    mats = surface.principled_to_phong(m, m.scale(p["CF Base Color"], inv), p["CF Metallic"] * inv,
                                       p["CF Roughness"] * inv, p["CF Specular IOR Level"] * inv,
                                       m.dot(incoming, normal))
    d1, d2, w1 = two_depths(m, p["CF U1"], p["CF U2"], p["CF U3"], beta)
    air = scat = back = None
    for k, (light, mod) in enumerate(zip(lights, models)):
        node = m.node("CompositorNodeGroup", 5)
        node.node_tree = light_group(mod, imgs, peak)
        for name, v in (("Beta", m.wrap(beta)), ("Camera", cam), ("Position", pos), ("Incoming", incoming),
                        ("View Distance", d_vp), ("Normal", normal), ("Diffuse", mats[0]),
                        ("Specular", mats[1]), ("Level", mats[2]), ("Direction", direction), ("Pixel", pixel),
                        ("D1", d1), ("D2", d2), ("W1", w1)):
            m.feed(node.inputs[name], v)
        if drive:   # the shipped groups' drivers (groups._light_instance), here in the compositor
            loc = m.node("ShaderNodeCombineXYZ", 4)
            groups._drive_location(loc, light)
            intensity = m.node("ShaderNodeCombineXYZ", 4)
            groups._drive_intensity(intensity, light.data)
            tree.links.new(loc.outputs[0], node.inputs["Light"])
            tree.links.new(intensity.outputs[0], node.inputs["Intensity"])
            if view.is_spot(light):
                groups._drive_spot(tree, k, light, node)
            position = m.wrap(loc.outputs[0], vector=True)
        else:
            node.inputs["Light"].default_value = tuple(light.matrix_world.translation)
            node.inputs["Intensity"].default_value = tuple(view.light_intensities([light])[0])
            if view.is_spot(light):   # the cone as groups._drive_spot feeds it (constants here)
                m3 = light.matrix_world.to_3x3()
                cofactor = m3.inverted() * m3.determinant()
                for i, name in enumerate(groups.SPOT_ROWS):
                    node.inputs[name].default_value = tuple(cofactor[i])
                node.inputs[groups.SPOT_COS].default_value = math.cos(light.data.spot_size * 0.5)
                node.inputs[groups.SPOT_BLEND].default_value = light.data.spot_blend
            position = m.wrap(tuple(light.matrix_world.translation))
        m.feed(node.inputs["Light Pixel"], picture_position(m, position - cam, corner, across, up,
                                                            (w * scale, h * scale)))
        a, s, b = (m.wrap(node.outputs[n], vector=True) for n in ("Airlight", "Scattered", "Background"))
        air, scat, back = (a, s, b) if air is None else (air + a, scat + s, back + b)
    t_vp = m.exp(d_vp * -beta)
    if MOMENTS:   # the light group weighted the surfaces' fog light (``two_depths``)
        fog = m.wrap(tuple(albedo)) * (air + scat)
    else:
        fog = m.scale(m.wrap(tuple(albedo)) * (air + m.scale(scat, t_vp)), cover) + \
            m.scale(m.wrap(tuple(albedo)) * back, 1.0 - cover)
    return tree, rl, out, fog


def two_depths(m, u1, u2, u3, beta):
    """(D1, D2, w1): the two depths (m; the sky at model.FAR) and the first's weight of the two-point
    distribution with the pixel's first three moments of u = e^{-beta D} over its samples (the sky u = 0):
    the two-node Gauss quadrature of the pixel's depths, exact where a pixel sees two surfaces (or a
    surface and the sky), the mean depth where it sees one.  Nodes mu + sigma t, t^2 - gamma t - 1 = 0
    (gamma the skewness, clamped to +-10 where sigma is rounding noise), weights t2 / (t2 - t1) and
    -t1 / (t2 - t1)."""
    var = m.maximum(u2 - u1 * u1, 0.0)
    sigma = m.sqrt(var)
    third = u3 - 3.0 * u1 * u2 + 2.0 * u1 * u1 * u1
    gamma = m.clamp(third / m.maximum(var * sigma, 1e-30), -10.0, 10.0)
    root = m.sqrt(gamma * gamma + 4.0)
    t1, t2 = (gamma - root) * 0.5, (gamma + root) * 0.5
    depths = []
    for t in (t1, t2):
        u = m.clamp01(u1 + sigma * t)
        depths.append(m.minimum(m.math("LOGARITHM", m.maximum(u, 1e-30), math.e) * (-1.0 / beta), model.FAR))
    return depths[0], depths[1], t2 / root


def add_aovs(scene, imgs):
    """The compositor's inputs as AOVs written by the Surface group (every fogged material uses it): the
    Principled inputs as the fog reads them (``surface.principled_to_phong`` runs in the compositor)."""
    ng = bpy.data.node_groups[groups.SURFACE]
    m = sockets.NodeOps(ng, imgs)
    gin = next(n for n in ng.nodes if n.bl_idname == "NodeGroupInput")
    geo = ng.nodes.new("ShaderNodeNewGeometry")
    g = {s.name: s for s in gin.outputs if s.name}
    cam = ng.nodes.new("ShaderNodeCameraData")
    u = m.exp(m.wrap(cam.outputs["View Distance"]) * -groups.get_beta())
    values = {"CF U1": u, "CF U2": u * u, "CF U3": u * u * u,
              "CF Cover": m.wrap(1.0), "CF Position": m.wrap(geo.outputs["Position"], vector=True),
              "CF Normal": m.wrap(geo.outputs["Normal"], vector=True),
              **{f"CF {k}": m.wrap(g[k], vector=k == "Base Color") for k in
                 ("Base Color", "Metallic", "Roughness", "Specular IOR Level")}}
    for name, kind in AOVS:
        node = ng.nodes.new("ShaderNodeOutputAOV")
        node.aov_name = name
        m.feed(node.inputs["Color" if kind == "COLOR" else "Value"], m.wrap(values[name]))
        aov = scene.view_layers[0].aovs.add()
        aov.name, aov.type = name, kind


def to_compositor(scene, comp=True, lights=None, drive=False):
    """Move the fogged ``scene``'s fog light into the compositor: with ``comp`` the materials and the World
    keep only e^{-beta D_vp} (no light's nodes) and the Composite is the render plus the compositor's fog
    light; without, the materials keep their fog and the Composite is the compositor's fog light alone
    (to compare with the Fog Light pass).  Each light gets the models its Quality chose (the stored
    choice: ``apply.choose_models``), spot lights and Henyey-Greenstein g included."""
    scene.render.use_compositing = True
    lights = lights or apply.fog_lights(scene)[0]
    g = groups.get_anisotropy()
    imgs = images.all_table_images(g)
    imgs[FILTER.name] = images.table_image(FILTER, bake_filter)
    if comp:
        groups.build_surface([], [], imgs)
        groups.build_world([], [], scene.camera, imgs)
    add_aovs(scene, imgs)
    albedo = tuple(bpy.data.node_groups[groups.PARAMS].nodes["Albedo"].outputs[0].default_value)[:3]
    choice = apply.stored_choice()
    steps = [choice["lights"].get(o.name, [0])[0] if choice else 0 for o in lights]
    lights, models = zip(*[(o, rungs.choose("nodes", k, g, view.is_spot(o))) for o, k in zip(lights, steps)
                           if k != rungs.LEFT_OUT])
    tree, rl, out, fog = build_compositor(scene, lights, models, imgs, groups.get_beta(), albedo, drive)
    m = CompOps(tree, imgs)
    if comp:
        fog = fog + m.wrap(rl.outputs["Image"], vector=True)
    m.feed(out.inputs[0], fog)
    scene.compositing_node_group = tree


def _render_best(reps):
    """(min CPU s, min wall s) of ``reps`` renders of the scene to its output file."""
    best = [1e9, 1e9]
    for _ in range(reps):
        c0, w0 = time.process_time(), time.perf_counter()
        bpy.ops.render.render(write_still=True)
        best = [min(best[0], time.process_time() - c0), min(best[1], time.perf_counter() - w0)]
    return best


def main(n, mode, out_path):
    """``mode`` "ratio": the render without fog, then with the compositor's fog (``comp``), in one process."""
    scene, _ = many_lights.build_scene(n, direct_light=True)
    for ob in scene.objects if os.environ.get("CF_SPOTS") == "1" else ():   # as benchmarks/overhead.py --spots
        if ob.type == "LIGHT":
            ob.data.type = "SPOT"
            ob.data.spot_size, ob.data.spot_blend = math.radians(60.0), 0.3
            ob.rotation_euler = (0.0, 0.0, 0.0)   # local -Z: straight down
    scene.render.engine = "CYCLES"
    measure.set_resolution(scene, W, H)
    measure.set_samples(scene, SPP)
    measure.set_cycles_cpu(scene)
    scene.cycles.use_denoising = False
    scene.render.use_persistent_data = False
    bpy.context.view_layer.update()   # matrix_world of the new objects, read below
    measure.configure_output(scene, out_path)
    if mode != "ratio":   # the passes, for compare.py (timing writes only the picture, as a render would)
        scene.render.image_settings.media_type = "MULTI_LAYER_IMAGE"
        scene.render.image_settings.file_format = "OPEN_EXR_MULTILAYER"
    reps = int(os.environ.get("REPS", 2))
    row = {"n": n, "mode": mode}
    if mode in ("nofog", "ratio"):
        row["cpu_nofog"], row["wall_nofog"] = _render_best(reps)
    if mode != "nofog":
        t0 = time.perf_counter()
        apply.apply_fog(scene, many_lights.BETA, albedo=many_lights.ALBEDO, with_passes=mode == "exact",
                        error="exact" if mode == "exact" else "final",
                        anisotropy=float(os.environ.get("CF_ANISOTROPY", 0.0)))
        to_compositor(scene, comp=mode != "exact")
        if mode == "exact":
            write_light_pixels(scene, out_path)
        row["setup"] = time.perf_counter() - t0
        row["cpu"], row["wall"] = _render_best(reps)
    if mode == "ratio":
        row["ratio_cpu"], row["ratio_wall"] = row["cpu"] / row["cpu_nofog"], row["wall"] / row["wall_nofog"]
    print(json.dumps(row), flush=True)


if __name__ == "__main__":
    main(int(sys.argv[-3]), sys.argv[-2], sys.argv[-1])
