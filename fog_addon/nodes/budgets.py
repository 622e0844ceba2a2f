"""Shader size budgets: what one fogged material, and the World, can hold with the node groups, per engine.

Two engine limits decide how many lights a material can hold: EEVEE keeps a material's node constants in one
uniform block of 64 KiB, and Cycles' OSL indexes a shader group's layers with a signed 16-bit integer.  The cost
a light adds, by its ladder step (``rungs.STEPS``), was measured for each (the comments at the constants);
``eevee_budget`` and ``osl_budget`` give them as a ``predict.Budget``, which the Quality's choice must fit.
"""
from ..precompute import predict

# EEVEE keeps a material's node constants, its inlined groups' included, in one uniform block of at most
# 64 KiB; beyond it the material fails to link ("Uniform block node_tree too big (78832/65536)") and
# renders EEVEE's fallback.  Every unlinked float, vector or colour input is such a constant, the inputs
# a node's operation leaves unused too, and a group's constants are uniforms of every instance (1 000
# Multiply-by-a-constant nodes in a group used 20 times: 240 032 bytes).  The fog's math nodes mark
# theirs as constants to compile in (``sockets.NodeOps.inline``), but Blender does not save that mark:
# a saved file, as a farm renders it, has them all again.  So the budget counts what a light's group
# costs in a saved and reopened file, by ladder step (rungs.STEPS), from the overflow messages of the
# many-lights scene in EEVEE (bpy 5.0.1, at 709fad8): full 2 848 bytes (24 and 36 lights: 68 656,
# 102 832), glow only 1 812 (40, 48, 72 lights: 72 784, 87 280, 130 768), off at most 334 (196 lights
# fit, measured before the tables' identity mapping, which off does not use); the World at most 936
# per light whose glow is on (256 lights: 239 728, before that mapping).  As built (until the file is
# reopened) a light costs 112 / 80 / 16 bytes and the World 48.  (Before the tables' identity mapping
# of ``sockets.NodeOps._tap``: 4 610 and 2 517; before the lighter table lookup: 4 910 and 2 649.)
EEVEE_ENGINE = "BLENDER_EEVEE"
EEVEE_UNIFORM_LIMIT = 65536
EEVEE_UNIFORM_RESERVE = 8192    # the material's own nodes and the Surface group's shared ones (272 measured
                                # for a bare Principled BSDF)
EEVEE_MATERIAL_BYTES = (2848, 1812, 334, 0)   # by rungs.STEPS (LEFT_OUT: not in the groups)
EEVEE_WORLD_BYTES = (936, 936, 0, 0)
# Anisotropic fog (g != 0) adds the phase weight's constants to every glow (model.hg_weight: 8 per
# segment, 1 per background tail).  Measured, saved and reopened, 36 lights fully modelled: 103 552 bytes
# at g = 0, 129 184 at g = 0.85: 712 more per full light.  Glow only keeps the same glow: taken as the
# same 712; the World's background (1 of the 8 weights, and the rows' mapping) taken as 150: estimates.
EEVEE_ANISOTROPIC_EXTRA = ((712, 712, 0, 0), (150, 150, 0, 0))


# Cycles' OSL: every node of a material becomes a layer of its OSL shader group, and liboslexec indexes
# the layers with a signed 16-bit integer: a 256-light material (53 195 nodes) crashed (SIGSEGV) while OSL
# optimised its groups (the index read as -32 763; no stack or memory exhaustion: helper's core dump, this
# stop).  Nodes a light adds to a material, inlined (counted at 16 lights; Cycles' own simplification only
# removes some): 248 full, 63 glow only, 59 off; the World 15 with the glow on.
OSL_LAYER_LIMIT = 32767
OSL_LAYER_RESERVE = 2767   # the material's own nodes and the Surface group's shared ones (48 with no light)
OSL_MATERIAL_LAYERS = (248, 63, 59, 0)
OSL_WORLD_LAYERS = (15, 15, 0, 0)


# A spot light (rungs.spot_rungs) costs more: its glow kernel (spot.py: two cone intervals, the inner segment
# and two rims of quadrature) in the material and the World, and its scatter's tables (spot.scatter: F, the
# moments, the lobe response, read once for both lobes).  Measured at bpy 5.0.1 (helper, at 99dbfcf), g = 0.85,
# files saved and reopened.  OSL, nodes a light adds with the OSL method (8 vs 4 lights): full 924 a spot
# against 249 a point, glow only 222 against 64, off 92 against 60; the World 149 against 16.  EEVEE (overflow
# messages): a fully modelled spot 13 276 bytes in a material (8 and 12 spots: 107 008, 160 112), a spot with
# its glow only 9 836 (12 and 16: 118 832, 158 176), a point 3 348 (24 and 32 points: 80 656, 107 440); the
# World 8 940 a spot (8, 12, 16: 71 632, 107 392, 143 152), 652 a point.  The extras over the budgeted point
# (EEVEE_MATERIAL_BYTES plus EEVEE_ANISOTROPIC_EXTRA) with a 3 % margin; off keeps the cone's factor (a few
# constants, estimated).
OSL_SPOT_EXTRA = ((700, 170, 40, 0), (140, 140, 0, 0))
# An area light's glow (area.py: the emitter's quadrature) is far bigger in OSL: measured at bpy 5.0.1 (g = 0.85,
# N = 1 and 4, docs/measurements/2026-11-29-shader-budgets.md) 3 812 nodes a fully modelled area light adds to a
# material and 3 340 to the World.  The extras over the point's, with a 3 % margin; glow only taken as the World's
# glow, off as a spot's (estimates: not measured).
OSL_AREA_EXTRA = ((3680, 3380, 40, 0), (3430, 3430, 0, 0))
EEVEE_SPOT_EXTRA = ((10010, 7540, 100, 0), (8960, 8960, 0, 0))


def _per_light(costs, extra, spots, area_extra=None, areas=()):
    """(K, N, STEPS) costs of lights ``spots`` (True for a spot or an area light) from the point light's ``costs``
    (K, STEPS) and a spot's ``extra``, an area light's (``areas``: True for one) ``area_extra`` where given; the
    (K, STEPS) costs themselves when no light is a spot."""
    if not any(spots):
        return costs
    areas = list(areas) + [False] * (len(spots) - len(areas))
    return tuple(tuple(tuple(c + (a if area and area_extra is not None else e if spot else 0)
                             for c, e, a in zip(cost, more, area_more)) for spot, area in zip(spots, areas))
                 for cost, more, area_more in zip(costs, extra, area_extra or extra))


def material_nodes(steps, spots):
    """About how many nodes the fog's lights add to each fogged material, inlined (OSL_MATERIAL_LAYERS and
    OSL_SPOT_EXTRA: Cycles' SVM sets up the same graph as OSL); ``steps``: each light's (rungs.STEPS),
    ``spots``: True for a spot."""
    return sum(OSL_MATERIAL_LAYERS[k] + (OSL_SPOT_EXTRA[0][k] if spot else 0) for k, spot in zip(steps, spots))


def osl_budget(spots=(), areas=()):
    """What a fogged material and the World can hold as one OSL shader group (predict.Budget); ``spots``:
    one bool per light, True for a spot or an area light; ``areas``: True for an area light."""
    room = OSL_LAYER_LIMIT - OSL_LAYER_RESERVE
    return predict.Budget(_per_light((OSL_MATERIAL_LAYERS, OSL_WORLD_LAYERS), OSL_SPOT_EXTRA, spots,
                                     OSL_AREA_EXTRA, areas), (room, room),
                          "OSL's shader group size (32 767 nodes per material)")


def eevee_budget(g=0.0, spots=()):
    """What a fogged material and the World can hold in EEVEE (predict.Budget over the lights' steps) for
    fog of anisotropy g; ``spots``: one bool per light, True for a spot."""
    room = EEVEE_UNIFORM_LIMIT - EEVEE_UNIFORM_RESERVE
    costs = (EEVEE_MATERIAL_BYTES, EEVEE_WORLD_BYTES)
    if g:
        costs = tuple(tuple(a + b for a, b in zip(c, extra)) for c, extra in zip(costs, EEVEE_ANISOTROPIC_EXTRA))
    return predict.Budget(_per_light(costs, EEVEE_SPOT_EXTRA, spots), (room, room),
                          "EEVEE's uniform block (64 KiB of node constants per material)")
