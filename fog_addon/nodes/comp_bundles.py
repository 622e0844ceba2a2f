"""The compositor's bundles: the scene's lights by ``BUNDLE_SIZE``, a group each in the fog group, holding each
light's glow, scatter, shaft and halo groups with their inputs driven by the light, and the sums of their
terms."""
from ..precompute.model import rungs
from ..precompute.physics.shafts import shafts
from . import comp_halos, comp_lights, comp_ops, comp_shafts, drivers, groups, light_groups, owned
from .comp_halos import HALO_STEP
from .comp_lights import GLOW_OUTPUTS, GLOW_SHARED, SCATTER_OUTPUTS, SURFACE, SURFACE_IMAGES, SURFACE_SHARED
from .comp_ops import CompOps
from .comp_shafts import (HALF, HALF_SHAFT, HALF_SHARED, SHAFT_MAP, SHAFT_PER_PIXEL, SHAFT_SHARED, SURFACE_EDGE,
                          SURFACE_OFFSET, SURFACE_TAPS)
from .groups import F, V

BUNDLE = f"{owned.PREFIX} Compositor Bundle"     # the scene's lights by BUNDLE_SIZE: "<BUNDLE> 1-8", ...
BUNDLE_SIZE = 8   # lights a bundle: Blender's node and link editing grows with a tree's size (one tree of 256
#                   lights with their drivers took over 15 min to build; ``comp_fog.build_fog_group``)
SHARED = (GLOW_SHARED + tuple((SURFACE + name, kind) for name, kind in SURFACE_SHARED[2:])
          + ((SURFACE_OFFSET, F),) + SHAFT_SHARED[3:] + HALF_SHARED + ((HALO_STEP, F),))   # a bundle's inputs
TERMS = tuple((o.compositor, V) for o in rungs.COMPOSITOR_OUTPUTS)     # a bundle's: Airlight, Scattered, Background


BUNDLE_SET = f"{BUNDLE} Set"   # the bundles by SET_SIZE where there are more than SET_SIZE of them: "<BUNDLE_SET> 1-64"
SET_SIZE = 8   # bundles a set (``build_bundle_set``): the fog group then holds sets, each of 64 lights


def bundle_set_name(first, count):
    """The set of bundles of the scene's lights ``first`` + 1 .. ``first`` + ``count``."""
    return f"{BUNDLE_SET} {first + 1}-{first + count}"


def build_bundle_set(scene, first, lights, models, images, peak, windows, shafted=None, layered=False):
    """The compositor group of the bundles (``build_bundle``) of the scene's lights ``first`` + 1 ..
    ``first`` + len(lights) (at most BUNDLE_SIZE x SET_SIZE), SHARED in, their TERMS summed step by step out
    (``comp_ops.in_step``).  Blender's node and link editing slows as a tree grows (a new node in a tree of 3 000
    takes 20-40 ms, in one of 100 0.3 ms), so a city of lamps is a tree of sets of bundles of lights, none of
    them large.  ``windows``: each light's, or None (``build_bundle``'s)."""
    name = bundle_set_name(first, len(lights))
    ng, gin, gout = groups.new_group(name, SHARED, TERMS, tree_type="CompositorNodeTree")
    m = CompOps(ng, images)
    g = {s.name: m.wrap(s, vector=s.type in ("VECTOR", "RGBA")) for s in gin.outputs if s.name}
    sums = {}
    for k in range(0, len(lights), BUNDLE_SIZE):
        node = m.node("CompositorNodeGroup", 2)
        node.node_tree = build_bundle(scene, first + k, lights[k:k + BUNDLE_SIZE], models[k:k + BUNDLE_SIZE], images,
                                      peak, None if windows is None else windows[k:k + BUNDLE_SIZE], shafted,
                                      layered)
        for socket, v in g.items():
            m.feed(node.inputs[socket], v)
        sums = comp_ops.in_step(m, sums, {o: m.wrap(node.outputs[o.compositor], vector=True)
                                          for o in rungs.COMPOSITOR_OUTPUTS})
    for o, v in sums.items():
        m.feed(gout.inputs[o.compositor], v)
    m.place()
    return groups.install(ng, name)


def bundle_name(first, count):
    """The bundle group of the scene's lights ``first`` + 1 .. ``first`` + ``count``."""
    return f"{BUNDLE} {first + 1}-{first + count}"


def build_bundle(scene, first, lights, models, images, peak, windows, shafted=None, layered=False):
    """The compositor group of the scene's lights ``first`` + 1 .. ``first`` + len(lights) (at most
    BUNDLE_SIZE): SHARED in, each light's glow and scatter groups (``comp_lights.build_glow_group``,
    ``comp_lights.build_scatter_group``) with its position, intensity and cone driven by the light
    (``drivers.drive_intensity``, ``light_groups.drive_spot``), TERMS summed out: Airlight and Background over
    the picture, Scattered over the Surface inputs' window.  ``windows``: each light's glow window
    (``footprint.py``), or None for none (the whole picture): a light with one gets its glow group's
    inputs cropped to it (``comp_ops.window_crop``).  ``shafted``: (shadow maps by light name, K, g) of the
    lights whose glows are shadowed (``comp_shafts.build_shaft_group``), or None.  ``layered``: the glows'
    origin is per pixel (a fog layer's span, ``comp_fog.build_fog_group``)."""
    name = bundle_name(first, len(lights))
    maps, samples, g_ = shafted or ({}, None, 0.0)
    ng, gin, gout = groups.new_group(name, SHARED, TERMS, tree_type="CompositorNodeTree")
    m = CompOps(ng, images)
    g = {s.name: m.wrap(s, vector=s.type in ("VECTOR", "RGBA")) for s in gin.outputs if s.name}
    # what a glow group reads per pixel: cropped to its light's window
    per_pixel = (("Direction", "View Distance", "Glow Length") + (("Incoming", "Pixel") if peak is not None else ())
                 + (("Glow Origin",) if layered else ()))
    # each sum starts black over its domain: the picture for the glows, the surfaces' window for the rest
    sums = {o: comp_ops.zero(m, g["Direction"] if o in GLOW_OUTPUTS else g[SURFACE + "Position"])
            for o in rungs.COMPOSITOR_OUTPUTS}
    coarse, halos = None, {}   # the halos' coarse inputs and sums (``comp_halos.halo``)
    for k, (light, mod) in enumerate(zip(lights, models), start=first):
        position = comp_ops.driven_location(m, f"Light {k} Location", light, col=4)
        intensity = m.node("ShaderNodeCombineXYZ", 4)
        drivers.drive_intensity(intensity, light.data)
        built = []   # a term the light's step leaves out (rungs.STEPS) gets no group at all
        terms = {}   # this light's terms by output
        # the light's glow window, made only where a glow or a shaft group reads it (a window no group reads
        # would still grow with the frames and mark the windows partial, ``comp_fog.set_windows``)
        has_window = windows is not None and windows[k - first] is not None
        win = (comp_ops.window_crop(m, scene, k, windows[k - first]) if has_window and (
            light.name in maps or any(o.computed(mod) for o in GLOW_OUTPUTS)) else None)
        crop = lambda socket: comp_ops.crop(m, g[socket], win) if win else g[socket]
        shaft = None
        if light.name in maps:   # its glows times the lit share, its surfaces' fog light times their visibility
            shaft = m.node("CompositorNodeGroup", 6)
            shaft.node_tree = comp_shafts.build_shaft_group(light, maps[light.name], images, samples, g_)
            shaft.label = f"Light {k} Shaft: {light.name}"
            half, half_length = comp_shafts.half_view(m, {s: crop(v) for s, v in HALF_SHAFT.items()},
                                                      g[HALF + "Step"])
            for socket, _ in SHAFT_SHARED:
                m.feed(shaft.inputs[socket], half[socket] if socket in SHAFT_PER_PIXEL else g[socket])
            shadow = maps[light.name]
            if shadow.atlas is None:
                source = m.node("CompositorNodeImage", 5)
                source.image = images[shadow.spec.name]
                ng.links.new(source.outputs["Image"], shaft.inputs[SHAFT_MAP])
            else:   # the frame's map, cut from the light's atlas of the animation's
                m.feed(shaft.inputs[SHAFT_MAP],
                       comp_shafts.atlas_tile(m, images[shadow.spec.name], f"Light {k} Shadow"))
            for socket in ("Position", "Normal", "Offset"):   # the surface share at half resolution
                m.feed(shaft.inputs["Surface " + socket], g[HALF + socket])
            m.feed(shaft.inputs["Light"], position)
            near, far = comp_shafts.full_view(m, [m.wrap(shaft.outputs[s]) for s in ("Share", "Share Far")],
                                              half_length, comp_ops.first(m, crop("Shaft Length")), g[HALF + "Step"])
            share = {o: near if o.at == rungs.SURFACE_POINT else far for o in GLOW_OUTPUTS}
        split = rungs.split_halo(mod)
        halo = None
        if split is not None:   # the multiply scattered halo at a coarser resolution (not shadowed by the shafts)
            coarse = coarse or comp_halos.coarse_inputs(m, g, per_pixel)
            halo = comp_halos.halo(m, coarse, g, split[1], images, f"Light {k} Halo: {light.name}", position)
            for at, v in halo[1].items():
                lit = m.scale(m.wrap(intensity.outputs[0], vector=True), v)
                halos[at] = lit if halos.get(at) is None else comp_ops.accumulate(m, halos[at], lit)
        if any(o.computed(mod) for o in GLOW_OUTPUTS):
            glow = m.node("CompositorNodeGroup", 6)
            glow.node_tree = comp_lights.build_glow_group(mod if split is None else split[0], images, peak)
            glow.label = f"Light {k}: {light.name}"
            for socket, _ in GLOW_SHARED:
                m.feed(glow.inputs[socket], crop(socket) if socket in per_pixel else g[socket])
            for o in GLOW_OUTPUTS:
                v = m.wrap(glow.outputs[o.compositor], vector=True)
                if shaft is not None:
                    v = m.scale(v, share[o])
                terms[o] = v if win is None else comp_ops.uncrop(m, v, win)
            built.append(glow)
        if any(o.computed(mod) for o in SCATTER_OUTPUTS):
            if shaft is not None:   # its directions interleave as the glow's nodes do (``shafts.surface_share``)
                parts = comp_shafts.interleave_mean_group(m, m.wrap(shaft.outputs["Visible"], vector=True),
                                                          m.length(g[HALF + "Position"] - g["Camera"]), SURFACE_TAPS,
                                                          SURFACE_EDGE)
                parts = comp_shafts.upsampled_group(m, parts, g[HALF + "Length"],
                                                    m.length(g[SURFACE + "Position"] - g["Camera"]), g[HALF + "Step"])
                visible = shafts.share_of(m.dot(parts, (1.0, 0.0, 0.0)), m.dot(parts, (0.0, 1.0, 0.0)))
            scatter = m.node("CompositorNodeGroup", 6)
            scatter.node_tree = comp_lights.build_scatter_group(mod, images)
            scatter.label = f"Light {k} Scatter: {light.name}"
            for socket, _ in SURFACE_SHARED:
                m.feed(scatter.inputs[socket], g[socket if socket not in SURFACE_IMAGES else SURFACE + socket])
            for o in SCATTER_OUTPUTS:
                v = m.wrap(scatter.outputs[o.compositor], vector=True)
                if shaft is not None:
                    v = m.scale(v, visible)
                terms[o] = v
            built.append(scatter)
        sums = comp_ops.in_step(m, sums, terms)   # this light's terms all computed before the next light's
        for node in built:
            m.feed(node.inputs["Light"], position)
            ng.links.new(intensity.outputs[0], node.inputs["Intensity"])
        if built and light_groups.SPOT_ROWS[0] in built[0].inputs:   # the cone's drivers once, for both groups
            light_groups.drive_spot(ng, k, light, built[0])
            for node in built[1:] + ([halo[0]] if halo is not None else []):
                for socket, _ in light_groups.spot_inputs(mod):
                    ng.links.new(built[0].inputs[socket].links[0].from_socket, node.inputs[socket])
        if shaft is not None and light_groups.SPOT_ROWS[0] in shaft.inputs:   # a moving spot's shafts: its cone
            # now; an area light's: its pose now
            if built and light_groups.SPOT_ROWS[0] in built[0].inputs:
                for socket in (*light_groups.SPOT_ROWS, light_groups.SPOT_COS, light_groups.SPOT_BLEND):
                    if socket in shaft.inputs:
                        ng.links.new(built[0].inputs[socket].links[0].from_socket, shaft.inputs[socket])
            else:
                light_groups.drive_spot(ng, k, light, shaft)
    if halos:
        fine = comp_halos.fine(m, g, coarse, halos)
        for o in GLOW_OUTPUTS:
            sums[o] = comp_ops.accumulate(m, sums[o], fine[o.at])
    for o, v in sums.items():
        m.feed(gout.inputs[o.compositor], v)
    m.place()
    return groups.install(ng, name)
