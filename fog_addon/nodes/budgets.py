"""Shader size budgets: what one fogged material, and the World, can hold with the node groups, per engine.

Two engine limits decide how many lights a material can hold: EEVEE keeps a material's node constants in one
uniform block of 64 KiB, and Cycles' OSL indexes a shader group's layers with a signed 16-bit integer.  The cost
a light adds, by its ladder step (``rungs.STEPS``), was measured for each (the comments at the constants);
``eevee_budget`` and ``osl_budget`` give them as a ``predict.Budget``, which the Quality's choice must fit.
"""
from ..precompute.model import predict

# EEVEE keeps a material's node constants, its inlined groups' included, in one uniform block of at most
# 64 KiB; beyond it the material fails to link ("Uniform block node_tree too big (78832/65536)") and
# renders EEVEE's fallback.  Every unlinked float, vector or colour input is such a constant, the inputs
# a node's operation leaves unused too, and a group's constants are uniforms of every instance (1 000
# Multiply-by-a-constant nodes in a group used 20 times: 240 032 bytes).  The fog's math nodes mark
# theirs as constants to compile in (``sockets.NodeOps.inline``), but Blender does not save that mark:
# a saved file, as a farm renders it, has them all again.  So the budget counts what a light adds to a
# saved and reopened file, by ladder step (rungs.STEPS), and holds exactly the measured limits: the overflow
# lines' bytes fitted over N, the limit rendered and one more overflowing (bpy 5.0.1, benchmarks/
# shader_budgets.py: a ground and a sphere of Principled BSDF, N lights of one kind at one step; docs/
# measurements/2026-11-29-shader-budgets.md).  A material with many constants of its own holds fewer.
EEVEE_ENGINE = "BLENDER_EEVEE"
EEVEE_UNIFORM_LIMIT = 65536
EEVEE_UNIFORM_RESERVE = 864     # the material's own nodes and the Surface group's shared ones: the fits' bytes at
                                # N = 0 were 749-832 (bpy 5.0.1, Principled BSDF with emission, g = 0 and 0.85)
# A point light at g = 0 (bpy 5.0.1): full 2 618 bytes (overflow at 25, 27, 30 lights: 66 192, 71 424, 79 280;
# 24 render); glow only 1 938 (2 395 measured at g = 0.85, less the phase weight of a full light, taken as the
# same); off 334 at most (196 lights fit, measured before the tables' identity mapping; not measured since).
# The World: 936 a light whose glow is on (256 lights: 239 728, before that mapping).
EEVEE_MATERIAL_BYTES = (2618, 1938, 334, 0)   # by rungs.STEPS (LEFT_OUT: not in the groups)
EEVEE_WORLD_BYTES = (936, 936, 0, 0)
# Anisotropic fog (g != 0) adds the phase weight's constants to every glow (model.hg_weight).  A fully
# modelled point at g = 0.85, bpy 5.0.1: 3 075 bytes (overflow at 22, 23, 26 lights: 68 464, 71 552, 80 768;
# 21 render) against 2 618 at g = 0: 457 more.  Glow only at g = 0.85: 2 395 (overflow at 28, 30, 34 lights:
# 67 888, 72 672, 82 256; 27 render), its g = 0 cost not measured: the same 457 taken.  The World's background
# (1 of the glow's weights) taken as 150: an estimate.
EEVEE_ANISOTROPIC_EXTRA = ((457, 457, 0, 0), (150, 150, 0, 0))
# Dense Fog (multiple scattering: rungs.choose's multiple_albedo) adds its tables to a light's terms.  A fully
# modelled point at g = 0.85 with Dense Fog, bpy 5.0.1: 4 184 bytes (overflow at 16 and 20 lights: 67 744,
# 84 480; 15 render), 1 109 more than without.  Glow only taken as the same, the World's as half of its
# light's cost (its inlined nodes grow by half): estimates; spots and area lights are charged the point's.
EEVEE_DENSE_EXTRA = ((1109, 1109, 0, 0), (550, 550, 0, 0))


# Cycles' OSL: every node of a material becomes a layer of its OSL shader group, and liboslexec indexes
# the layers with a signed 16-bit integer: a 256-light material (53 195 nodes) crashed (SIGSEGV) while OSL
# optimised its groups (the index read as -32 763; no stack or memory exhaustion).  The budget counts a
# material's inlined nodes (Cycles' own simplification only removes some, so the count bounds the layers) and
# holds exactly the lights whose count stays within 32 767: a margin over what renders, since 9 fully modelled
# area lights (34 464 nodes) rendered clean and the crash's own layer count was not measured.  Nodes a light
# adds to a material with the OSL method, bpy 5.0.1, g = 0.85, fitted over N = 1 and 4 (counts are exact lines
# in N; checked at 153 and 154 points): a point 213 full, 61 glow only, 57 off; the World 14 with the glow on.
# The material with no light: 156 (a Principled BSDF).
OSL_LAYER_LIMIT = 32767
OSL_LAYER_RESERVE = 156    # the material's own nodes and the Surface group's shared ones (measured with no light)
OSL_MATERIAL_LAYERS = (213, 61, 57, 0)
OSL_WORLD_LAYERS = (14, 14, 0, 0)


# A spot light (rungs.spot_rungs) costs more: its glow kernel (spot.py: two cone intervals, the inner segment
# and two rims of quadrature) in the material and the World, and its scatter's tables (spot.scatter: F, the
# moments, the lobe response, read once for both lobes).  The extras over a point light's (the costs above at
# g = 0.85), bpy 5.0.1, g = 0.85.  OSL, nodes: a spot adds 668 full, 202 glow only, 81 off to a material and
# 131 to the World (N = 1 and 4).  EEVEE, saved and reopened: a fully modelled spot 12 128 bytes in a material
# (overflow at 6 and 7 spots: 73 536, 85 664; 5 render), glow only 10 064 (7 and 9: 71 280, 91 408; 6 render);
# the World about 8 900 a spot (9 spots: 80 240, with the World's 144 bytes of its own measured for area
# lights); off keeps the cone's factor (a few constants, estimated).
OSL_SPOT_EXTRA = ((455, 141, 24, 0), (117, 117, 0, 0))
EEVEE_SPOT_EXTRA = ((9053, 7669, 100, 0), (7814, 7814, 0, 0))
# An area light's glow (area.py: the emitter's quadrature) is bigger still.  OSL, nodes (bpy 5.0.1, g = 0.85,
# N = 1 and 4): 3 812 full, 3 407 glow only, 77 off in a material; 3 340 in the World.  EEVEE, saved and
# reopened: a fully modelled area light 19 936 bytes in a material (overflow at 4, 5, 7 lights: 80 544,
# 100 480, 140 352; 3 render) and 17 072 in the World (68 432, 85 504, 119 648: the World overflows at 4 too);
# glow only 18 048 in a material (6 and 8 lights: 109 088, 145 184; 3 render), the World's the same (102 576,
# 136 720); off as a spot's (estimated).
OSL_AREA_EXTRA = ((3599, 3346, 20, 0), (3326, 3326, 0, 0))
EEVEE_AREA_EXTRA = ((16861, 15653, 100, 0), (15986, 15986, 0, 0))


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


# Room kept for the user's own nodes in a material (and the World): the reserves above are the probes' bare
# Principled BSDF; a real material's textures and mixes add their own constants and layers.  An allowance, not a
# measurement: about one fully modelled point light's worth in EEVEE at g = 0.85 and five in OSL.
EEVEE_USER_ALLOWANCE = 3072   # bytes
OSL_USER_ALLOWANCE = 1024     # nodes


def osl_budget(spots=(), areas=(), allowance=OSL_USER_ALLOWANCE):
    """What a fogged material and the World can hold as one OSL shader group (predict.Budget); ``spots``:
    one bool per light, True for a spot or an area light; ``areas``: True for an area light; ``allowance``: nodes
    kept for the user's own (0: the measured limit itself, tests/test_shader_budgets.py)."""
    room = OSL_LAYER_LIMIT - OSL_LAYER_RESERVE - allowance
    return predict.Budget(_per_light((OSL_MATERIAL_LAYERS, OSL_WORLD_LAYERS), OSL_SPOT_EXTRA, spots,
                                     OSL_AREA_EXTRA, areas), (room, room),
                          "OSL's shader group size (32 767 nodes per material)")


def eevee_budget(g=0.0, spots=(), areas=(), dense=False, allowance=EEVEE_USER_ALLOWANCE):
    """What a fogged material and the World can hold in EEVEE (predict.Budget over the lights' steps) for
    fog of anisotropy g; ``spots``: one bool per light, True for a spot or an area light; ``areas``: True for
    an area light; ``dense``: Dense Fog (multiple scattering) on; ``allowance``: bytes kept for the user's own
    nodes (0: the measured limit itself, tests/test_shader_budgets.py)."""
    room = EEVEE_UNIFORM_LIMIT - EEVEE_UNIFORM_RESERVE - allowance
    costs = (EEVEE_MATERIAL_BYTES, EEVEE_WORLD_BYTES)
    for on, more in ((g, EEVEE_ANISOTROPIC_EXTRA), (dense, EEVEE_DENSE_EXTRA)):
        if on:
            costs = tuple(tuple(a + b for a, b in zip(c, extra)) for c, extra in zip(costs, more))
    return predict.Budget(_per_light(costs, EEVEE_SPOT_EXTRA, spots, EEVEE_AREA_EXTRA, areas), (room, room),
                          "EEVEE's uniform block (64 KiB of node constants per material)")
