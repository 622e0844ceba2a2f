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
  picture; each light in two groups, its glows (``comp_lights.build_glow_group``) and the fog light its surface
  reflects (``comp_lights.build_scatter_group``), each evaluated only in its window (``precompute/model/footprint.py``:
  a spot's cone, the picture's surfaces) through Crop nodes, and put back in place by Translate nodes;
* the pixel's fog is composed in one place, ``compose.compose`` (Sun et al. 2005 Eq. 19 and 12): the builder hands
  it the lamps' sums over the bundles, a fog layer's sun and sky (``daylight_terms.pixel_terms``), the glowing objects'
  glows (``comp_emitters.glows``) and the layer's dimmings of the render's pixel as terms, and wires its output.

Everything the graph reads from the scene reaches it by simple-expression drivers (the camera's matrix,
lens, sensor and shift, the render's size, each light's position, power, colour and cone, the fog's
density and colour in the params group; the windows' crops from ID properties that hold every frame of an
animation): a saved file renders any frame on a farm without the add-on.

In EEVEE, which writes AOVs as half floats accumulated with a loss and clamps negatives, the surface point
is the Depth pass's (float32) on the pixel's ray (``EEVEE_AOVS``), and the materials keep the lights' shared
dimming of direct light (EEVEE has no light node trees: ``methods.compositor.dimming_lights``).

Limits (README "The Compositor method"): one surface point per pixel, so a pixel that sees two surfaces
gets the fog light of one point (Cycles: their mean position; EEVEE: the one its centre sees); perspective
cameras.  The fog passes are the group's outputs (Fog Light, Fog Transmittance), which a File Output node after
it writes (``compositor.py``): the view layers' own passes hold no fog light.
"""
import bpy

from ..precompute.model import compose, daylight_terms, footprint, pixel, rungs
from ..precompute.physics.daylight import sun_shafts, sunlight
from ..precompute.physics.point import model, surface
from ..precompute.physics.shafts import shafts
from . import (budgets, comp_bundles, comp_daylight, comp_emitters, comp_halos, comp_lights, comp_ops, comp_shafts,
               compositor, groups, images as images_, owned, passes)
from .comp_bundles import BUNDLE, BUNDLE_SIZE
from .comp_daylight import LAYER_OPEN
from .comp_emitters import EMITTERS
from .comp_halos import HALO_STEP
from .comp_lights import LIGHT_GROUP, SCATTER_OUTPUTS, SURFACE
from .comp_ops import WINDOW, CompOps
from .comp_shafts import SKY_LENGTH
from .groups import C, F
from .sockets import NodeOps

FOG_GROUP = f"{owned.PREFIX} Compositor Fog"     # the compositor group that adds the fog's light
AOVS = (("Fog Coverage", "VALUE"), ("Fog Position", "COLOR"), ("Fog Normal", "COLOR"),
        ("Fog Base Color", "COLOR"), ("Fog Metallic", "VALUE"), ("Fog Roughness", "VALUE"),
        ("Fog Specular IOR Level", "VALUE"), ("Fog Transmission Weight", "VALUE"))
# EEVEE writes AOVs as half floats accumulated with a loss (a constant 37.123 read back 37.03-37.09 at 16
# samples, README "The Compositor method") and clamps negatives: its surface point is the Depth pass's (float32,
# the sample nearest the pixel's centre) along the pixel's ray, with the mean View Z Depth where they disagree
# (``pixel.depth_surface``)
EEVEE_AOVS = tuple(("Fog Depth", "VALUE") if name == "Fog Position" else (name, kind) for name, kind in AOVS)
AOV_ROLE = "Compositor AOV"   # the Surface group's AOV Output nodes: "<AOV_ROLE> <AOV name>"
PRINCIPLED = ("Base Color", "Metallic", "Roughness", "Specular IOR Level", "Transmission Weight")


DIRECTION_AOV = ("Fog Direction", "COLOR")   # a panoramic camera's rays (Cycles): each sample's, the pixel's mean


def panoramic(scene):
    """True if ``scene``'s camera is panoramic in Cycles: the compositor reads its pixels' rays from the Fog Direction
    AOV (the materials' and the World's) instead of a perspective image plane (``camera_frame``).  EEVEE renders no
    panoramic camera (the method refuses one there)."""
    return (scene.camera is not None and scene.camera.data.type == "PANO"
            and scene.render.engine != budgets.EEVEE_ENGINE)


def aovs(engine, panoramic=False):
    """The AOVs (name, kind) the Compositor method reads in ``engine`` (a ``render.engine``), with a panoramic
    camera's ray directions (Cycles)."""
    return EEVEE_AOVS if engine == budgets.EEVEE_ENGINE else AOVS + ((DIRECTION_AOV,) if panoramic else ())


def _aov_node(tree, m, name, kind, k, value):
    node = owned.add(tree, "ShaderNodeOutputAOV", f"{AOV_ROLE} {name}", (4000, -300 - 150 * k))
    node.aov_name = name
    m.feed(node.inputs["Color" if kind == "COLOR" else "Value"], value)


def add_surface_aovs(surface_group, engine="CYCLES", panoramic=False):
    """AOV Output nodes in the Surface group: the compositor's inputs per sample (``aovs(engine, panoramic)``),
    the normal as (1 + n) / 2 (EEVEE clamps negatives), the Principled inputs as the fog reads them
    (``surface.principled_to_phong`` runs in the compositor), a panoramic camera's ray direction (-Incoming)."""
    m = NodeOps(surface_group)
    gin = next(n for n in surface_group.nodes if n.bl_idname == "NodeGroupInput")
    geo = surface_group.nodes.new("ShaderNodeNewGeometry")
    cam = surface_group.nodes.new("ShaderNodeCameraData")
    normal = m.wrap(geo.outputs["Normal"], vector=True)
    values = {"Fog Coverage": m.wrap(1.0), "Fog Position": m.wrap(geo.outputs["Position"], vector=True),
              "Fog Depth": m.wrap(cam.outputs["View Z Depth"]), "Fog Normal": m.scale(normal, 0.5) + (0.5, 0.5, 0.5),
              DIRECTION_AOV[0]: m.scale(m.wrap(geo.outputs["Incoming"], vector=True), -1.0),
              **{f"Fog {k}": m.wrap(gin.outputs[k], vector=k == "Base Color") for k in PRINCIPLED}}
    for k, (name, kind) in enumerate(aovs(engine, panoramic)):
        _aov_node(surface_group, m, name, kind, k, values[name])
    m.place()


def add_world_aovs(world_group):
    """The World group's Fog Direction AOV (a panoramic camera's, Cycles): the ray's direction, which the World
    reads as its Position.  With the materials' it is every sample's ray, whose mean the compositor normalises."""
    m = NodeOps(world_group)
    geo = world_group.nodes.new("ShaderNodeNewGeometry")
    _aov_node(world_group, m, *DIRECTION_AOV, 0, m.vmath("NORMALIZE", m.wrap(geo.outputs["Position"], vector=True)))
    m.place()


def all_group_names():
    """The compositor groups the fog can make in this file, users first: the fog group, the sets of bundles, the
    bundles, the per-light groups (their kernels are among ``groups.all_group_names``, which must come after
    these)."""
    names = {owned.base_name(ng.name) for ng in bpy.data.node_groups
             if ng.get(groups.FOG_PROP) and ng.name.startswith((LIGHT_GROUP, BUNDLE))}
    return [FOG_GROUP] + sorted(names, key=lambda name: (not name.startswith(comp_bundles.BUNDLE_SET),
                                                         not name.startswith(BUNDLE), name))


PARTIAL = "Fog Windows Partial"   # on the fog group: its windows were grown by single frames (or built full)
#                                    since they were last computed over an animation's range


def windows_partial():
    """True if the windows should be computed over the range again before the file is saved (``PARTIAL``)."""
    ng = bpy.data.node_groups.get(FOG_GROUP)
    return bool(ng is not None and ng.get(PARTIAL))


def set_windows(lights, windows, grow=False):
    """Set the windows (``footprint.py``) the fog's compositor groups crop to: ``windows`` = (the surfaces'
    window, [each light's glow window or None]), ``lights`` in the order of ``build_fog_group``'s; ``grow``:
    each the union of the one it had and the new one.  Only values change: a light built without a window
    keeps none (the whole picture)."""
    surface_window, glows = windows
    fog = bpy.data.node_groups.get(FOG_GROUP)
    changed = _set(fog, "Surface", surface_window, grow)
    for first in range(0, len(lights), BUNDLE_SIZE):
        bundle = bpy.data.node_groups.get(comp_bundles.bundle_name(first, min(BUNDLE_SIZE, len(lights) - first)))
        for k, win in enumerate(glows[first:first + BUNDLE_SIZE], start=first):
            if win is not None:
                changed = _set(bundle, k, win, grow) or changed
    if fog is not None and (not grow or changed) and bool(fog.get(PARTIAL)) != grow:
        fog[PARTIAL] = grow


def _set(ng, label, win, grow):
    """Set the window "<WINDOW> <label>" of ``ng`` (the union with the one it has if ``grow``); True if it changed."""
    key = f"{WINDOW} {label}"
    if ng is None or key not in ng:
        return False
    if grow:
        win = footprint.union(tuple(ng[key]), win)
    if tuple(ng[key]) == tuple(win):   # no needless update of the tree
        return False
    ng[key] = list(win)
    return True


def _params(m):
    """(beta 1/m, albedo) of the params group, driven (a density or colour change needs no rebuild)."""
    params = bpy.data.node_groups[groups.PARAMS]
    beta = comp_ops.driven_value(m, "Beta", "b", [("b", params, 'nodes["Beta"].outputs[0].default_value')])
    albedo = comp_ops.driven_vector(m, "Albedo", ["a"] * 3,
                                    lambda i: [("a", params, f'nodes["Albedo"].outputs[0].default_value[{i}]')])
    return beta, albedo


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
    return [comp_ops.driven_vector(m, f"Camera {label}", [e] * 3, axes)
            for label, e in (("corner", corner), ("across", f"{w}*a"), ("up", f"{h}*b"))]


def _picture_scale(m, scene, filter_path):
    """(w, h, 0): the picture's size in the filter table's pixels (``pixel.filter_scale``), driven by the
    render's resolution and percentage and the filter's width (``filter_path``: ``comp_lights.pixel_filter``'s;
    None: 0)."""
    r = [("rx", scene, "render.resolution_x"), ("ry", scene, "render.resolution_y"),
         ("pc", scene, "render.resolution_percentage"), ("fw", scene, filter_path or "cycles.filter_width")]
    k = f"pc/100*{pixel.DEFAULT_FILTER_WIDTH!r}/fw" if filter_path else "0"
    return comp_ops.driven_vector(m, "Picture Size", [f"rx*{k}", f"ry*{k}", "0"], r)


def build_fog_group(scene, lights, models, images, windows=None, partial=False, shafted=None, emitters=None,
                    day=None, layer=None, with_passes=False, mirrors=False, emitter_points=None):
    """(Re)build the compositor group ``FOG_GROUP``: Image (the render) and the AOVs in; Image (the render
    plus the fog's light) and Fog Light out, and with the fog passes (``with_passes``) Fog Transmittance: the
    materials' Fog Transmittance AOV (``passes.py``) times the factor the group puts on the render, so that
    Image = Fog Transmittance x (the surface as lit through the fog) + Fog Light, as the node groups' passes.  ``lights``: the fog's lights, ``models``: each light's
    rungs.LightModels; ``windows``: (the surfaces' window, [each light's glow window or None]) of
    ``footprint.py`` (``view.windows``), or None to evaluate every term over the whole picture; ``partial``:
    they do not hold the animation's range (``PARTIAL``); ``shafted``: ``comp_bundles.build_bundle``'s;
    ``emitters``: (the fog's g, Dense Fog's albedo or None) if glowing objects get their glows
    (``comp_emitters.glows``: an Emission input), else None; ``day``: a ``comp_daylight.Day`` for a fog layer with
    a sun or a sky (``daylight_terms.pixel_terms``; the render's surfaces take the sun's and the sky's dimming here, once
    per pixel, and the sky seen its transmittance), else None; ``layer``: a fog layer's (top, falloff, ground) in
    units (``FogSpec.layer_per_unit``), where the lights' glows end (``sunlight.lamp_glow_span``), or None for fog
    that fills all space; ``mirrors``: the materials shade the sharp mirrors' reflected fog (``glass_tails``: Cycles,
    where the scene has specular paths), so the pixels' glossy lobe leaves them out (``surface.sharp_share``);
    ``emitter_points``: (points (N, 3), intensities (N, 3)) the glowing objects are taken as
    (``methods.compositor.emitter_points``), whose fog light the surfaces reflect (``emitter_fog_light``) and whose
    glows far from them the pixels take (``emitter_far_glows``), or None.
    Rebuilt in place, so the scene's compositor keeps its group node.  Returns the table
    images it reads (``images`` and the pixel filter's and the emitters' weights)."""
    filt, peak = None if panoramic(scene) else comp_lights.pixel_filter(scene), None
    if filt is not None:
        peak, baker = pixel.filter_table(filt[0])
        images = dict(images, **{peak.name: images_.table_image(peak, baker)})
    if emitters is not None:
        images = dict(images, **comp_emitters.emitter_table(*emitters[:1], comp_emitters.emitter_pixel_angle(scene),
                                                            emitters[1]))
    eevee = scene.render.engine == budgets.EEVEE_ENGINE
    pano = panoramic(scene)
    inputs = ((("Image", "COLOR"),) + aovs(scene.render.engine, pano)
              + (((compositor.DEPTH, "VALUE"),) if eevee else ())
              + (((EMITTERS, "COLOR"),) if emitters is not None else ())
              + (((passes.TRANSMITTANCE, "VALUE"),) if with_passes else ()))
    outputs = ("Image", passes.FOG_LIGHT) + ((passes.TRANSMITTANCE,) if with_passes else ())
    ng = bpy.data.node_groups.get(FOG_GROUP)
    if ng is None:
        ng = bpy.data.node_groups.new(FOG_GROUP, "CompositorNodeTree")
        ng[groups.FOG_PROP] = True
    have = [(i.name, i.in_out) for i in ng.interface.items_tree if i.item_type == "SOCKET"]
    if ([s for s in have if s[1] == "INPUT"] != [(n, "INPUT") for n, _ in inputs]   # (Blender lists outputs first)
            or [s for s in have if s[1] == "OUTPUT"] != [(n, "OUTPUT") for n in outputs]):
        # new, or another engine's: its group nodes lose their links, and the chain links them anew
        ng.interface.clear()
        for name, kind in inputs:
            ng.interface.new_socket(name, in_out="INPUT", socket_type=C if kind == "COLOR" else F)
        for name in outputs:
            ng.interface.new_socket(name, in_out="OUTPUT", socket_type=C)
    ng.animation_data_clear()
    ng.nodes.clear()
    gin, gout = ng.nodes.new("NodeGroupInput"), ng.nodes.new("NodeGroupOutput")
    gout.location = (6000, 0)
    m = CompOps(ng, images)
    p = {s.name: m.wrap(s, vector=s.type == "RGBA") for s in gin.outputs if s.name}
    cover = p["Fog Coverage"]
    inv = 1.0 / m.maximum(cover, 1e-6)
    cam = comp_ops.driven_location(m, "Camera", scene.camera)
    beta, albedo = _params(m)
    coords = m.node("CompositorNodeImageCoordinates", 0)
    ng.links.new(gin.outputs["Image"], coords.inputs[0])
    uv = m.wrap(coords.outputs["Normalized"], vector=True)
    corner, across, up = camera_frame(m, scene)
    ray = corner + m.scale(across, m.dot(uv, (1.0, 0.0, 0.0))) + m.scale(up, m.dot(uv, (0.0, 1.0, 0.0)))
    if pano:   # the pixel's mean ray, as the camera traced it (``add_world_aovs``)
        ray = p[DIRECTION_AOV[0]]
        direction = m.scale(ray, 1.0 / m.maximum(m.length(ray), 1e-9))
    else:
        direction = m.scale(ray, 1.0 / m.length(ray))
    if eevee:   # ray is the pixel's ray at unit view depth
        pos = pixel.depth_surface(m, cam, ray, p[compositor.DEPTH], p["Fog Depth"] * inv)
    else:
        pos = m.scale(p["Fog Position"], inv)
    to_cam = cam - pos
    d_vp = m.length(to_cam)
    incoming = m.scale(to_cam, 1.0 / m.maximum(d_vp, 1e-9))
    summed = m.scale(p["Fog Normal"], 2.0) - m.scale(m.wrap((1.0, 1.0, 1.0)), cover)   # written as (1 + n) / 2
    normal = m.scale(summed, 1.0 / m.maximum(m.length(summed), 1e-9))
    size = _picture_scale(m, scene, filt and filt[1])
    pix = uv * size if peak is not None else m.wrap((0.0, 0.0, 0.0))
    roughness = p["Fog Roughness"] * inv
    diffuse, specular, level = surface.principled_to_phong(
        m, m.scale(p["Fog Base Color"], inv), p["Fog Metallic"] * inv, roughness,
        p["Fog Specular IOR Level"] * inv, m.dot(incoming, normal), transmission=p["Fog Transmission Weight"] * inv)
    if mirrors:   # a sharp mirror's reflected fog is the materials' tails' (``glass_tails.place_tails``)
        specular = m.scale(specular, 1.0 - surface.sharp_share(m, roughness))
    shared = {"Beta": beta, "Camera": cam, "Incoming": incoming, "View Distance": d_vp, "Direction": direction,
              "Pixel": pix, "Corner": corner, "Across": across, "Up": up, "Size": size, "Glow Origin": cam,
              "Glow Length": d_vp}
    if layer is not None:   # the lights' glows over the part of the ray in the layer: from where it enters, to where it
        # leaves or meets the surface; a pixel that sees mostly sky takes the sky's (one evaluation a pixel)
        t0, t1 = sunlight.lamp_glow_span(m, sunlight.lamp_glow_top(*layer), cam, direction)
        bounded, meets = m.less(t1, LAYER_OPEN), m.less(t0, LAYER_OPEN)
        shared["Glow Origin"] = cam + m.scale(direction, m.minimum(t0, LAYER_OPEN))
        to_surface = m.maximum(m.minimum(t1, d_vp) - t0, 0.0)
        shared["Glow Length"] = m.select(m.less(0.5, cover), to_surface, m.select(bounded, t1 - t0, model.FAR))
    surface_in = {"Position": pos, "Incoming": incoming, "Normal": normal, "Diffuse": diffuse, "Specular": specular,
                  "Level": level}
    pixel_xy = m.wrap(coords.outputs["Pixel"], vector=True)
    px, py = m.dot(pixel_xy, (1.0, 0.0, 0.0)), m.dot(pixel_xy, (0.0, 1.0, 0.0))
    surface_offset = surface_in["Offset"] = shafts.surface_offset(m, px, py)
    win = None if windows is None else comp_ops.window_crop(m, scene, "Surface", windows[0])
    if win is not None:   # the fog light on surfaces: only where the picture has surfaces
        surface_in = {k: comp_ops.crop(m, v, win) for k, v in surface_in.items()}
    shared.update({SURFACE + k: v for k, v in surface_in.items()})
    if shafted:   # the surface share at a coarser resolution
        xy = (px, py) if win is None else (m.dot(comp_ops.crop(m, pixel_xy, win), axis)
                                           for axis in ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0)))
        shared.update(comp_shafts.halved(m, scene, shared[SURFACE + "Position"], shared[SURFACE + "Normal"], *xy, cam,
                                         (px, py)))
    shared[HALO_STEP] = (comp_halos.coarse_step(m, scene) if any(rungs.split_halo(mod) is not None for mod in models)
                         else m.wrap(1.0))
    shared["Shaft Length"] = m.select(m.less(1e-3, cover), d_vp, SKY_LENGTH)
    shared["Shaft Offset"] = shafts.offset(m, px, py)
    sums = {}   # Output -> the sum over the bundles (over sets of bundles where there are many lights)
    step, build = ((BUNDLE_SIZE, comp_bundles.build_bundle) if len(lights) <= BUNDLE_SIZE * comp_bundles.SET_SIZE
                   else (BUNDLE_SIZE * comp_bundles.SET_SIZE, comp_bundles.build_bundle_set))
    for first in range(0, len(lights), step):
        node = m.node("CompositorNodeGroup", 5)
        node.node_tree = build(scene, first, lights[first:first + step], models[first:first + step], images, peak,
                               None if windows is None else windows[1][first:first + step], shafted,
                               layered=layer is not None)
        for name, v in shared.items():
            m.feed(node.inputs[name], v)
        sums = comp_ops.in_step(m, sums, {o: m.wrap(node.outputs[o.compositor], vector=True)
                                          for o in rungs.COMPOSITOR_OUTPUTS})
    if win is not None:   # the sums over the surfaces' window back in place, on the picture's domain
        sums.update({o: comp_ops.accumulate(m, comp_ops.zero(m, direction), comp_ops.uncrop(m, sums[o], win))
                     for o in SCATTER_OUTPUTS if o in sums})
    terms = compose.output_terms(sums)   # the lamps' glows and fog light, summed over the bundles
    if layer is not None and rungs.BACKGROUND_OUT in sums:   # a ray that leaves the layer: its glow ends at the top
        terms += [compose.Term(compose.LAYER_END, compose.SKY, compose.LAMPS, bounded),
                  compose.Term(compose.SHARE, compose.SKY, compose.LAMPS, meets)]
    daylight = None if day is None else day.build(m, beta, albedo)
    t_day = None if daylight is None else sunlight.view_transmittance(m, daylight, pos, incoming, d_vp)
    if rungs.SCATTERED_OUT in sums:   # the lamps' fog light on surfaces, dimmed on its way by one grey factor
        t_vp = model.transmittance(m, beta, d_vp) if daylight is None else sunlight.grey(m, t_day)
        terms.append(compose.Term(compose.DIMMING, compose.SURFACE, compose.LAMPS, t_vp))
    if daylight is not None:
        sun_share = surface_share = None
        if day.sun_shadow is not None and layer is not None:   # the sun's shafts
            sun_share, surface_share = comp_daylight.sun_shares(
                m, day.sun_shadow, day.sun_nodes, daylight, cam, direction, layer,
                m.select(m.less(0.5, cover), d_vp, model.FAR), beta, pos, normal,
                (shared["Shaft Offset"], surface_offset), shared["Shaft Length"])
        terms += daylight_terms.pixel_terms(m, daylight, day.table, cam, direction, pos, normal, diffuse + specular, d_vp,
                                      t_day, cover, sun_share, surface_share)
    if emitters is not None:
        facing_normal = m.scale(normal, m.select(m.less(m.dot(normal, incoming), 0.0), -1.0, 1.0))
        image_x, image_y = (m.scale(v, 1.0 / m.length(v)) for v in (across, up))
        lean = m.combine(m.dot(facing_normal, image_x), m.dot(facing_normal, image_y), 0.0)
        lean = m.scale(lean, 1.0 / m.maximum(m.length(lean), 1e-6))
        pixel_angle = comp_emitters.emitter_pixel_angle(scene)
        terms.append(compose.Term(compose.GLOW, compose.RAY, compose.EMITTERS, comp_emitters.glows(
            m, p, beta, d_vp, emitters[0], pixel_angle, emitters[1], cover, m.abs(m.dot(normal, incoming)), lean)))
        values = emitter_point_values(m, emitter_points) if emitter_points is not None else []
        if values:   # the glows far from them, which the ladder leaves out, and their fog light on surfaces
            far = emitter_far_glows(m, shared, values, emitters[0], emitters[1], images, pixel_angle)
            terms += [compose.Term(compose.GLOW, at, compose.EMITTERS, v) for at, v in far.items()]
            light = emitter_fog_light(m, shared, values, emitters[0], images, p[EMITTERS], win, direction)
            t_vp = model.transmittance(m, beta, d_vp) if daylight is None else sunlight.grey(m, t_day)
            terms += [compose.Term(compose.REFLECTED, compose.SURFACE, compose.EMITTERS, light),
                      compose.Term(compose.DIMMING, compose.SURFACE, compose.EMITTERS, t_vp)]
    if daylight is not None:   # the dimming of the pixel's surface by the fog above it and of the sky seen through
        one = 1.0 if daylight.air is None else m.wrap((1.0, 1.0, 1.0))   # (with air the dimming is RGB)
        sun_visible = (None if sun_share is None else   # the sun's map: a surface in its shadow takes the sky's factor
                       sun_shafts.sun_surface_lit(m, day.sun_shadow.spec, day.sun_shadow.frame, pos, normal))
        # the materials dimmed their samples by a grey stand-in (``sunlight.proxy_transmittance``): the camera
        # segment's exact transmittance (with air its colour) comes here, per pixel
        inv = 1.0 / m.maximum(sunlight.proxy_transmittance(m, daylight, d_vp), 1e-30)
        tint = t_day * inv if daylight.air is None else m.scale(t_day, inv)
        terms.append(compose.Term(compose.DIMMING, compose.SURFACE, compose.RENDER, tint))
        if day.dims:   # the layer's dimming of the sun's and the sky's direct light
            terms.append(compose.Term(compose.DIMMING, compose.SURFACE, compose.RENDER, m.select(
                m.less(0.0, cover), sunlight.direct_dimming(m, daylight, pos, normal, sun_visible), one)))
        terms.append(compose.Term(compose.DIMMING, compose.SKY, compose.RENDER,
                                  sunlight.sky_seen(m, daylight, cam, direction)))
    # Eq. 19 where the pixel sees its surface, Eq. 12 where it sees the sky
    fog, factor = compose.compose(m, compose.Pixel(cover, albedo), terms)
    fog = m.wrap((0.0, 0.0, 0.0)) if fog is None else fog
    m.feed(gout.inputs[passes.FOG_LIGHT], fog)
    if with_passes:
        t = p[passes.TRANSMITTANCE]
        m.feed(gout.inputs[passes.TRANSMITTANCE], compose.dimmed(m, m.combine(t, t, t), factor))
    m.place()
    m.feed(gout.inputs["Image"], fog + compose.dimmed(m, p["Image"], factor))
    ng[PARTIAL] = partial
    ng[owned.BUILT] = groups.code_fingerprint()
    return images


EMITTER_POINT = "Emitter Point"   # the nodes of the glowing objects' points: "<EMITTER_POINT> k Light" / "Intensity"


def emitter_point_values(m, points):
    """[(position, intensity)] of the glowing objects' points (``points``: (positions, intensities),
    ``methods.compositor.emitter_points``), each a value node of the fog group (``EMITTER_POINT``) whose constants
    are set here and by ``set_emitter_points``; their fog light on surfaces (``emitter_fog_light``) and their far
    glows (``emitter_far_glows``) read them."""
    values = []
    for k, (centre, intensity) in enumerate(zip(*points)):
        pair = []
        for name, value in (("Light", centre), ("Intensity", intensity)):
            value_node = m.node("ShaderNodeCombineXYZ", 6)
            value_node.name = value_node.label = f"{EMITTER_POINT} {k} {name}"
            for c in range(3):
                value_node.inputs[c].default_value = float(value[c])
            pair.append(m.wrap(value_node.outputs[0], vector=True))
        values.append(tuple(pair))
    return values


def emitter_fog_light(m, shared, values, g, images, emission, win, domain):
    """The fog light the pixel's surface reflects of the glowing objects (RGB per unit albedo, Sun et al. 2005 Eq.
    17-18), each taken as point sources along it (``values``: ``emitter_point_values``) through the point lights'
    scatter group (``comp_lights``: single scattering, no shadows), summed over the surfaces' window ``win`` (or the
    picture) and put back on the picture (``domain``: a value of its size); none on a glowing pixel itself
    (``emission``, the Emission pass: the point lies inside its own surface)."""
    models = rungs.choose("nodes", 0, g, "point")
    total = None
    for k, (light, intensity) in enumerate(values):
        node = m.node("CompositorNodeGroup", 7)
        node.node_tree = comp_lights.build_scatter_group(models, images)
        node.label = f"{EMITTER_POINT} {k} Scatter"
        for socket, _ in comp_lights.SURFACE_SHARED:   # (the per-pixel ones cropped to the surfaces' window)
            per_pixel = socket in comp_lights.SURFACE_IMAGES
            m.feed(node.inputs[socket], shared[SURFACE + socket if per_pixel else socket])
        m.feed(node.inputs["Light"], light)
        m.feed(node.inputs["Intensity"], intensity)
        v = m.wrap(node.outputs[rungs.SCATTERED_OUT.compositor], vector=True)
        total = v if total is None else comp_ops.accumulate(m, total, v)
    if win is not None:
        total = comp_ops.accumulate(m, comp_ops.zero(m, domain), comp_ops.uncrop(m, total, win))
    glowing = m.less(1e-30, m.dot(emission, (1.0, 1.0, 1.0)))
    return m.scale(total, 1.0 - glowing)


def emitter_far_glows(m, shared, values, g, multiple_albedo, images, pixel_angle):
    """The glowing objects' glows far from them (RGB per unit albedo: {rungs place: value}, the glow to the
    pixel's surface and to the sky): each point of ``values`` (``emitter_point_values``) as a point light times the
    far window of its angle off the pixel's ray (``comp_lights.build_glow_group``'s far one: Sun et al. 2005 Eq. 11 to
    the surface, Eq. 12 to the sky; with Dense Fog's field where ``multiple_albedo`` is given): the part of the
    glow kernel the ladder of blurs leaves out (``comp_emitters.glows`` blurs the near part,
    ``emitter_glow.far_window``)."""
    models = rungs.choose("nodes", 0, g, "point", multiple_albedo=multiple_albedo)
    totals = {}
    for k, (light, intensity) in enumerate(values):
        node = m.node("CompositorNodeGroup", 7)
        node.node_tree = comp_lights.build_glow_group(models, images, None, far_from=pixel_angle)
        node.label = f"{EMITTER_POINT} {k} Far Glow"
        for socket, _ in comp_lights.GLOW_SHARED:
            m.feed(node.inputs[socket], shared[socket])
        m.feed(node.inputs["Light"], light)
        m.feed(node.inputs["Intensity"], intensity)
        for o in comp_lights.GLOW_OUTPUTS:
            v = m.wrap(node.outputs[o.compositor], vector=True)
            totals[o.at] = v if o.at not in totals else comp_ops.accumulate(m, totals[o.at], v)
    return totals


def set_emitter_points(points):
    """Set the glowing objects' points' constants in the fog group (``emitter_fog_light``) to ``points``:
    (positions, intensities), as many as it holds (a new count rebuilds the group: the build's signature names the
    objects and their pieces)."""
    ng = bpy.data.node_groups.get(FOG_GROUP)
    if ng is None or points is None:
        return
    for k, (centre, intensity) in enumerate(zip(*points)):
        for name, value in (("Light", centre), ("Intensity", intensity)):
            node = ng.nodes.get(f"{EMITTER_POINT} {k} {name}")
            if node is not None:
                for c in range(3):
                    if node.inputs[c].default_value != float(value[c]):
                        node.inputs[c].default_value = float(value[c])
