"""The Surface group, ``AnalyticFog Surface``, which every fogged material uses: ``shading.shade_surface`` (Sun et
al. 2005 Eq. 19) over the scene's fog lights in bundles (``build_surface_bundle``), with a fog layer's daylight
(``daylight_terms.surface_terms``, composed by ``compose.surface_light``) and the glows past glass and mirrors
(``glass_tails.py``)."""
import functools

import bpy

from ..precompute.model import compose, daylight_terms, rungs, shading
from ..precompute.physics.daylight import sunlight
from ..precompute.physics.point import surface
from . import (closures, glass_tails, groups, light_bundles, light_groups, passes, preview as preview_,
               preview_sampled, preview_shafts)
from .groups import C, F, V
from .sockets import NodeOps

_SURFACE_SHARED = (("Beta", F), ("Position", V), ("Incoming", V), ("View Distance", F), ("Normal", V),
                   ("Diffuse", C), ("Specular", C), ("Glossy Level", F))   # a light group's inputs but its own


def build_surface_bundle(images, first, lights, models, with_passes, chained, prefix=groups.SURFACE_LIGHTS,
                         shadows=None, g_=0.0, samples=None, chances=None, cycles=False):
    """One bundle of the Surface group (``light_bundles.split``): ``shading.sum_lights`` over ``lights``
    (Sun et al. 2005 Eq. 19's L_a) from their per-light groups (``light_groups.build_light``).

    ``shadows``: {light name: ShadowMap} of the lights whose glow and reflected fog light take their lit shares
    (the viewport's preview: ``preview_shafts.py``, fog of anisotropy ``g_``, ``samples`` nodes a sample), or None.
    ``chances``: every light's probability of being the one a sample takes (``closures.drawn``, by the Pick
    input; the surfaces past glass), or None: every light on every sample.  ``cycles``: the light groups for Cycles
    alone (``light_groups.build_light``: the preview's, a rebuild follows a change of engine).

    Outputs: Fog (one Emission closure per lit light, times the Opacity input; a spot's or an area light's
    glow a closure of its own, ``closures.closure_sum``), Emission (their colours' sum), Weighted and Weight
    (``shading.LightSums``).  ``with_passes``: Running Sum out is Running Sum in (``chained``; else nothing)
    plus this bundle's Fog Light (``closures.chained_closure_sum``); the glows are not gated then (the pass
    reads them: SVM computes them on every ray anyway), but stay closures of their own (``closure_sum``'s
    ``gates`` says why).
    """
    name = light_bundles.bundle_name(prefix, first, lights)   # (``prefix``: the viewport preview's have their own)
    inputs = [*_SURFACE_SHARED, ("Albedo", C), ("View Transmittance", F), ("Is Camera", F), (passes.OPACITY, C)]
    inputs += [("Pick", F)] if chances is not None else []
    outputs = [("Fog", "NodeSocketShader"), ("Emission", C), ("Weighted", F), ("Weight", F)]
    if with_passes:
        inputs, outputs = inputs + [(light_bundles.RUNNING, C)], outputs + [(light_bundles.RUNNING, C)]
    ng, gin, gout = groups.new_group(name, inputs, outputs)
    m = NodeOps(ng, {})
    g = {s.name: s for s in gin.outputs if s.name}
    terms, jitter = [], None
    for k, (light, mod) in enumerate(zip(lights, models)):
        shares = None
        if shadows and light.name in shadows:   # the preview's shafts (``preview_shafts.py``)
            jitter = jitter or preview_shafts.jitter(ng, g["Position"])
            shares = _shares(m, ng, light, shadows[light.name], images, g, jitter, g_, samples)
        node = light_groups.light_instance(ng, first + k, light, light_groups.build_light(mod, images, cycles).name,
                                           [(g[n], n) for n, _ in _SURFACE_SHARED])
        terms.append(light_groups.read(m, node, rungs.SURFACE_OUTPUTS, shading.LightTerms))
        if shares is not None:
            ng.links.new(node.inputs["Light"].links[0].from_socket, shares.inputs["Light"])
            terms[-1] = _shafted(m, terms[-1], shares)
    sums = shading.sum_lights(m, terms, light_groups.medium(m, g["Beta"], g["Albedo"]),
                              m.wrap(g["View Transmittance"]), m.wrap(g["Is Camera"]))
    opacity = m.wrap(g[passes.OPACITY], vector=True)
    colours = [_times(m, e, opacity) for e in sums.emissions]
    if chances is not None:
        colours = [closures.drawn(m, c, m.wrap(g["Pick"]), chances, first + k) for k, c in enumerate(colours)]
    closures.closure_sum(m, gout.inputs["Fog"], "ShaderNodeEmission", [c for c, mod in zip(colours, models)
                                                                        if _lit(mod)], gates=not with_passes)
    for sock, v in (("Emission", sums.emission), ("Weighted", sums.weighted), ("Weight", sums.weight)):
        m.feed(gout.inputs[sock], m.wrap(v))
    if with_passes:
        start = m.wrap(g[light_bundles.RUNNING], vector=True) if chained else None
        m.feed(gout.inputs[light_bundles.RUNNING], closures.chained_closure_sum(m, gout.inputs["Fog"], start))
    m.place()
    return ng


def build_surface(lights, models, images, with_passes=False, extra=None, tails=True, day=None, day_table=None,
                  day_dims=True, day_exact=True, preview=None, mirrors=False):
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
    past glass and mirrors (See Through, ``glass_tails.place_tails``), only where the scene has them
    (``caveats.specular_paths``): of ``lights`` with ``models``, or of the (lights, models) ``tails`` gives (the
    Compositor method's, whose materials hold no lights).  ``day(m, beta)``: the fog layer's ``sunlight.Daylight`` in this tree
    (``sunsky.daylight``), or None for fog that fills all space: the camera segment's transmittance is then the
    layer's, and the user's shader on every ray takes the sun's and the sky's dimming (``sunlight.direct_dimming``);
    with ``day_table`` (the fog light's TableSpec, its image in ``images``) camera rays also get the sun's and the
    sky's glow and their fog light on the surface (``daylight_terms.surface_terms``, composed); ``day_dims`` False leaves the sun's and the
    sky's dimming to the compositor (``comp_fog.build_fog_group``: once per pixel), ``day_exact`` False dims the
    camera segment by ``sunlight.proxy_transmittance`` (the compositor puts the exact colour on every pixel).  The
    lights sit in bundle groups (``light_bundles.split``, ``build_surface_bundle``).  ``preview``: ``preview.Shown``
    of the viewport's preview of a fog added at render time: their fog light on camera rays, behind the Params
    group's Viewport Preview (``preview.behind_switch``), or None; it changes no other output.  ``mirrors`` (Cycles,
    with ``tails``): a sharp mirror's reflected fog is its tails' (``glass_tails.place_tails``), exact, and its
    glossy lobe's fog light left out (``surface.sharp_share``).

    Why closures: Cycles' SVM emits a shader's value nodes in the order of
    their ids, so one colour summed over the lights keeps every light's values
    on its stack of 255 floats at once (out of SVM stack space, every fogged
    material black, at 4 lights), while each closure's inputs are compiled
    and released before the next closure's.
    """
    ng, gin, gout = groups.new_group(groups.SURFACE, [
        ("Base Color", C), ("Metallic", F), ("Roughness", F), ("Specular IOR Level", F), (passes.OPACITY, C),
        (glass_tails.GLASS_COLOR, C), (glass_tails.GLASS_IOR, F), (glass_tails.GLASS_WEIGHT, F),
        (glass_tails.GLASS_MIRRORED, F), ("Transmission Weight", F),
    ], [("Fog", "NodeSocketShader"), ("Emission", C), ("Transmittance", F), ("Direct Attenuation", F),
        ("Cycles Mix Factor", F), ("EEVEE Mix Factor", F), (glass_tails.SEE_THROUGH, "NodeSocketShader")])
    items = {i.name: i for i in ng.interface.items_tree if i.item_type == "SOCKET" and i.in_out == "INPUT"}
    items[passes.OPACITY].default_value = (1.0, 1.0, 1.0, 1.0)
    items[glass_tails.GLASS_COLOR].default_value = (0.0, 0.0, 0.0, 1.0)
    items[glass_tails.GLASS_IOR].default_value = 1.5
    items[glass_tails.GLASS_WEIGHT].default_value = 1.0
    items[glass_tails.GLASS_MIRRORED].default_value = 1.0
    m = NodeOps(ng, images)
    params = ng.nodes.new("ShaderNodeGroup")
    params.node_tree = bpy.data.node_groups[groups.PARAMS]
    geo = ng.nodes.new("ShaderNodeNewGeometry")
    cam = ng.nodes.new("ShaderNodeCameraData")
    path = ng.nodes.new("ShaderNodeLightPath")
    g = {s.name: s for s in gin.outputs if s.name}
    diffuse, specular, level = surface.principled_to_phong(
        m, m.wrap(g["Base Color"], vector=True), m.wrap(g["Metallic"]), m.wrap(g["Roughness"]),
        m.wrap(g["Specular IOR Level"]), m.dot(m.wrap(geo.outputs["Incoming"], vector=True),
                                               m.wrap(geo.outputs["Normal"], vector=True)),
        transmission=m.wrap(g["Transmission Weight"]))
    mirror = surface.sharp_share(m, m.wrap(g["Roughness"])) if mirrors and tails else None
    lobe = specular if mirror is None else m.scale(specular, 1.0 - mirror)   # (a sharp mirror's: the tails')
    is_camera = m.wrap(path.outputs["Is Camera Ray"])
    segment = glass_tails.specular_segment(m, path)
    fogged = is_camera + segment   # the rays the fog shades: 0 or 1
    view = m.wrap(cam.outputs["View Distance"])
    # the segment's length: from the camera on camera rays (Ray Length starts at the near clip there), from the
    # pane or mirror on a specular segment (Ray Length: the point is P + Incoming x Ray Length's end)
    length = m.select(segment, m.wrap(path.outputs["Ray Length"]), view)
    t_vp, transmit = shading.view_transmittance(m, m.wrap(params.outputs["Beta"]), length, fogged)
    # the viewport's preview of a daylight the compositor adds (``preview.Shown.day_table``): the exact grey
    # transmittance, the sun's and the sky's dimming and their light, where the preview shows (``preview.blend``)
    day_preview = preview.day_table if preview and day is not None else None
    shown = preview_.factor(m, params) if day_preview is not None else None
    if day is not None:
        daylight = day(m, m.wrap(params.outputs["Beta"]), m.wrap(params.outputs["Albedo"], vector=True))
        position, incoming = m.wrap(geo.outputs["Position"], vector=True), m.wrap(geo.outputs["Incoming"], vector=True)
        # a shader's factor is one number: with air, the mean of its colour (the Compositor takes the colour)
        exact = (lambda: sunlight.grey(m, sunlight.view_transmittance(m, daylight, position, incoming, length)))
        t_vp = exact() if day_exact else sunlight.proxy_transmittance(m, daylight, length)
        if shown is not None and not day_exact:
            t_vp = preview_.blend(m, t_vp, exact(), shown)
        transmit = 1.0 + fogged * (t_vp - 1.0)
        dimming = (lambda: sunlight.grey(m, sunlight.direct_dimming(
            m, daylight, position, m.wrap(geo.outputs["Normal"], vector=True))))
        if day_dims:
            transmit = transmit * dimming()
        elif shown is not None and preview.day_dims:
            transmit = transmit * preview_.blend(m, 1.0, dimming(), shown)
    glow_length = view * (1.0 - segment)   # a specular segment's glow is the tails' (``glass_tails``)
    shared = {"Beta": params.outputs["Beta"], "Albedo": params.outputs["Albedo"], "Position": geo.outputs["Position"],
              "Incoming": geo.outputs["Incoming"], "View Distance": glow_length.sock,
              "Normal": geo.outputs["Normal"], "Diffuse": diffuse.sock, "Specular": lobe.sock,
              "Glossy Level": level.sock, "View Transmittance": t_vp.sock, "Is Camera": fogged.sock,
              passes.OPACITY: g[passes.OPACITY]}
    placed, bundles, running = light_bundles.place_bundles(
        ng, lights, models, functools.partial(build_surface_bundle, images), shared, with_passes)
    sums = None
    for node, _ in placed:
        sums = shading.merge_sums(sums, shading.LightSums(
            [], *(m.wrap(node.outputs[f], vector=f == "Emission") for f in ("Emission", "Weighted", "Weight"))))
    fogs = [node.outputs["Fog"] for node, mods in placed if any(_lit(mod) for mod in mods)]
    if preview:
        shown, preview_trees, _ = light_bundles.place_bundles(
            ng, preview.lights, preview.models, functools.partial(
                build_surface_bundle, images, prefix=groups.SURFACE_PREVIEW, shadows=preview.shadows, g_=preview.g,
                cycles=preview.cycles),
            shared, False)
        shaders = [node.outputs["Fog"] for node, mods in shown if any(_lit(mod) for mod in mods)]
        if preview.sampled is not None:   # the other point lights, one sampled a sample
            shaders.append(preview_sampled.group_node(ng, preview_sampled.build_surface_group(
                images, preview.sampled, preview.g, preview.sampled_dense, preview.cycles), shared))
        if day_preview is not None:   # the sun's and the sky's glow and fog light, as the node groups give them
            shaders.append(_day_light(m, ng, daylight, day_preview, geo, incoming, length, diffuse + specular, t_vp,
                                      is_camera)[0])
        fogs += [sock for sock in [preview_.behind_switch(ng, params, shaders)] if sock]
    fog = shading.surface_fog(m, sums, transmit)
    if day is not None and day_table is not None:
        emission, light = _day_light(m, ng, daylight, day_table, geo, incoming, length, diffuse + specular, t_vp,
                                     is_camera)
        fogs.append(emission)
        fog = fog._replace(emission=fog.emission + light)
    closures.shader_tree(ng, gout.inputs["Fog"], fogs)
    for sock, v in (("Emission", fog.emission), ("Transmittance", fog.transmittance),
                    ("Direct Attenuation", fog.direct_attenuation), ("Cycles Mix Factor", fog.cycles_mix),
                    ("EEVEE Mix Factor", fog.eevee_mix)):
        m.feed(gout.inputs[sock], m.wrap(v))
    if with_passes:
        light = m.wrap(running, vector=True) if running is not None else m.wrap((0.0, 0.0, 0.0))
        passes.write_group(m, ng, light, m.wrap(fog.transmittance), m.wrap(g[passes.OPACITY], vector=True),
                           light_weighted=True)
    else:
        closures.camera_rays_only(ng, gout.inputs["Fog"], fogged.sock)
    own = not isinstance(tails, glass_tails.Tails)
    tail_lights, tail_models = (lights, models) if own else (tails.lights, tails.models)
    shadows, anisotropy, chances, cycles = ((None, 0.0, None, False) if own
                                            else (tails.shadows, tails.g, tails.chances, tails.cycles))
    pick = closures.pick_noise(ng, geo.outputs["Position"]) if chances is not None and tails else None
    segment_lights, segment_trees = [], []
    if not own:   # the materials hold no lights: the fog light surfaces past glass reflect
        placed_segment, segment_trees, _ = light_bundles.place_bundles(
            ng, tail_lights, tail_models, functools.partial(build_surface_bundle, images,
                                                            prefix=groups.SURFACE_SEGMENT, shadows=shadows,
                                                            g_=anisotropy, samples=preview_shafts.SEGMENT_SAMPLES,
                                                            chances=chances, cycles=cycles),
            dict(shared, **{"Is Camera": segment.sock}, **({"Pick": pick} if pick is not None else {})), False)
        segment_lights = [node.outputs["Fog"] for node, _ in placed_segment]
    tails = (glass_tails.place_tails(m, ng, tail_lights, tail_models, images, geo, g, segment, is_camera, t_vp,
                                     {"Beta": params.outputs["Beta"], "Albedo": params.outputs["Albedo"],
                                      "Position": geo.outputs["Position"]}, len(placed),
                                     extra=segment_lights, shadows=shadows, g_=anisotropy,
                                     chances=chances, pick=pick, cycles=cycles,
                                     mirror=None if mirror is None else m.scale(specular, mirror))
             + segment_trees if tails else [])
    if extra is not None:   # before it replaces the group the materials use: adding a node there costs more
        extra(ng)
    m.place()
    ng = groups.install(ng, groups.SURFACE)
    light_bundles.name_bundles(bundles + tails + (preview_trees if preview else []))
    return ng


def _day_light(m, ng, daylight, table, geo, incoming, length, reflectance, t_vp, is_camera):
    """(an Emission's output, its colour) of a fog layer's sun and sky on camera rays (``daylight_terms.surface_terms``,
    composed: Sun et al. 2005 Eq. 19): the glow along the ray to the surface and the fog light it reflects, from the
    fog light's ``table``."""
    position = m.wrap(geo.outputs["Position"], vector=True)
    light = m.scale(compose.surface_light(m, daylight_terms.surface_terms(
        m, daylight, table, position + m.scale(incoming, length), m.scale(incoming, -1.0), position,
        m.wrap(geo.outputs["Normal"], vector=True), reflectance, length, t_vp)), is_camera)
    emit = ng.nodes.new("ShaderNodeEmission")
    emit.location = (3000, -600)
    m.feed(emit.inputs["Color"], light)
    return emit.outputs["Emission"], light


def _shares(m, ng, light, shadow, images, g, jitter, anisotropy, samples=None):
    """A node of ``light``'s shares (``preview_shafts.shares``) on the bundle's camera ray, its Light input left for
    the caller to link.  Built before the light's own group node: Cycles' SVM compiles a shader's
    nodes in the order they were made, so the shares' quadrature runs first and only its two results stay on the
    stack while the light's kernels run (the other way round: out of SVM stack space, the material black)."""
    position, incoming = m.wrap(g["Position"], vector=True), m.wrap(g["Incoming"], vector=True)
    length = m.wrap(g["View Distance"])
    camera = position + m.scale(incoming, length)
    return preview_shafts.shares(ng, light, shadow, images, anisotropy, {
        "Beta": g["Beta"], "Camera": camera.sock, "Direction": m.scale(incoming, -1.0).sock, "Length": length.sock,
        "Position": g["Position"], "Normal": g["Normal"], "Jitter": jitter}, samples or preview_shafts.PREVIEW_SAMPLES)


def _shafted(m, terms, shares):
    """A light's ``terms`` (shading.LightTerms) with its glow along the camera ray times its lit share and the fog
    light its surface reflects times the share its shadows leave (the ``shares`` node's outputs; Dobashi et al.
    2002 Eq. 2's visibility).  The lit share is the glow's gate (``LightTerms.seen``, a spot's times it): the glow
    is a closure of its own behind a Mix Shader of that factor (``closures.closure_sum``), so SVM computes the
    share first and the light's glow after it, each with the stack to itself, and skips the glow in full shadow."""
    share, visible = m.wrap(shares.outputs["Share"]), m.wrap(shares.outputs["Visible"])
    scattered = None if terms.scattered is None else m.scale(m.wrap(terms.scattered, vector=True), visible)
    return terms._replace(scattered=scattered, seen=share if terms.seen is None else m.wrap(terms.seen) * share)


def _lit(models):
    """False for a light whose every fog term is off (``rungs.STEPS`` "off"): it adds no fog light."""
    return any(o.computed(models) for o in rungs.SURFACE_OUTPUTS if o.colour)


def _times(m, emission, factor):
    """A light's fog light (a colour or ``shading.Gated``) times the colour ``factor``."""
    if not isinstance(emission, shading.Gated):
        return m.wrap(emission, vector=True) * factor
    glow, rest = m.wrap(emission.glow, vector=True) * factor, m.wrap(emission.rest, vector=True) * factor
    return emission._replace(glow=glow, rest=rest)
