"""The sun and the sky of a scene, as a layered fog's daylight takes them (``precompute/physics/daylight/sunlight.py``).

A fog with a top (``FogSpec.fog_top``) lets the sun and the sky through: the sun is the scene's brightest Sun
light (its direction and Strength x Color, W/m^2, followed by drivers), the sky the World's colour over the upper
hemisphere (a Background node's Color x Strength, driven; any other World is rendered once, small, and taken as
its mean over the upper hemisphere: ``probe_sky``).  ``daylight(m, ...)`` builds the ``sunlight.Daylight`` value
in a node tree of any backend (shader groups, the compositor's group), ``fog_light_table`` the fog light's baked
irradiance map, and ``notes`` says what the daylight leaves out.
"""
import functools
import hashlib
import math

import bpy
import numpy as np

from .nodes import comp_ops
from .precompute.core.ops import NumpyOps
from .precompute.model import bakers, daylight_terms
from .precompute.physics.daylight import daylight_tables, sunlight

SUN_KEY_DIGITS = 4   # the sun's direction enters the built groups' signature at this precision (the map is baked)


def scene_suns(scene):
    """The scene's Sun lights that render and shine (Fog Glow on, strength > 0), brightest first."""
    suns = []
    for obj in scene.objects:
        if obj.type != "LIGHT" or obj.data.type != "SUN" or obj.hide_render:
            continue
        settings = getattr(obj.data, "analytic_fog", None)
        if settings is not None and not settings.use:
            continue
        if obj.data.energy > 0.0 and any(c > 0.0 for c in obj.data.color):
            suns.append(obj)
    return sorted(suns, key=lambda o: -o.data.energy * sum(o.data.color))


def sun_direction(obj):
    """Unit vector towards the sun of Sun light ``obj`` (its local +Z: a Sun light shines along its -Z)."""
    z = obj.matrix_world.to_3x3().col[2]
    return tuple(float(c) for c in z.normalized())


def _background(world):
    """The World's Background node feeding its output's Surface, or None."""
    if world is None or not world.use_nodes or world.node_tree is None:
        return None
    out = next((n for n in world.node_tree.nodes if n.type == "OUTPUT_WORLD" and n.is_active_output), None)
    if out is None or not out.inputs["Surface"].is_linked:
        return None
    node = out.inputs["Surface"].links[0].from_node
    return node if node.type == "BACKGROUND" else None


def uniform_sky(world):
    """The World's Background node if its colour and strength are plain values (the sky the kernels model),
    else None."""
    bg = _background(world)
    if bg is None or bg.inputs["Color"].is_linked or bg.inputs["Strength"].is_linked:
        return None
    return bg


PROBE_KEY = "analytic_fog_sky_probe"   # on a World: {"fingerprint": of its nodes, "colour": ``probe_sky``'s}
PROBE_SIZE = (daylight_tables.SKY_COLUMNS, 256)   # px of the equirectangular probe render (0.7 degrees a row)
PROBE_SAMPLES = 16


def _tree_fingerprint(world):
    """A string that changes when the World's own nodes, links or input values change (the fog's are left out)."""
    from .nodes import owned
    parts = []
    for node in sorted((n for n in world.node_tree.nodes if not owned.is_ours(n)), key=lambda n: n.name):
        values = []
        for sock in node.inputs:
            v = getattr(sock, "default_value", None)
            values.append(repr(tuple(v) if hasattr(v, "__len__") and not isinstance(v, str) else v))
        image = getattr(node, "image", None)
        parts.append(f"{node.bl_idname}:{node.name}:{','.join(values)}:{image.name_full if image else ''}")
    parts += [f"{l.from_node.name}.{l.from_socket.identifier}>{l.to_node.name}.{l.to_socket.identifier}"
              for l in world.node_tree.links if not (owned.is_ours(l.from_node) or owned.is_ours(l.to_node))]
    return "|".join(parts)


PROBE_VERSION = "probe 3|"   # in the probe's fingerprint: probes kept by an older way of probing are made again


def _sky_textures(world):
    """The World's own Sky Texture nodes (not the fog's)."""
    if world is None or not world.use_nodes or world.node_tree is None:
        return []
    from .nodes import owned
    return [n for n in world.node_tree.nodes if n.bl_idname == "ShaderNodeTexSky" and not owned.is_ours(n)]


def sun_discs(world):
    """The World's Sky Texture nodes that draw a sun disc."""
    return [n for n in _sky_textures(world) if getattr(n, "sun_disc", False)]


def probe_sky(world):
    """The mean radiance of ``world`` over the upper hemisphere (RGB, W/(m^2 sr), solid-angle weighted), from a
    small equirectangular Cycles render of the World alone as its user made it (any World: a Sky Texture, an HDRI,
    node set-ups; a fogged World is rendered from a copy without the fog's nodes), kept on the World with its own
    nodes' fingerprint so it is rendered again only when they change; None if it can't be rendered now (during a
    render).  A Sky Texture's sun disc is left out (a copy renders with it off): it is a sun, ten times the sky's
    mean at 40 degrees, and the fog's sun is the scene's Sun light (docs/measurements/2026-11-27-sky-texture.md)."""
    fingerprint = _probe_fingerprint(world)
    kept = world.get(PROBE_KEY)
    if kept is not None and kept.get("fingerprint") == fingerprint:
        return tuple(float(c) for c in kept["colour"])
    if bpy.app.is_job_running("RENDER"):
        return None
    pixels = _probe_pixels(world, fingerprint)
    h = pixels.shape[0]
    elevation = (0.5 - (np.arange(h) + 0.5) / h) * math.pi      # row 0 at the top (+90 degrees)
    weight = np.where(elevation > 0.0, np.cos(elevation), 0.0)[:, None]
    mean = (pixels * weight[..., None]).sum(axis=(0, 1)) / (weight.sum() * pixels.shape[1])
    world[PROBE_KEY] = {"fingerprint": fingerprint, "colour": [float(c) for c in mean]}
    return tuple(float(c) for c in mean)


def _probe_fingerprint(world):
    return hashlib.sha1((PROBE_VERSION + _tree_fingerprint(world)).encode()).hexdigest()


_PROBED = {}   # fingerprint -> the probe's pixels, this process (the mean and the World's table share one render)


def _probe_pixels(world, fingerprint):
    """The World's equirectangular probe (``_render_equirect``), its Sky Textures' sun discs off and the fog's own
    nodes left out (a copy)."""
    from .nodes import owned
    if fingerprint in _PROBED:
        return _PROBED[fingerprint]
    probe = world
    if owned.is_fogged(world) or sun_discs(world):
        probe = world.copy()
        for node in [n for n in probe.node_tree.nodes if owned.is_ours(n)]:
            probe.node_tree.nodes.remove(node)
        outputs = [n for n in probe.node_tree.nodes if n.type == "OUTPUT_WORLD"]
        if outputs:
            outputs[0].is_active_output = True
        for node in sun_discs(probe):   # a Sky Texture's sun is a sun, not sky: its disc is left out of the mean
            node.sun_disc = False
    try:
        pixels = _render_equirect(probe)
    finally:
        if probe is not world:
            bpy.data.worlds.remove(probe)
    _PROBED.clear()
    _PROBED[fingerprint] = pixels
    return pixels


def holds_air(world):
    """Whether the World is a sky seen through its own air: a Sky Texture (of any sky type) that feeds something."""
    return any(any(o.is_linked for o in n.outputs) for n in _sky_textures(world))


def world_sky_spec():
    """The TableSpec of the World's radiance table (``world_sky_table``)."""
    return daylight_tables.sky_spec()


def world_sky_table(scene, spec):
    """(TableSpec, {name: image}) of the World's radiance over the upper hemisphere (``sunlight.world_radiance``:
    SKY_ROWS elevations x SKY_COLUMNS azimuths from the probe, sun discs off) where the fog has Air and the World
    holds its own (``holds_air``), re-baked in place when the World's nodes change; else (None, {})."""
    from .nodes import images as images_
    world = scene.world
    if spec.air_per_unit() is None or not is_daylit(scene, spec) or not holds_air(world):
        return None, {}
    table = world_sky_spec()
    fingerprint = _probe_fingerprint(world)

    def bake():
        return daylight_tables.sky_table_from_probe(_probe_pixels(world, fingerprint))
    if bpy.app.is_job_running("RENDER") and bpy.data.images.get(table.name) is None:
        return None, {}
    return table, {table.name: images_.keyed_image(table, fingerprint, bake)}


def _render_equirect(world):
    """(h, w, 3) linear RGB of ``world`` seen by an equirectangular camera looking along +Y, +Z up (PROBE_SIZE,
    PROBE_SAMPLES, Cycles CPU), in a scene of its own that is removed afterwards."""
    import os
    import tempfile

    from . import imageio
    scene = bpy.data.scenes.new("AnalyticFog Sky Probe")
    cam_data = bpy.data.cameras.new("AnalyticFog Sky Probe")
    cam = bpy.data.objects.new("AnalyticFog Sky Probe", cam_data)
    path = os.path.join(tempfile.mkdtemp(prefix="analytic_fog_sky_"), "sky.exr")
    try:
        cam_data.type = "PANO"
        cam_data.panorama_type = "EQUIRECTANGULAR"
        cam.rotation_euler = (math.pi / 2.0, 0.0, 0.0)
        scene.collection.objects.link(cam)
        scene.camera = cam
        scene.world = world
        r = scene.render
        r.engine = "CYCLES"
        r.resolution_x, r.resolution_y = PROBE_SIZE
        r.resolution_percentage = 100
        r.image_settings.file_format = "OPEN_EXR"
        r.filepath = path
        scene.cycles.samples = PROBE_SAMPLES
        scene.cycles.device = "CPU"
        bpy.ops.render.render(write_still=True, scene=scene.name)
        return imageio.read_rgb(path)[..., :3]
    finally:
        bpy.data.scenes.remove(scene)
        bpy.data.objects.remove(cam)
        bpy.data.cameras.remove(cam_data)
        if os.path.exists(path):
            os.remove(path)


def sky_colour(world):
    """(RGB radiance over the upper hemisphere, W/(m^2 sr), exact): the Background's Color x Strength for a
    uniform World (exact: the kernels' sky); for any other, its mean over the upper hemisphere (``probe_sky``;
    not exact: the fog's sky glow takes it as uniform); black without a World."""
    if world is None:
        return (0.0, 0.0, 0.0), True
    if not world.use_nodes or world.node_tree is None:
        return tuple(float(c) for c in world.color), True
    bg = uniform_sky(world)
    if bg is None:
        probe = probe_sky(world)
        return (probe if probe is not None else (0.0, 0.0, 0.0)), False
    s = float(bg.inputs["Strength"].default_value)
    return tuple(float(c) * s for c in bg.inputs["Color"].default_value[:3]), True


def is_daylit(scene, spec):
    """The fog has a top and something shines through it: a sun, or a World that is not black."""
    if not spec.layered:
        return False
    return bool(scene_suns(scene)) or any(c > 0.0 for c in sky_colour(scene.world)[0])


def dims_surfaces(scene, lamps):
    """Whether the sun's and the sky's dimming goes on surfaces (``sunlight.direct_dimming``): with a sun, or with
    no lamps.  The one factor takes the user's whole shading, so at night (no sun) it would dim the lamps' light
    on surfaces by the sky's share: then the sky's light on surfaces is left undimmed (noted)."""
    return bool(scene_suns(scene)) or not lamps


def key(scene, spec):
    """What the built groups depend on: the layer and the density (the fog light's map is baked for them), the
    sun's name and direction, the sky's source."""
    if not spec.layered:
        return "daylight:none"
    suns = scene_suns(scene)
    sun = (f"{suns[0].name_full}:" + ",".join(f"{c:.{SUN_KEY_DIGITS}f}" for c in sun_direction(suns[0]))
           if suns else "none")
    world = scene.world
    sky = "uniform" if uniform_sky(world) is not None else ("none" if world is None else "other")
    top, falloff, ground = spec.layer_per_unit()
    return (f"daylight:{spec.beta_per_unit!r}:{top!r}:{falloff!r}:{ground!r}:{spec.anisotropy!r}:{spec.air!r}:{sun}:"
            f"{sky}:glow table {uses_glow_table(scene, spec)}:"
            f"{world.name_full if world else ''}")


def fog_light_table(scene, spec):
    """(TableSpec, {name: image}) of the fog light's irradiance map (``daylight_tables.bake_fog_light``) for the scene's
    sun (straight up without one: its irradiance is 0 then) and the spec's layer (with air a tuple of three, one
    per colour channel); (None, {}) where the layer has no daylight (``is_daylit``)."""
    from .nodes import images as images_
    table = fog_light_spec(scene, spec)
    if table is None:
        return None, {}
    images = dict(glow_table(scene, spec)[1])        # (the glow's table with the maps: ``daylight`` reads it)
    images.update(world_sky_table(scene, spec)[1])   # (and the World's own sky, where it holds its air)
    images.update({t.name: images_.table_image(t)    # (their kind's baker, through the disk cache)
                   for t in (table if isinstance(table, tuple) else (table,))})
    return table, images


def fog_light_spec(scene, spec):
    """``fog_light_table``'s TableSpec (with air a tuple of three, one map per colour channel, both species' light
    and the albedos in it), or None where the layer has no daylight."""
    if not is_daylit(scene, spec):
        return None
    top, falloff, _ = spec.layer_per_unit()
    suns = scene_suns(scene)
    direction = tuple(round(c, SUN_KEY_DIGITS) for c in (sun_direction(suns[0]) if suns else (0.0, 0.0, 1.0)))
    air = spec.air_per_unit()
    channels = [None] if air is None else [(b, air[1], a) for b, a in zip(air[0], spec.albedo)]
    tables_ = [daylight_tables.table_spec(spec.beta_per_unit, top, falloff, direction, spec.anisotropy, c)
               for c in channels]
    return tables_[0] if air is None else tuple(tables_)


def sampled_fog(scene, spec, samples):
    """(P, 3) W/(m^2 sr): the fog layer's sun and sky fog light at the view ``samples`` (``predict.ViewSamples``)
    before the fog's albedo, as a pixel composes it (``daylight_terms.sampled_light``; the sun unshadowed, the World
    taken as the light above the air), or None where nothing shines through a layer (``is_daylit``): the part of
    each sample's fog the lamps' ladder never leaves out (``ViewSamples.other``)."""
    table = fog_light_spec(scene, spec)
    if table is None:
        return None
    m = NumpyOps({t.name: bakers.table_array(t) for t in (table if isinstance(table, tuple) else (table,))})
    day = daylight(m, scene, spec, spec.beta_per_unit)
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        light = daylight_terms.sampled_light(m, day, table, samples.camera,
                                             samples.direction, samples.distance, samples.normal,
                                             np.asarray(samples.rho_d) + np.asarray(samples.rho_s))
    return np.nan_to_num(np.asarray(light, float), nan=0.0, posinf=0.0)


def uses_glow_table(scene, spec):
    """Whether the sun's and the sky's glow along camera rays is read from a table baked for the camera's height
    (``sunlight.table_glow``: a few lookups a pixel instead of the kernels' thousands of nodes): in daylight, with
    a camera and a sun that are not animated (a frame of a farm's render would read another frame's table: those
    scenes keep the kernels, which follow every frame)."""
    from . import caveats
    if not is_daylit(scene, spec) or scene.camera is None or caveats.is_animated(scene.camera):
        return False
    suns = scene_suns(scene)
    return not (suns and caveats.is_animated(suns[0]))


def _glow_bake_args(scene, spec):
    """(beta, top, falloff, mu_s, g, camera height, air, air height) of ``daylight_tables.bake_glow_table`` for the
    scene now: units, the sun's elevation sine rounded as ``key`` rounds the sun's direction, straight up without a sun,
    and the camera's height to 6 significant digits (the image is re-baked when it changes)."""
    top, falloff, ground = spec.layer_per_unit()
    suns = scene_suns(scene)
    mu_s = round(sun_direction(suns[0])[2], SUN_KEY_DIGITS) if suns else 1.0
    height = float(f"{scene.camera.matrix_world.translation.z - ground:.6g}")
    air = spec.air_per_unit()
    return (spec.beta_per_unit, top, falloff, mu_s, spec.anisotropy, height,
            None if air is None else tuple(air[0]), 0.0 if air is None else air[1])


def glow_table(scene, spec):
    """(``daylight_tables.GlowTable``, {name: image}) of the scene's camera (``uses_glow_table``), or (None, {}): its
    image re-baked in place when the camera's height or the layer changed (``images.keyed_image``)."""
    from .nodes import images as images_
    if not uses_glow_table(scene, spec):
        return None, {}
    args = _glow_bake_args(scene, spec)
    table = daylight_tables.glow_table(args[0], args[6])
    image = images_.keyed_image(table.spec, repr(args), functools.partial(daylight_tables.bake_glow_table, *args))
    return table, {table.spec.name: image}


def refresh_glow_table(scene, spec):
    """Re-bake the glow table in place if the camera's height changed, and set the World group's copy of a uniform
    sky's radiance again (``refresh_world_sky``): the depsgraph handler's call, when nothing else needs a rebuild
    (nothing if the groups read no table)."""
    if bpy.data.images.get(daylight_tables.GLOW_NAME) is not None:
        glow_table(scene, spec)
    if spec.layered:
        refresh_world_sky(scene)


def sun_casts_shafts(scene, spec):
    """The Sun light whose shadows fall in the fog layer as shafts (``sun_shafts.sun_lit_share``), or None: the
    daylight's sun, with Light Shafts on and the sun casting shadows."""
    if not spec.shafts or not is_daylit(scene, spec) or scene.camera is None:
        return None
    suns = scene_suns(scene)
    if not suns or not getattr(suns[0].data, "use_shadow", True):
        return None
    return suns[0]


def shaft_region(scene, spec):
    """(8, 3) world corners of the box of fog layer the camera sees, where the sun's shafts are mapped: over the
    ground, up to the lamps' glow top (``sunlight.lamp_glow_top``), and across the part of the view frustum's corner
    and centre rays in the layer (``sunlight.lamp_glow_span``), each at most SUN_REACH mean free paths long."""
    from .precompute.physics.daylight import daylight as daylight_, sun_shafts
    from .precompute.core.ops import NumpyOps
    top, falloff, ground = spec.layer_per_unit()
    top_z = sunlight.lamp_glow_top(top, falloff, ground)
    cam = scene.camera
    eye = np.asarray(cam.matrix_world.translation, float)
    frame = [np.asarray(cam.matrix_world.to_3x3() @ v, float) for v in cam.data.view_frame(scene=scene)]
    rays = [v / np.linalg.norm(v) for v in frame + [sum(frame)]]
    reach = sun_shafts.SUN_REACH / max(spec.beta_per_unit, 1e-9)
    m = NumpyOps()
    points = [eye]
    for d in rays:
        t0, t1 = (float(t) for t in sunlight.lamp_glow_span(m, top_z, eye, d))
        if t0 >= daylight_.UNBOUNDED:
            continue
        points += [eye + d * t0, eye + d * min(t1, t0 + reach)]
    xy = np.array(points)[:, :2]
    lo, hi = np.maximum(xy.min(axis=0), eye[:2] - reach), np.minimum(xy.max(axis=0), eye[:2] + reach)
    return np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (ground, top_z)])


def sun_shadow(scene, spec, lazy=False):
    """(``sun_maps.SunShadow`` or None, {image name: image}): the sun's map over ``shaft_region`` when
    ``sun_casts_shafts``, baked unless its image holds it already (an atlas of an animation's frames where the
    camera or a caster moves; ``lazy``: a handler's rebuild, ``sun_maps.shadow``)."""
    from . import sun_maps
    sun = sun_casts_shafts(scene, spec)
    if sun is None:
        return None, {}
    shadow = sun_maps.shadow(scene, sun, lambda s: shaft_region(s, spec), lazy=lazy)
    if shadow is None:
        return None, {}
    return shadow, {sun_maps.SUN_IMAGE: bpy.data.images[sun_maps.SUN_IMAGE]}


def follow_sun(scene, spec):
    """The frame changed: the sun's atlas follows casters that moved otherwise than it was baked for
    (``sun_maps.follow_frame``)."""
    from . import sun_maps
    sun = sun_casts_shafts(scene, spec) if spec is not None else None
    if sun is not None and bpy.data.images.get(sun_maps.SUN_IMAGE) is not None:
        sun_maps.follow_frame(scene, sun, lambda s: shaft_region(s, spec))


def sun_atlas_due(scene, spec):
    """True if the sun's map should be an atlas of the animation's frames and is not one up to date
    (``sun_maps.atlas_due``): the file's save rebuilds the fog then."""
    from . import sun_maps
    return spec is not None and sun_maps.atlas_due(scene, sun_casts_shafts(scene, spec))


def builder(scene, spec):
    """The groups' ``day`` argument: ``daylight`` of this scene and spec as a function of (m, beta, albedo,
    in_world), or None for fog that fills all space (``in_world``: the tree is the World's group)."""
    if not spec.layered:
        return None
    return lambda m, beta, albedo=1.0, in_world=False: daylight(m, scene, spec, beta, albedo, in_world)


WORLD_SKY_LABEL = "Sky Radiance (World)"   # the World group's copy of a uniform sky's radiance (``_sky``)


def _uniform_radiance(bg):
    """A uniform sky's radiance: its Background's Color x Strength (RGB)."""
    s = float(bg.inputs["Strength"].default_value)
    return tuple(float(c) * s for c in bg.inputs["Color"].default_value[:3])


def _sky(m, scene, in_world):
    """The sky's radiance in the tree of ``m``: a uniform sky's driven by its World's Background (Color x
    Strength), except in the World's own group (``in_world``), which holds it as a value set from the Background
    (``refresh_world_sky``); any other World's mean (``sky_colour``), a value.

    Why not driven in the World's group: a driver reads a node's socket through its tree's output (Blender's
    depsgraph keys every socket of a tree to that tree's one NTREE_OUTPUT), and the World's tree's output waits
    for the fog's World group it holds: a driver there reading the World's Background closes a dependency cycle
    (Blender printed "Detected 6 dependency cycles" on every evaluation, and a driver in a cycle may read a value
    of the frame before).  So does every other way found for it to reach that group: a driver on the World's own
    tree, one reading through the World or the scene's world as a Context Property (tests/scenes/
    dependency_cycles.py measures them, ``probe``)."""
    world = scene.world
    bg = uniform_sky(world)
    if bg is None:
        return m.wrap(sky_colour(world)[0])
    if in_world:
        node = m.node("ShaderNodeCombineXYZ", 0)
        node.label = WORLD_SKY_LABEL
        for i, c in enumerate(_uniform_radiance(bg)):
            node.inputs[i].default_value = c
        return m.wrap(node.outputs[0], vector=True)
    path = f'nodes["{bg.name}"].inputs'
    return comp_ops.driven_vector(m, "Sky Radiance", ["c*s"] * 3,
                                  lambda i: [("c", world, f'node_tree.{path}["Color"].default_value[{i}]'),
                                             ("s", world, f'node_tree.{path}["Strength"].default_value')])


def background_animated(world):
    """Whether a uniform World's Background Color or Strength is animated or driven (the World group's copy of it,
    ``_sky``, is not: it is set when the fog is updated)."""
    bg = uniform_sky(world)
    ad = world.node_tree.animation_data if bg is not None else None
    if ad is None:
        return False
    from bpy_extras import anim_utils
    curves = list(ad.drivers)
    if ad.action is not None:
        bag = anim_utils.action_get_channelbag_for_slot(ad.action, ad.action_slot)
        curves += list(bag.fcurves) if bag is not None else []
    prefix = f'nodes["{bg.name}"].inputs'
    return any(fc.data_path.startswith(prefix) for fc in curves)


def refresh_world_sky(scene):
    """Set the World group's copy of a uniform sky's radiance (``_sky``) from the World's Background again, where it
    changed (nothing else: a value set is a tree update).  Returns True if a value changed."""
    from .nodes import groups
    ng = bpy.data.node_groups.get(groups.WORLD)
    bg = uniform_sky(scene.world)
    if ng is None or bg is None or ng.library is not None:
        return False
    radiance = [float(np.float32(c)) for c in _uniform_radiance(bg)]   # (as a socket stores it)
    changed = False
    for node in ng.nodes:
        if node.bl_idname == "ShaderNodeCombineXYZ" and node.label == WORLD_SKY_LABEL:
            for sock, c in zip(node.inputs, radiance):
                if sock.default_value != c:
                    sock.default_value = c
                    changed = True
    return changed


def daylight(m, scene, spec, beta, albedo=1.0, in_world=False):
    """The scene's ``sunlight.Daylight`` in the node tree of ``m`` (NodeOps or CompOps; NumpyOps: its values now,
    evaluated by the kernels, without the trees' tables): ``beta`` the tree's
    density socket (driven by the params group), the layer from ``spec``, the sun's direction and irradiance and a
    uniform sky's radiance driven by the Sun light and the World's Background (a change needs no rebuild; the sun's
    direction re-bakes the fog light's map at the next Update Fog).  ``in_world``: the tree is the World's group,
    whose sky is a value kept up to date by the add-on instead (``_sky``: a driver there would be a dependency
    cycle)."""
    top, falloff, ground = spec.layer_per_unit()
    suns = scene_suns(scene)
    values = isinstance(m, NumpyOps)   # the scene now, as values (``sampled_fog``): the kernels, RGB air
    if values:
        sun = suns[0] if suns else None
        direction = np.array(sun_direction(sun) if sun else (0.0, 0.0, 1.0))
        irradiance = np.array(sun.data.color) * sun.data.energy if sun else np.zeros(3)
    elif suns:
        sun = suns[0]
        direction = comp_ops.driven_vector(m, "Sun Direction", ["x"] * 3,
                                           lambda i: [("x", sun, f"matrix_world[2][{i}]")])
        direction = m.scale(direction, 1.0 / m.length(direction))
        irradiance = comp_ops.driven_vector(m, "Sun Irradiance", ["e*c"] * 3,
                                            lambda i: [("e", sun.data, "energy"), ("c", sun.data, f"color[{i}]")])
    else:
        direction, irradiance = m.wrap((0.0, 0.0, 1.0)), m.wrap((0.0, 0.0, 0.0))
    sky = np.array(sky_colour(scene.world)[0]) if values else _sky(m, scene, in_world)
    air = spec.air_per_unit()
    table = (daylight_tables.glow_table(spec.beta_per_unit, None if air is None else air[0])
             if uses_glow_table(scene, spec) and not values else None)
    world_sky = None
    if (air is not None and not values and holds_air(scene.world)
            and bpy.data.images.get(daylight_tables.SKY_TABLE) is not None):
        world_sky = world_sky_spec()   # (baked by ``fog_light_table`` with the groups' other tables)
    return sunlight.Daylight(beta, top, falloff, ground, direction, irradiance, sky, spec.anisotropy, albedo,
                             None if air is None else tuple(air[0]), 0.0 if air is None else air[1], table, world_sky,
                             grey_air=not (values or isinstance(m, comp_ops.CompOps)))
