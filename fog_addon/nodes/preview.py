"""The switch of the viewport's preview of a fog that is added at render time (docs/decisions/
2026-11-29-viewport-preview.md).

The Compositor method adds its fog to the render's passes after the render, which the rendered viewport never runs
(Cycles gives the viewport compositor no passes; EEVEE's runs only when the user turns it on).  So the materials and
the World hold a preview of that fog behind the Params group's Viewport Preview value (``groups.PREVIEW``), the
factor of a Mix Shader: at 0 Cycles' SVM jumps over the preview's nodes and the picture is the render without them.
The value is 1 while an artist works with the add-on, and 0

* for every final render: ``render_pre`` sets it, ``render_complete`` and ``render_cancel`` set it back;
* in every saved file: ``save_pre`` sets it, ``save_post`` sets it back, so a farm, which opens the file without
  the add-on, renders no preview;
* in a session without a window (``blender -b``, bpy as a module): nobody looks at its viewport.

``forced`` keeps it at 1 through a render: ``render --viewport`` renders what the rendered viewport shows.
"""
import contextlib
from typing import Any, NamedTuple

import bpy

from . import closures, groups

class Shown(NamedTuple):
    """What the preview holds (``ops/plan.preview_models``), as the Surface and World groups build it."""
    lights: list
    models: list               # their models (rungs.LightModels, the Node Groups method's)
    shadows: Any = None        # {light name: shadow_maps.ShadowMap} of those whose shafts it shows (Cycles), or None
    g: float = 0.0             # the fog's anisotropy (the shafts' phase weight)
    sampled: Any = None        # the TableSpec of the other point lights and the glowing objects' points, sampled one
    #                            a sample (``preview_sampled``)
    day_table: Any = None      # the fog layer's fog light TableSpec where the compositor adds the daylight: the
    #                            preview's sun and sky, their glow, fog light and dimming, or None
    day_dims: bool = True      # the preview dims the surfaces' direct light by the sun's and the sky's dimming
    #                            (``sunsky.dims_surfaces``)
    sampled_dense: Any = None  # (grey albedo, scale) of the sampled lights' Dense Fog (``preview_sampled``), or None
    cycles: bool = False       # built for Cycles' viewport (a rebuild follows a change of engine): the sampled
    #                            lights' tables read by Cycles' own filter (``sockets.NodeOps.cycles``)


def factor(m, params):
    """The Viewport Preview value of the Params group node ``params`` as a value of ``m``."""
    return m.wrap(params.outputs[groups.PREVIEW])


def blend(m, final, previewed, shown):
    """``final`` where the preview is off, ``previewed`` where it shows (``shown``: ``factor``): final + shown x
    (previewed - final).  At 0 Cycles folds it to ``final`` when it compiles the shader (x 0 and + 0 fold away), so
    a final render runs none of ``previewed``'s nodes; elsewhere (EEVEE) it is final + 0, the same number."""
    return final + shown * (previewed - final)


_forced = []   # non-empty while a render must show the preview (``forced``)
_held = []     # non-empty while a final render runs (``before_render``)


def _node():
    """The Params group's Viewport Preview node, or None (no Params group, one built before it, or Blender's data
    not open to add-ons yet: while they register)."""
    node_groups = getattr(bpy.data, "node_groups", None)
    ng = node_groups.get(groups.PARAMS) if node_groups is not None else None
    return ng.nodes.get(groups.PREVIEW) if ng is not None and ng.library is None else None


def value():
    """The Viewport Preview value, or None without one."""
    node = _node()
    return None if node is None else node.outputs[0].default_value


def show(on):
    """Set the Viewport Preview value to 1 (``on``) or 0, where there is one and it differs (a change makes
    Blender evaluate every fogged material again)."""
    node = _node()
    if node is not None and node.outputs[0].default_value != float(on):
        node.outputs[0].default_value = float(on)


def _session():
    """True in an artist's session (Blender with a window), where someone looks at the viewport."""
    return not bpy.app.background


def working():
    """Whether the preview shows now: ``forced``, or an artist's session while no final render runs."""
    return bool(_forced) or (_session() and not _held)


@contextlib.contextmanager
def forced():
    """The preview shows for the renders within (``render --viewport``), whatever the handlers do."""
    _forced.append(True)
    show(True)
    try:
        yield
    finally:
        _forced.pop()
        show(working())


def before_render():
    """A final render starts (``render_pre``, every frame of an animation): no preview, unless ``forced``."""
    if not _held:
        _held.append(True)
    show(working())


def after_render():
    """A render ended or was cancelled, the file was saved or opened: the preview as the session has it."""
    _held.clear()
    show(working())


def before_save():
    """The file is about to be saved: it keeps no preview (a farm renders what F12 does)."""
    show(False)


def behind_switch(ng, params, shaders, label="Viewport Preview"):
    """The sum of the shader outputs ``shaders`` (``closures.shader_tree``) behind a Mix Shader in ``ng`` whose
    factor is the Viewport Preview output of the Params group node ``params``: its output socket, or None for
    no shaders.  At 0 Cycles' SVM jumps over every node that feeds only the preview (NODE_JUMP_IF_ZERO)."""
    if not shaders:
        return None
    mix = ng.nodes.new("ShaderNodeMixShader")
    mix.name = mix.label = label
    ng.links.new(params.outputs[groups.PREVIEW], mix.inputs[0])
    closures.shader_tree(ng, mix.inputs[2], shaders)
    return mix.outputs[0]
