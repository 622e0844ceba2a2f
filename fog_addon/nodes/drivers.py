"""Drivers that feed the fog's node groups from the scene: an object's location (TRANSFORMS variables) and simple
expressions of single properties.  Neither needs Python to evaluate, so a saved file renders the same with
auto-run off and without the add-on (a farm)."""
from ..precompute.physics.area import area


def _new_driver(sock):
    """A new driver of ``sock``'s value whose result is the value itself.  Blender 5.0's ``driver_add`` gives the
    driver's F-Curve two keyframes, (0, 0) and (1, 1), through which the result is mapped, and their evaluation
    snaps within 1e-4 of a key: a haze's density of 9.8e-5 /m came out 0 (no fog at all), 0.99995 came out 1.
    Without keyframes (or modifiers) an F-Curve passes the driver's value through."""
    sock.driver_remove("default_value")
    curve = sock.driver_add("default_value")
    curve.keyframe_points.clear()
    for modifier in list(curve.modifiers):
        curve.modifiers.remove(modifier)
    return curve.driver


def drive_location(node, obj):
    """Inputs 0-2 of ``node`` follow ``obj``'s world location (TRANSFORMS drivers)."""
    for i, axis in enumerate("XYZ"):
        sock = node.inputs[i]
        d = _new_driver(sock)
        d.type = "SUM"
        var = d.variables.new()
        var.type = "TRANSFORMS"
        t = var.targets[0]
        t.id = obj
        t.transform_type = f"LOC_{axis}"
        t.transform_space = "WORLD_SPACE"


def drive_expression(sock, expression, variables):
    """Drive ``sock``'s value by the simple expression ``expression`` of ``variables``: (name, ID, data path)
    of single properties (the ID's type taken from it: an object, light, camera, scene or node group).
    Simple expressions evaluate without Python, so with auto-run off and without the add-on."""
    d = _new_driver(sock)
    d.type = "SCRIPTED"
    for name, owner, path in variables:
        var = d.variables.new()
        var.name = name
        var.type = "SINGLE_PROP"
        var.targets[0].id_type = owner.id_type
        var.targets[0].id = owner
        var.targets[0].data_path = path
    d.expression = expression


def drive_intensity(node, light_data):
    """Inputs 0-2 of ``node`` = radiant intensity P * colour * ``area.intensity_per_watt`` in W/sr
    (simple-expression drivers)."""
    for i in range(3):
        drive_expression(node.inputs[i], f"p * c * {area.intensity_per_watt(light_data.type)!r}",
                         (("p", light_data, "energy"), ("c", light_data, f"color[{i}]")))


def vector_node(ng, name, x, y):
    """A Combine XYZ node named ``name`` in ``ng`` at (x, y), for drivers to feed."""
    n = ng.nodes.new("ShaderNodeCombineXYZ")
    n.name = n.label = name
    n.location = (x, y)
    return n
