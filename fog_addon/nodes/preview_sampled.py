"""The viewport preview's other lights (Cycles and EEVEE): the point lights the preview does not model one by one,
their glows estimated by sampling one of them per sample.

A shader has no loop over lights, and a group per light costs every sample its kernels (``preview.py``'s budget
holds two fully modelled lights or four glows).  The viewport adds samples up, so each sample may instead pick one
light j of the N others with probability p_j and add its glow times 1 / p_j: the sum's unbiased estimate, whose mean
over the samples is the glow of all N (a Monte Carlo estimator; Cycles' many-lights sampling does the same for
direct light).  The fog light is linear in the light's intensity, so the light group of one point light
(``light_groups.build_light``: Sun et al. 2005 Eq. 11 and 17-18 at a surface, fully modelled;
``build_background_light``: Eq. 12 to the sky) takes the intensity I_j / p_j.  Its terms are estimated the same
way, since the light is already one a sample: its glow from two points of the ray (``model.airlight_equiangular``),
from a third uniform number; the fog light a surface reflects and Dense Fog's multiply scattered light are read
from their tables.  In Cycles the light groups' tables are each one Linear tap (``sockets.NodeOps.cycles``).

p_j is proportional to I_j e^{-beta d_j} / max(d_j, 1 m), d_j the light's distance to the camera (a glow's light
over the picture falls as 1 / d, dimmed on its way); j is drawn by Walker's alias method (one uniform number picks a
column, a second keeps it or takes its alias: two texel reads, no search).  The lights' positions, I_j / p_j and the
alias table are an image (``TABLE``), written by ``write_table`` when the fog is built and each time the handlers
follow the scene (``Compositor.update``): a light moved, recoloured or dimmed shows at the next depsgraph update.

The glowing objects join them as point sources along their length (``methods.compositor.sampled_points``): their
glows and the fog light they give the surfaces are a lamp's, as the final render's (``comp_fog.emitter_fog_light``).
Spot and area lights are not sampled (a point's glow is not theirs): the notes name those the preview leaves out.
"""
import math

import bpy
import numpy as np

from ..precompute.core.tables import TableSpec
from ..precompute.model import sampling
from ..precompute.model import rungs, shading
from ..precompute.physics.point import multiple
from . import closures, groups, light_groups
from .groups import C, F, V
from .sockets import NodeOps

TABLE = "AnalyticFog Preview Sampled Lights"   # ``sampling.table_rows``
ROWS = sampling.ROWS
SURFACE_GROUP = groups.SURFACE + " Preview Sampled"
WORLD_GROUP = groups.WORLD + " Preview Sampled"


def sampled(lights):
    """The ``lights`` the sampling can take: point lights."""
    return [o for o in lights if o.data.type == "POINT"]


def table_spec(count):
    return TableSpec(TABLE, max(count, 1), ROWS, channels=4)


def write_table(scene, lights, beta, points=None):
    """Write the table of ``lights`` (``sampled``'s, as they are now) and of ``points`` (centres (K, 3) m, RGB
    intensities (K, 3) W/sr: the glowing objects as point sources, ``methods.compositor.sampled_points``, drawn and
    modelled as the lamps are) into the image ``TABLE`` (made if missing or of another size); returns (spec, image),
    or (None, None) with neither (the image removed)."""
    img = bpy.data.images.get(TABLE)
    centres, glowing = (np.zeros((0, 3)), np.zeros((0, 3))) if points is None else points
    if not lights and not len(centres):
        if img is not None:
            bpy.data.images.remove(img)
        return None, None
    from .. import view   # noqa: PLC0415 (view imports the nodes)
    camera = scene.camera
    frame = [tuple(v) for v in camera.data.view_frame(scene=scene)]
    directions = view.frame_rays(scene, camera, sampling.TILES)[1]
    nx, ny = sampling.TILES
    half_angle = 0.5 * math.atan(max(np.linalg.norm(np.subtract(frame[1], frame[2])) / nx,
                                     np.linalg.norm(np.subtract(frame[3], frame[2])) / ny)
                                 / max(abs(frame[0][2]), 1e-6))
    positions = np.concatenate([np.reshape([tuple(o.matrix_world.translation) for o in lights], (-1, 3)), centres])
    intensities = np.concatenate([np.reshape(view.light_intensities(lights), (-1, 3)), glowing])
    rows = sampling.table_rows(positions, intensities, camera.matrix_world.translation, beta, directions, half_angle)
    spec = table_spec(len(positions))
    if img is not None and tuple(img.size) != (spec.width, spec.height):
        bpy.data.images.remove(img)
        img = None
    if img is None:
        img = bpy.data.images.new(TABLE, spec.width, spec.height, alpha=True, float_buffer=True, is_data=True)
        img.colorspace_settings.name = "Non-Color"
        img.alpha_mode = "CHANNEL_PACKED"
        img.use_half_precision = False
        img[groups.FOG_PROP] = True
    flat = rows.ravel()
    old = np.empty(len(flat), np.float32)
    img.pixels.foreach_get(old)
    if not np.array_equal(old, flat):   # (an image changed makes the viewport sync it again)
        img.pixels.foreach_set(flat)
        img.update()
    return spec, img


def pack_table():
    """Keep the table in the saved file (Blender's packing of the float image, a few hundred bytes a light): a file
    opened again shows the sampled lights before the handlers first write it (``write_table``)."""
    img = bpy.data.images.get(TABLE)
    if img is not None:
        img.pack()


def _tile(m, ng):
    """The index of the tile (``sampling.TILES``) the shading point lies in on the camera's frame, by its window
    coordinates (0 to 1 from the frame's bottom-left corner; a point outside the frame takes the nearest tile)."""
    coord = ng.nodes.new("ShaderNodeTexCoord")
    coord.name = coord.label = "Preview Sampled Window"
    sep = ng.nodes.new("ShaderNodeSeparateXYZ")
    ng.links.new(coord.outputs["Window"], sep.inputs[0])
    nx, ny = sampling.TILES
    tx = m.clamp(m.floor(m.wrap(sep.outputs[0]) * float(nx)), 0.0, nx - 1.0)
    ty = m.clamp(m.floor(m.wrap(sep.outputs[1]) * float(ny)), 0.0, ny - 1.0)
    return m.mul_add(ty, float(nx), tx)


def _pick(m, spec, u1, u2, tile):
    """(the column Walker's alias method takes in the row of ``tile`` for the uniform numbers ``u1``, ``u2`` in
    [0, 1), as a texture coordinate (its centre); the v coordinate of the tile's intensities over probabilities)."""
    n, rows = float(spec.width), float(spec.height)
    column = m.minimum(m.floor(u1 * n), n - 1.0)
    u = m.mul_add(column, 1.0 / n, 0.5 / n)
    alias_row = m.mul_add(tile, 2.0 / rows, 2.5 / rows)
    keep = m.tap(spec, u, alias_row, 0)
    alias = m.tap(spec, u, alias_row, 1)
    taken = m.select(m.less(u2, keep), column, alias)
    return m.mul_add(taken, 1.0 / n, 0.5 / n), m.mul_add(tile, 2.0 / rows, 1.5 / rows)


def _light(m, spec, u, intensity_row):
    """(position, I / p) of the column at the texture coordinate ``u``, I / p from the row ``intensity_row``."""
    pos = m.combine(*(m.tap(spec, u, 0.5 / spec.height, c) for c in range(3)))
    inten = m.combine(*(m.tap(spec, u, intensity_row, c) for c in range(3)))
    return pos, inten


def _randoms(ng, source):
    """Three uniform numbers that change at every sample: a White Noise of ``source`` (the pixel filter moves it)."""
    noise = ng.nodes.new("ShaderNodeTexWhiteNoise")
    noise.noise_dimensions = "4D"
    noise.inputs["W"].default_value = 7.31   # (not the shafts' jitter: independent numbers)
    noise.name = noise.label = "Preview Sampled Jitter"
    ng.links.new(source, noise.inputs["Vector"])
    sep = ng.nodes.new("ShaderNodeSeparateColor")
    ng.links.new(noise.outputs["Color"], sep.inputs[0])
    return sep.outputs[0], sep.outputs[1], sep.outputs[2]


def light_models(g, step=0, dense=None):
    """A point light's models at the ladder's ``step`` (``rungs.choose``): fully modelled for the surfaces (its glow
    and the fog light they reflect), "glow only" for the sky; the glow's single scattering one point of the ray a
    sample (``rungs.sampled_rungs``: the light is already one a sample, and a table's glow costs several fog-free
    renders); with Dense Fog's multiply scattered light where ``dense`` = (grey albedo, the share of its field the
    surfaces leave) is given (one for every sampled light: ``dense_of``)."""
    albedo, scale = dense if dense is not None else (None, 1.0)
    return rungs.choose("nodes", step, g, "point", multiple_albedo=albedo, multiple_scale=scale, sampled_glow=True)


def dense_of(lights, models, g, albedo, scales, weights):
    """(albedo, scale) of Dense Fog for the sampled ``lights`` whose final ``models`` (rungs.LightModels, in order)
    have it (their airlight reads the field's table), or None if none has: their field scales (``scales``: by name,
    1 where missing) averaged by ``weights`` (their importance).  One light group serves every sampled light, so a
    light whose own scale differs gets the mean (``escape.field_scales``: near a wall, a hood)."""
    if albedo is None:
        return None
    field = multiple.table_spec(g, albedo).name
    dense = [i for i, mod in enumerate(models) if any(t.name == field for t in mod.airlight.tables)]
    if not dense:
        return None
    w = np.asarray(weights, float)[dense]
    k = np.array([scales.get(lights[i].name, 1.0) for i in dense])
    return albedo, float(np.round((w * k).sum() / w.sum() if w.sum() > 0 else k.mean(), 2))


def _sampled_group(name, inputs, images, spec, light_group, shared, jitter_from):
    """(tree, its output node, its NodeOps, its inputs by name, the light group's node) of a group ``name`` with
    ``inputs``: one light drawn from the table ``spec`` per sample (``_pick``, its randoms from the input ``jitter_from``) feeds
    ``light_group``'s Light and Intensity, the group's ``shared`` inputs its own."""
    ng, gin, gout = groups.new_group(name, inputs, [("Fog", "NodeSocketShader")])
    m = NodeOps(ng, dict(images))
    s = {x.name: x for x in gin.outputs if x.name}
    u1, u2, u3 = _randoms(ng, s[jitter_from])
    position, intensity = _light(m, spec, *_pick(m, spec, m.wrap(u1), m.wrap(u2), _tile(m, ng)))
    node = ng.nodes.new("ShaderNodeGroup")
    node.node_tree = light_group
    node.name = node.label = "Sampled Light"
    m.feed(node.inputs["Light"], position)
    m.feed(node.inputs["Intensity"], intensity)
    ng.links.new(u3, node.inputs[light_groups.JITTER])
    for sock in shared:
        ng.links.new(s[sock], node.inputs[sock])
    return ng, gout, m, s, node


def build_surface_group(images, spec, g, dense=None, cycles=False):
    """The Surface group's estimate of the other lights' fog light (shader group, output Fog: an Emission of the
    sampled light's, fully modelled: Sun et al. 2005 Eq. 19's albedo x (glow + T x reflected fog light) on camera
    rays, ``shading.sum_lights``; ``light_models``)."""
    shared = ("Beta", "Position", "Incoming", "View Distance", "Normal", "Diffuse", "Specular", "Glossy Level")
    ng, gout, m, s, node = _sampled_group(SURFACE_GROUP, [
        ("Beta", F), ("Albedo", C), ("Position", V), ("Incoming", V), ("View Distance", F), ("Normal", V),
        ("Diffuse", C), ("Specular", C), ("Glossy Level", F), ("View Transmittance", F), ("Is Camera", F)],
        images, spec, light_groups.build_light(light_models(g, 0, dense), images, cycles), shared, "Position")
    terms = light_groups.read(m, node, rungs.SURFACE_OUTPUTS, shading.LightTerms)
    sums = shading.sum_lights(m, [terms], light_groups.medium(m, s["Beta"], s["Albedo"]),
                              m.wrap(s["View Transmittance"]), m.wrap(s["Is Camera"]))
    closures.closure_sum(m, gout.inputs["Fog"], "ShaderNodeEmission", sums.emissions)
    m.place()
    return groups.install(ng, SURFACE_GROUP)


def build_world_group(images, spec, g, dense=None, cycles=False):
    """The World group's estimate of the other lights' glows to the sky (shader group, output Fog: a Background of
    albedo x the sampled light's glow to infinity x Is Camera)."""
    ng, gout, m, s, node = _sampled_group(
        WORLD_GROUP, [("Beta", F), ("Albedo", C), ("Camera", V), ("Direction", V), ("Is Camera", F)], images, spec,
        light_groups.build_background_light(light_models(g, 1, dense), images, cycles), ("Beta", "Camera", "Direction"),
        "Direction")
    sky = light_groups.read(m, node, rungs.SKY_OUTPUTS, shading.SkyTerms)
    glow = m.scale(m.wrap(s["Albedo"], vector=True) * m.wrap(sky.background, vector=True), m.wrap(s["Is Camera"]))
    closures.closure_sum(m, gout.inputs["Fog"], "ShaderNodeBackground", [glow])
    m.place()
    return groups.install(ng, WORLD_GROUP)


def group_node(ng, tree, shared):
    """A node of ``tree`` in ``ng``, its inputs linked from ``shared`` (name: output socket); its Fog output."""
    node = ng.nodes.new("ShaderNodeGroup")
    node.node_tree = tree
    node.name = node.label = tree.name
    for sock in node.inputs:
        if sock.name in shared:
            ng.links.new(shared[sock.name], sock)
    return node.outputs["Fog"]
