"""Analytic Fog: closed-form single-scattering fog for Blender (Cycles and EEVEE).

Blender entry points live here; everything under ``precompute`` is pure numpy
and imports without Blender.
"""


def _modules():
    from . import handlers, props, ui
    from .ops import operators
    return props, operators, ui, handlers


def register():
    for m in _modules():
        m.register()


def unregister():
    for m in reversed(_modules()):
        m.unregister()
