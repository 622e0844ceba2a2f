"""Analytic Fog: closed-form single-scattering fog for Blender (Cycles and EEVEE).

Blender entry points live here; everything under ``precompute`` is pure numpy
and imports without Blender.
"""


def register():
    from . import props, ops
    props.register()
    ops.register()


def unregister():
    from . import props, ops
    ops.unregister()
    props.unregister()
