"""Per-light shader groups, shared by every light with the same models: one light seen from a surface point
(``build_light``: ``shading.shade_point``) and on a ray to the sky (``build_background_light``:
``shading.background_point``), with a spot's or an area light's inputs; and an instance of one in a bundle,
driven by its light (``light_instance``)."""
import bpy

from ..precompute.model import rungs, shading
from ..precompute.physics.area import area
from ..precompute.core.medium import Medium
from . import drivers, groups, owned
from .groups import C, F, V
from .sockets import NodeOps

SPOT_ROWS = ("Spot X", "Spot Y", "Spot Z")   # a spot light's group inputs: its inverse matrix's rows (shading.Spot)
SPOT_COS, SPOT_BLEND = "Spot Cos Half", "Spot Blend"
AREA_HALF_X, AREA_HALF_Y = "Area Half X", "Area Half Y"   # an area light's: its rectangle's half sizes (m)
CYCLES_TAG = " (Cycles)"   # a group built for Cycles alone (``build_light``)
JITTER = "Jitter"   # a sampling glow's uniform number (``shading.Light.u``)


def medium(m, beta, albedo=None):
    """The Medium of a group's sockets (the per-light groups need only beta)."""
    return Medium(m.wrap(beta)) if albedo is None else Medium(m.wrap(beta), m.wrap(albedo, vector=True))


def _shape_names(models):
    """The names of the two shape inputs of a spot's or an area light's group (``shading.shape_args``)."""
    return (AREA_HALF_X, AREA_HALF_Y) if rungs.is_area(models) else (SPOT_COS, SPOT_BLEND)


def spot_inputs(models):
    """The extra inputs of a spot's or an area light's group (``rungs.is_spot``), none for a point light's; and
    the uniform number JITTER of a light whose glow samples (``rungs.Rung.sampled``)."""
    sampled = [(JITTER, F)] if models.airlight.sampled or models.background.sampled else []
    return ([(n, V) for n in SPOT_ROWS] + [(n, F) for n in _shape_names(models)] if rungs.is_spot(models)
            else []) + sampled


def _outputs(outputs, models):
    """A light group's outputs (name, socket type) for ``models``: the quantities ``outputs`` of
    ``rungs.OUTPUTS`` a light with these models has (``rungs.Output.present``)."""
    return [(o.name, C if o.colour else F) for o in outputs if o.present(models)]


def read(m, node, outputs, kind):
    """``kind`` (shading.LightTerms or SkyTerms) from the outputs of a light group's instance ``node``."""
    return kind(**{o.field: m.wrap(node.outputs[o.name], vector=o.colour) for o in outputs if o.name in node.outputs})


def light_of(g, models):
    """shading.Light from a per-light group's inputs ``g`` (name: value)."""
    cone = None
    if rungs.is_spot(models):
        kind = shading.Area if rungs.is_area(models) else shading.Spot
        cone = kind(tuple(g[n] for n in SPOT_ROWS), *(g[n] for n in _shape_names(models)))
    return shading.Light(g["Light"], g["Intensity"], cone, g.get(JITTER))


def build_light(models, images, cycles=False):
    """Per-light surface group: ``shading.shade_point`` (Sun et al. 2005 Eq. 11, 14, 17-18) with ``models``;
    ``cycles``: for Cycles alone, its tables read by Cycles' own bilinear filter (``NodeOps.cycles``)."""
    name = groups.light_group_name(models) + (CYCLES_TAG if cycles else "")
    if (ng := groups.up_to_date(name)) is not None:
        return ng
    ng, gin, gout = groups.new_group(name, [
        ("Beta", F), ("Light", V), ("Intensity", C), ("Position", V), ("Incoming", V),
        ("View Distance", F), ("Normal", V), ("Diffuse", C), ("Specular", C), ("Glossy Level", F),
        *spot_inputs(models)], _outputs(rungs.SURFACE_OUTPUTS, models))
    m = NodeOps(ng, images, cycles=cycles)
    g = {s.name: m.wrap(s, vector=s.type in ("VECTOR", "RGBA")) for s in gin.outputs if s.name}
    pos, incoming, d_vp = g["Position"], g["Incoming"], g["View Distance"]
    geo = shading.Geometry(pos + incoming * d_vp, pos, incoming, d_vp, g["Normal"])
    material = shading.Material(g["Diffuse"], g["Specular"], g["Glossy Level"])
    light = light_of(g, models)
    terms = shading.shade_point(m, geo, material, light, medium(m, g["Beta"]), models)
    return _finish(m, ng, gout, name, rungs.SURFACE_OUTPUTS, models, terms)


def build_background_light(models, images, cycles=False):
    """Per-light world group: ``shading.background_point`` (Sun et al. 2005 Eq. 12) with ``models`` (``cycles``: as
    ``build_light``'s)."""
    name = groups.background_group_name(models) + (CYCLES_TAG if cycles else "")
    if (ng := groups.up_to_date(name)) is not None:
        return ng
    ng, gin, gout = groups.new_group(name, [
        ("Beta", F), ("Light", V), ("Intensity", C), ("Camera", V), ("Direction", V), *spot_inputs(models),
    ], _outputs(rungs.SKY_OUTPUTS, models))
    m = NodeOps(ng, images, cycles=cycles)
    g = {s.name: m.wrap(s, vector=s.type in ("VECTOR", "RGBA")) for s in gin.outputs if s.name}
    light = light_of(g, models)
    terms = shading.sky_terms(m, g["Camera"], g["Direction"], light, medium(m, g["Beta"]), models)
    return _finish(m, ng, gout, name, rungs.SKY_OUTPUTS, models, terms)


def _finish(m, ng, gout, name, outputs, models, terms):
    """Feed each of ``outputs`` the ``models`` compute from ``terms`` (a LightTerms or SkyTerms), mark the group
    with the code's fingerprint and install it as ``name``."""
    for o in outputs:
        if o.present(models):
            m.feed(gout.inputs[o.name], m.wrap(getattr(terms, o.field)))
    ng[owned.BUILT] = groups.code_fingerprint()
    m.place()
    return groups.install(ng, name)


def light_instance(ng, k, light, group_name, inputs):
    """Instance ``group_name`` for the ``k``-th light, its Light and Intensity inputs driven by ``light``.

    ``inputs``: (output socket, input name) pairs for the other inputs.
    Returns the group node.
    """
    loc = drivers.vector_node(ng, f"Light {k} Location", -600, -300 * k)
    drivers.drive_location(loc, light)
    inten = drivers.vector_node(ng, f"Light {k} Intensity", -600, -300 * k - 120)
    drivers.drive_intensity(inten, light.data)
    node = ng.nodes.new("ShaderNodeGroup")
    node.node_tree = bpy.data.node_groups[group_name]
    node.name = node.label = f"Light {k}: {light.name}"
    node.location = (-300, -300 * k)
    for a, b in ((loc.outputs[0], "Light"), (inten.outputs[0], "Intensity"), *inputs):
        ng.links.new(a, node.inputs[b])
    if SPOT_ROWS[0] in node.inputs:
        drive_spot(ng, k, light, node)
    return node


def drive_spot(ng, k, light, node):
    """Feed a spot group ``node``'s cone inputs from ``light``: the rows of its world matrix's cofactor
    matrix (det(M) M^-1: row i is the cross product of the other two columns, j x k in cyclic order), and
    cos(spot_size / 2) and spot_blend, all by simple-expression drivers (``drivers.drive_expression``).  The
    RNA path matrix_world[c][r] is the element of row r, column c."""
    for i, row_name in enumerate(SPOT_ROWS):
        vec = drivers.vector_node(ng, f"Light {k} {row_name}", -900, -300 * k - 60 * i)
        cj, ck = (i + 1) % 3, (i + 2) % 3
        for axis in range(3):
            a1, a2 = (axis + 1) % 3, (axis + 2) % 3
            drivers.drive_expression(vec.inputs[axis], "a * b - c * e",   # (col_j x col_k)[axis]
                                     [(name, light, f"matrix_world[{col}][{row}]") for name, col, row in
                                      (("a", cj, a1), ("b", ck, a2), ("c", cj, a2), ("e", ck, a1))])
        ng.links.new(vec.outputs[0], node.inputs[row_name])
    for sock_name, path, expression in _shape_drivers(light):
        if sock_name not in node.inputs:   # (an area light's shaft group takes its rows alone)
            continue
        value = ng.nodes.new("ShaderNodeValue")
        value.name = value.label = f"Light {k} {sock_name}"
        value.location = (-900, -300 * k - 200)
        drivers.drive_expression(value.outputs[0], expression, (("v", light.data, path),))
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
