"""Bundles: the Surface and World groups' lights in groups of ``BUNDLE`` (``split`` says why), one group node each
in the scene group, and the Fog Light pass's running sum carried from one bundle to the next (``RUNNING``)."""
import bpy

from . import groups

BUNDLE = 8   # lights per bundle group (``split``)
RUNNING = "Running Sum"   # a bundle's input and output with the fog passes: the Fog Light pass so far


def split(lights, models):
    """[(index of the first light, lights, models)] in runs of at most ``BUNDLE`` lights.

    Why bundles: Blender updates the whole node tree on every edit through its Python API (about 1 us
    per node already in the tree for each node added, link made or value set), so a Surface group
    holding every light's nodes took time growing with the square of the lights to build (64 lights:
    13 s; 256: minutes).  Each bundle is a group of its own, small while it is built, and the Surface
    and World groups hold one node per bundle.  Cycles and EEVEE inline groups, so what they compile
    is the same graph.
    """
    return [(k, lights[k:k + BUNDLE], models[k:k + BUNDLE]) for k in range(0, len(lights), BUNDLE)]


def bundle_name(prefix, first, lights):
    return f"{prefix} {first + 1}-{first + len(lights)}"


def name_bundles(bundles):
    """Give bundles built beside ones in use (``groups.new_group``'s BUILDING name) their own names, once the
    scene group that used the old ones has been replaced (``groups.install``), deleting the old ones.

    Not ``groups.install``: remapping a bundle's users while the old scene group still held it updated every
    material using that group (0.1 s a bundle with 1 000 materials)."""
    for ng in bundles:
        name = ng.name.removesuffix(groups.BUILDING)
        if ng.name != name:
            old = bpy.data.node_groups.get(name)
            if old is not None and not old.users:
                bpy.data.node_groups.remove(old)
            ng.name = name


def group_node(ng, tree, name, x, y, links=()):
    """A group node for ``tree`` in ``ng``, its inputs linked from ``links`` ((output socket, input name))."""
    node = ng.nodes.new("ShaderNodeGroup")
    node.node_tree = tree
    node.name = node.label = name
    node.location = (x, y)
    for src, dst in links:
        ng.links.new(src, node.inputs[dst])
    return node


def place_bundles(ng, lights, models, build, shared, with_passes):
    """Build ``lights``' bundles with ``build`` (``surface_group.build_surface_bundle`` or
    ``world_group.build_world_bundle``, its images given) and put one group node per bundle in ``ng``, its inputs
    linked from ``shared`` (input name: output socket) and, with the passes, from the bundle before's Running Sum.

    Returns ([(group node, the bundle's models)], bundle trees for ``name_bundles``, the last Running Sum
    output or None)."""
    placed, trees, running = [], [], None
    for first, some, mods in split(lights, models):
        tree = build(first, some, mods, with_passes, running is not None)
        trees.append(tree)
        node = group_node(ng, tree, tree.name.removesuffix(groups.BUILDING), -300, -300 * len(placed), [
            *((src, n) for n, src in shared.items()), *(((running, RUNNING),) if running is not None else ())])
        placed.append((node, mods))
        running = node.outputs[RUNNING] if with_passes else None
    return placed, trees, running
