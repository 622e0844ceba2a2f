"""Analytic Fog: closed-form single-scattering fog for Blender (Cycles and EEVEE).

Blender entry points live here; everything under ``precompute`` is pure numpy
and imports without Blender.
"""


def _modules():
    from . import handlers, ops, props, ui
    return props, ops, ui, handlers


def register():
    for m in _modules():
        m.register()


def unregister():
    for m in reversed(_modules()):
        m.unregister()
