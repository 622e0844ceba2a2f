"""The fog's shader node groups: what each is called, how one is built beside the one in use and swapped in,
which are up to date, and the params group that every other reads.

One shared copy of each group per .blend:

* ``AnalyticFog Params``: the fog's settings (density beta per scene unit, albedo colour: ``set_params``).
* ``AnalyticFog Light [models]``: ``shading.shade_point`` — one light seen
  from a surface point (airlight along the camera ray, fog light scattered
  onto the surface, direct-light attenuation) with the rungs ``models``
  (``rungs.LightModels``), instanced once per light that uses those models (``light_groups.py``).
* ``AnalyticFog Background Light [model]``: ``shading.background_point`` —
  one light's airlight on a ray that meets no surface (the World).

  A rung that runs only in OSL becomes a Script node (``osl.py``, Cycles only).
* ``AnalyticFog Surface`` / ``AnalyticFog World``: ``shading.shade_surface`` /
  ``shade_background`` over the scene's fog lights (``surface_group.py``, ``world_group.py``), the lights in
  bundle groups (``light_bundles.py``), their positions and intensities fed by drivers (``drivers.py``: no
  Python expression, so they evaluate with auto-run off and without the add-on).  Rebuilding these two when
  lights or their models change leaves every material untouched.

The compositor's groups (``comp_fog.py``) are made and swapped in the same way.  Each group records the
fingerprint of the code that built it (``owned.BUILT``, ``code_fingerprint``: all of the add-on's source): a
saved file made by other code rebuilds it.
"""
import re

import bpy

from ..precompute.core import fingerprint
from ..precompute.model import rungs
from . import owned, sockets

PARAMS = "AnalyticFog Params"
LIGHT = "AnalyticFog Light"
BACKGROUND_LIGHT = "AnalyticFog Background Light"
SURFACE = "AnalyticFog Surface"
WORLD = "AnalyticFog World"
SURFACE_LIGHTS = SURFACE + " Lights"   # bundles: "AnalyticFog Surface Lights 1-8", ... (``light_bundles.split``)
WORLD_LIGHTS = WORLD + " Lights"
SURFACE_TAILS = SURFACE + " Tails"     # bundles of the glows past glass and mirrors (``glass_tails.build_tail_bundle``)
SURFACE_PREVIEW = SURFACE + " Preview Lights"   # bundles of the viewport's preview (``nodes/preview.py``)
WORLD_PREVIEW = WORLD + " Preview Lights"
SURFACE_SEGMENT = SURFACE + " Segment Lights"   # the fog light a surface reflects on a segment past glass (Compositor)
PREVIEW_SHAFT = "AnalyticFog Preview Shaft"   # "<PREVIEW_SHAFT> <light name>" (``preview_shafts.py``)
_BUNDLES = (SURFACE_LIGHTS, WORLD_LIGHTS, SURFACE_TAILS, SURFACE_PREVIEW, WORLD_PREVIEW, SURFACE_SEGMENT)
_BUNDLE_NAME = re.compile(rf"^({'|'.join(re.escape(p) for p in _BUNDLES)}) \d+-\d+$")

FOG_PROP = "analytic_fog"   # custom-property key marking data the fog made or changed
BUILDING = " (building)"     # name suffix of a group being built beside the one in use
F, V, C = "NodeSocketFloat", "NodeSocketVector", "NodeSocketColor"


def code_fingerprint():
    """Fingerprint of the code that decides a group's content: all of the add-on's source
    (``fingerprint.package_fingerprint``: no list of modules to keep)."""
    return fingerprint.package_fingerprint()


def light_group_name(models):
    """Name of the per-light surface group for ``models`` (rungs.LightModels)."""
    return f"{LIGHT} [{models.airlight.name}, {models.scatter.name}, {models.direct.name}]"


def background_group_name(models):
    return f"{BACKGROUND_LIGHT} [{models.background.name}]"


def all_group_names():
    """Every group name the fog can make (for Remove and for merging appended copies): the light bundles
    this file has (their names without a ``.NNN`` suffix) first, as they use the per-light groups (so
    deleting unused groups in this order leaves none behind), then the fixed ones."""
    names = sorted(base for ng in bpy.data.node_groups
                   if _BUNDLE_NAME.match(base := owned.base_name(ng.name)))
    names += [PARAMS, SURFACE, WORLD]
    # the viewport preview's own groups (``preview_shafts``, ``preview_sampled``): the Surface, World and preview
    # bundles use them
    names += sorted(base for ng in bpy.data.node_groups if ng.get(FOG_PROP) and (base := owned.base_name(ng.name))
                    .startswith((PREVIEW_SHAFT + " ", SURFACE + " Preview Sampled", WORLD + " Preview Sampled")))
    for pref in rungs.PREFERENCES:
        for kind in rungs.LIGHT_KINDS:
            models = rungs.choose(pref, kind=kind)
            names += [light_group_name(models), background_group_name(models)]
    names += sorted(base for ng in bpy.data.node_groups if ng.get(FOG_PROP)   # another anisotropy's
                    and (base := owned.base_name(ng.name)).startswith((f"{LIGHT} [", f"{BACKGROUND_LIGHT} [")))
    # the kernels' shared groups (sockets.NodeOps.group), last: the light groups use them, and the larger
    # kernels the smaller ones (deleted in the order of their size)
    kernels = [ng for ng in bpy.data.node_groups if ng.get(FOG_PROP) and ng.name.startswith(sockets.KERNEL_GROUP)]
    names += [owned.base_name(ng.name) for ng in sorted(kernels, key=lambda ng: -_kernel_depth(ng))]
    return list(dict.fromkeys(names))


def _kernel_depth(ng):
    """How deep ``ng``'s group nodes nest (0: none): a group is deleted before those it uses."""
    return max((1 + _kernel_depth(n.node_tree) for n in ng.nodes
                if n.bl_idname in ("ShaderNodeGroup", "CompositorNodeGroup") and n.node_tree is not None), default=0)


def new_group(name, inputs, outputs, tree_type="ShaderNodeTree"):
    """An empty shader group (or ``tree_type``'s) for ``name`` with the given (name, socket type) interface.

    An unused group of that name is emptied and reused; one in use is left
    alone and a new group is built beside it, for ``install`` to swap in:
    every node added to a group that 1 000 materials use costs ~50 ms, to a
    fresh one almost nothing.
    """
    ng = bpy.data.node_groups.get(name)
    if ng is None or ng.users:
        ng = bpy.data.node_groups.new(name + BUILDING, tree_type)
    ng.animation_data_clear()
    ng.nodes.clear()
    want = [(n, t, "INPUT") for n, t in inputs] + [(n, t, "OUTPUT") for n, t in outputs]
    have = sorted(((i.name, i.socket_type, i.in_out) for i in ng.interface.items_tree if i.item_type == "SOCKET"),
                  key=lambda s: s[2])   # Blender lists outputs first; a stable sort puts them after the inputs
    if have != want:
        ng.interface.clear()
        for n, t, io in want:
            ng.interface.new_socket(n, in_out=io, socket_type=t)
    ng[FOG_PROP] = True
    ng.pop(owned.BUILT, None)
    gin = ng.nodes.new("NodeGroupInput")
    gout = ng.nodes.new("NodeGroupOutput")
    gin.location = (-300, 0)
    gout.location = (4000, 0)
    return ng, gin, gout


def install(ng, name):
    """Put a group built by ``new_group`` in place of the old ``name``: its users are remapped to it."""
    if ng.name == name:
        return ng
    old = bpy.data.node_groups.get(name)
    if old is not None:
        old.user_remap(ng)
        bpy.data.node_groups.remove(old)
    ng.name = name
    return ng


def up_to_date(name):
    """The group ``name`` if this code built it and its tables are all there (rebuilding costs seconds)."""
    ng = bpy.data.node_groups.get(name)
    if ng is None or ng.get(owned.BUILT) != code_fingerprint():
        return None
    return ng if all(n.image is not None for n in ng.nodes if n.bl_idname == "ShaderNodeTexImage") else None


def build_params(beta, albedo, world_light=False):
    ng, gin, gout = new_group(PARAMS, [], [("Beta", F), ("Albedo", C), (WORLD_LIGHT, F), (PREVIEW, F)])
    for name, kind, value in (("Beta", "ShaderNodeValue", beta), ("Albedo", "ShaderNodeRGB", (*albedo, 1.0)),
                              (WORLD_LIGHT, "ShaderNodeValue", float(world_light)),
                              (PREVIEW, "ShaderNodeValue", 0.0)):
        node = ng.nodes.new(kind)
        node.name = node.label = name
        node.outputs[0].default_value = value
        ng.links.new(node.outputs[0], gout.inputs[name])
    return install(ng, PARAMS)


WORLD_LIGHT = "World Light"   # the params group's 0/1: the World lights surfaces through the fog
PREVIEW = "Viewport Preview"   # the params group's 0/1: the viewport's preview of a fog added at render time shows
#                                (``nodes/preview.py``; 0 in saved files and final renders)
ANISOTROPY_KEY = "analytic_fog_anisotropy"   # on the params group: the g the lights' models are built for


def set_anisotropy(g):
    """Store the fog's anisotropy g in the params group (which must exist)."""
    bpy.data.node_groups[PARAMS][ANISOTROPY_KEY] = float(g)


def set_params(beta, albedo, g=None, world_light=None, preview=None):
    """Write the fog's settings into the shared params group (creating it if needed, or if an older
    version made it); ``g``: the anisotropy to store, ``world_light``: whether the World lights surfaces
    through the fog (``shading.shade_background``), ``preview``: whether the viewport's preview shows
    (``preview.working``) (None: keep them)."""
    ng = bpy.data.node_groups.get(PARAMS)
    if ng is None or ng.nodes.get(WORLD_LIGHT) is None or ng.nodes.get(PREVIEW) is None:
        kept = ng.get(ANISOTROPY_KEY) if ng is not None else None
        ng = build_params(beta, albedo, bool(world_light))
        if kept is not None:
            ng[ANISOTROPY_KEY] = kept
    if g is not None and ng.get(ANISOTROPY_KEY, 0.0) != float(g):
        set_anisotropy(g)
    ng.nodes["Beta"].outputs[0].default_value = beta
    ng.nodes["Albedo"].outputs[0].default_value = (*albedo, 1.0)
    if world_light is not None:
        ng.nodes[WORLD_LIGHT].outputs[0].default_value = float(world_light)
    if preview is not None and ng.nodes[PREVIEW].outputs[0].default_value != float(preview):
        ng.nodes[PREVIEW].outputs[0].default_value = float(preview)
    return ng
