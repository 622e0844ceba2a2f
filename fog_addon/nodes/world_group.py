"""The World group, ``AnalyticFog World``: ``shading.shade_background`` (Sun et al. 2005 Eq. 12) over the scene's
fog lights in bundles (``build_world_bundle``), the World seen through a fog layer where there is one."""
import functools

import bpy

from ..precompute.model import compose, daylight_terms, rungs, shading
from ..precompute.physics.daylight import sunlight
from . import (closures, drivers, groups, light_bundles, light_groups, passes, preview as preview_,
               preview_sampled, preview_shafts)
from .groups import C, F, V
from .sockets import NodeOps


def build_world_bundle(images, first, lights, models, with_passes, chained, scaled=False,
                       prefix=groups.WORLD_LIGHTS, shadows=None, g_=0.0, cycles=False):
    """One bundle of the World group (``light_bundles.split``): the lights' glows to infinity (Sun et al. 2005
    Eq. 12) from their per-light groups (``light_groups.build_background_light``).

    Outputs: Fog (one Background closure per light: its glow times the albedo on camera rays, times the input
    Scale with ``scaled``) and Airlight (the glows' sum).  ``with_passes``: Running Sum out is Running Sum in (``chained``; else
    nothing) plus the glows read by the pass's own instances of the light groups
    (``_world_pass_instances``).  ``prefix``: the bundles' name (the viewport preview's have their own).
    ``shadows``: {light name: ShadowMap} of the lights whose glows take their lit shares (the viewport's preview:
    ``preview_shafts.py``, fog of anisotropy ``g_``), or None.  ``cycles``: the light groups for Cycles alone
    (``light_groups.build_light``: the preview's, a rebuild follows a change of engine).
    """
    name = light_bundles.bundle_name(prefix, first, lights)
    inputs = [("Beta", F), ("Albedo", C), ("Camera", V), ("Direction", V), ("Is Camera", F)]
    inputs += [("Scale", F)] if scaled else []
    outputs = [("Fog", "NodeSocketShader"), ("Airlight", C)]
    if with_passes:
        running = (light_bundles.RUNNING, C)
        inputs, outputs = inputs + [("Pass Direction", V), running], outputs + [running]
    ng, gin, gout = groups.new_group(name, inputs, outputs)
    m = NodeOps(ng, {})
    g = {s.name: s for s in gin.outputs if s.name}
    medium, is_camera = light_groups.medium(m, g["Beta"], g["Albedo"]), m.wrap(g["Is Camera"])
    nodes, airlights, colours, jitter = [], [], [], None
    for k, (light, mod) in enumerate(zip(lights, models)):
        group = light_groups.build_background_light(mod, images, cycles).name
        node = light_groups.light_instance(ng, first + k, light, group,
                                           [(g[n], n) for n in ("Beta", "Camera", "Direction")])
        nodes.append(node)
        sky = light_groups.read(m, node, rungs.SKY_OUTPUTS, shading.SkyTerms)
        if shadows and light.name in shadows:   # the preview's shafts along the ray to the sky
            jitter = jitter or preview_shafts.jitter(ng, g["Direction"])
            sky = sky._replace(background=m.scale(m.wrap(sky.background, vector=True), _sky_share(
                m, ng, light, node, shadows[light.name], images, g, g_, jitter)))
        airlights.append(sky.background)
        colour = m.wrap(shading.shade_background(m, [airlights[-1]], medium, is_camera)[0], vector=True)
        if scaled:
            colour = m.scale(colour, m.wrap(g["Scale"]))
        gated = sky.seen is not None and not with_passes
        colours.append(shading.Gated(sky.seen, colour, None) if gated else colour)
    # why closures: ``surface_group.build_surface``
    closures.closure_sum(m, gout.inputs["Fog"], "ShaderNodeBackground", colours)
    m.feed(gout.inputs["Airlight"], shading.total(airlights))
    if with_passes:
        start = m.wrap(g[light_bundles.RUNNING], vector=True) if chained else None
        m.feed(gout.inputs[light_bundles.RUNNING],
               _world_pass_instances(m, ng, nodes, m.wrap(g["Pass Direction"]), start))
    m.place()
    return ng


def _sky_share(m, ng, light, node, shadow, images, g, anisotropy, jitter):
    """The lit share of ``light``'s glow (its group instance ``node``) along the ray to the sky
    (``preview_shafts.shares``), its nodes turned at each sample by ``jitter``."""
    shares = preview_shafts.shares(ng, light, shadow, images, anisotropy, {
        "Beta": g["Beta"], "Camera": g["Camera"], "Direction": g["Direction"], "Length": preview_shafts.SKY_LENGTH,
        "Light": node.inputs["Light"].links[0].from_socket, "Position": g["Camera"], "Normal": g["Direction"],
        "Jitter": jitter})
    return m.wrap(shares.outputs["Share"])


def build_world(lights, models, camera, images, with_passes=False, day=None, day_table=None, day_dims=True,
                preview=None, extra=None):
    """Scene group for the World: ``shading.shade_background`` (Sun et al. 2005 Eq. 12) over ``lights``.

    Camera position by TRANSFORMS drivers on ``camera`` (no node gives it in a
    world shader).  The background itself is seen through infinite fog:
    Transmittance is 0 (1 on rays other than the camera's if the params
    group's World Light is 1: they keep the world's lighting).  With a fog layer (``day``:
    ``surface_group.build_surface``'s) the World is seen through it on camera rays (``sunlight.sky_seen``) and
    lights surfaces on every other ray (the materials dim it: ``sunlight.direct_dimming``), and with ``day_table``
    camera rays get the sun's and the sky's glow to infinity (``sunlight.ray_glow``); ``day_dims`` False leaves the
    World untouched on every ray (the compositor dims the sky it sees: ``comp_fog.build_fog_group``).  The lights
    whose glow is on sit in bundle groups (``light_bundles.split``, ``build_world_bundle``).  ``preview``:
    ``preview.Shown``, the viewport's preview of a fog added at render time, their glows behind the Params group's Viewport
    Preview (``preview.behind_switch``), or None; where the World is left to the compositor (``day_dims`` False:
    the sky through a daylit layer) the preview also dims the sky and adds the sun's and the sky's glow
    (``preview.Shown.day_table``; ``preview.blend``), or shows nothing without it.  ``extra(group)``:
    adds nodes of its own (the Compositor method's AOVs with a panoramic camera, ``comp_fog.add_world_aovs``).
    """
    ng, gin, gout = groups.new_group(groups.WORLD, [],
                                     [("Fog", "NodeSocketShader"), ("Emission", C), ("Transmittance", F)])
    m = NodeOps(ng, images)   # (the daylight glow's table: ``sunlight.table_glow``)
    params = ng.nodes.new("ShaderNodeGroup")
    params.node_tree = bpy.data.node_groups[groups.PARAMS]
    geo = ng.nodes.new("ShaderNodeNewGeometry")
    path = ng.nodes.new("ShaderNodeLightPath")
    cam = drivers.vector_node(ng, "Camera Location", -600, 300)
    if camera is not None:
        drivers.drive_location(cam, camera)
    direction = m.vmath("NORMALIZE", m.wrap(geo.outputs["Position"]))
    shared = {"Beta": params.outputs["Beta"], "Albedo": params.outputs["Albedo"], "Camera": cam.outputs[0],
              "Direction": direction.sock, "Is Camera": path.outputs["Is Camera Ray"]}
    if with_passes:   # the pass's direction, given another way (``_world_pass_instances``)
        shared["Pass Direction"] = m.vmath("NORMALIZE", m.vmath("SCALE", m.wrap(geo.outputs["Incoming"]), -1.0)).sock
    kept = [(light, mod) for light, mod in zip(lights, models)
            if any(o.computed(mod) for o in rungs.SKY_OUTPUTS if o.colour)]
    medium = light_groups.medium(m, params.outputs["Beta"], params.outputs["Albedo"])
    is_camera = m.wrap(path.outputs["Is Camera Ray"])
    transmittance = shading.shade_background(m, [], medium, is_camera, m.wrap(params.outputs[groups.WORLD_LIGHT]))[1]
    day_glow, layer_scale, day_preview = None, None, None
    if day is not None and not day_dims:   # a World the compositor dims: the preview dims it, or shows nothing
        preview = preview if preview and preview.day_table is not None else None
        day_preview = preview.day_table if preview else None
    if day is not None:   # (``in_world``: no driver reads the World from its own group: a dependency cycle)
        daylight = day(m, m.wrap(params.outputs["Beta"]), m.wrap(params.outputs["Albedo"], vector=True),
                       in_world=True)
        camera_at = m.wrap(cam.outputs[0], vector=True)
        seen = sunlight.grey(m, sunlight.sky_seen(m, daylight, camera_at, direction))
        transmittance = 1.0 + is_camera * (seen - 1.0) if day_dims else m.const(1.0)
        if day_preview is not None:   # the sky through the layer where the preview shows (``preview.blend``)
            transmittance = preview_.blend(m, 1.0, 1.0 + is_camera * (seen - 1.0), preview_.factor(m, params))
        if day_table is not None or day_preview is not None:
            day_glow = m.scale(compose.source_light(m, 0.0, daylight_terms.sky_terms(m, daylight, camera_at, direction)),
                               is_camera)
        if kept or day_table is not None or preview:   # (the compositor's World: no glow, the sky dimmed per pixel)
            # The fogged World mixes the Fog closure by 1 - Transmittance (world.py), right where the sky is not
            # seen; through a layer it is, so every glow closure (each lamp's and the daylight's) is scaled by
            # 1 / (1 - Transmittance).  One closure a lamp, as without a layer: their sum in one closure's
            # colour would keep every lamp's values live at once, 15 floats a lamp on SVM's stack of 255
            # (docs/measurements/2026-11-29-shader-budgets.md).
            layer_scale = m.wrap(1.0 / m.maximum(1.0 - transmittance, 1e-6))
            shared["Scale"] = layer_scale.sock
    placed, bundles, running = light_bundles.place_bundles(
        ng, [light for light, _ in kept], [mod for _, mod in kept],
        functools.partial(build_world_bundle, images, scaled=layer_scale is not None), shared, with_passes)
    fogs = [node.outputs["Fog"] for node, _ in placed]
    if preview:
        shown, preview_trees, _ = light_bundles.place_bundles(
            ng, preview.lights, preview.models, functools.partial(
                build_world_bundle, images, scaled=layer_scale is not None, prefix=groups.WORLD_PREVIEW,
                shadows=preview.shadows, g_=preview.g, cycles=preview.cycles),
            {k: v for k, v in shared.items() if k != "Pass Direction"}, False)   # (the preview writes no pass)
        shaders = [node.outputs["Fog"] for node, _ in shown]
        if preview.sampled is not None and layer_scale is None:   # the other point lights, one sampled a sample
            shaders.append(preview_sampled.group_node(ng, preview_sampled.build_world_group(
                images, preview.sampled, preview.g, preview.sampled_dense, preview.cycles), shared))
        if day_preview is not None:   # the sun's and the sky's glow to the sky
            shaders.append(_emission(m, ng, m.scale(day_glow, layer_scale)))
        fogs += [sock for sock in [preview_.behind_switch(ng, params, shaders)] if sock]
    emission = shading.shade_background(
        m, [m.wrap(node.outputs["Airlight"], vector=True) for node, _ in placed], medium, is_camera)[0]
    if day_glow is not None and day_preview is None:
        emission = m.wrap(emission, vector=True) + day_glow
        fogs.append(_emission(m, ng, m.scale(day_glow, layer_scale)))
    m.feed(gout.inputs["Emission"], m.wrap(emission))
    closures.shader_tree(ng, gout.inputs["Fog"], fogs)
    m.feed(gout.inputs["Transmittance"], m.wrap(transmittance))
    if with_passes:
        light, _ = shading.shade_background(m, [] if running is None else [m.wrap(running, vector=True)], medium,
                                            is_camera)
        passes.write_group(m, ng, m.wrap(light, vector=True), m.wrap(transmittance))
    m.place()
    if extra is not None:
        extra(ng)
    ng = groups.install(ng, groups.WORLD)
    light_bundles.name_bundles(bundles + (preview_trees if preview else []))
    return ng


def _emission(m, ng, colour):
    """An Emission node of ``colour`` in ``ng``: its output."""
    emit = ng.nodes.new("ShaderNodeEmission")
    m.feed(emit.inputs["Color"], colour)
    return emit.outputs["Emission"]


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
    # direction plus an exact zero made from the running sum of lights 0..k-1 (``closures.exact_zero``): it
    # starts once the light before it is summed, and one light's values are kept at a time (the
    # World's peak: 33 floats at 4 to 64 lights, 71 at 4 before).
    for node in nodes:
        twin = ng.nodes.new("ShaderNodeGroup")
        twin.node_tree = node.node_tree
        twin.name = twin.label = f"{node.name} (passes)"
        twin.location = (node.location.x, node.location.y - 150)
        along = direction if total is None else m.vmath("ADD", direction, closures.exact_zero(m, total))
        for sock in node.inputs:
            src = along.sock if sock.name == "Direction" else (sock.links[0].from_socket if sock.is_linked
                                                                 else None)
            if src is not None:
                ng.links.new(src, twin.inputs[sock.name])
        airlight = m.wrap(twin.outputs[rungs.BACKGROUND_OUT.name], vector=True)
        total = airlight if total is None else total + airlight
    return total
