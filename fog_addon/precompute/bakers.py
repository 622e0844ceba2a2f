"""The one map from every table the shaders read to its baker (numpy only).

Each baked array goes through the on-disk table cache (``table_cache.cached_bake``): baking every table
takes seconds in every process that needs them.
"""
import functools

from . import airlight, multiple, spot, spot_multiple, surface, tables
from .table_cache import cached_bake


@functools.lru_cache(maxsize=None)
def _spot_tables(g):
    return spot.bake_scatter_tables(g)


def bakers(g=0.0):
    """{TableSpec.name: (TableSpec, baker)} of the tables for Henyey-Greenstein anisotropy g (the lobe
    response and the specular albedo are the same for every g)."""
    air, surf = tables.anisotropic(tables.AIRLIGHT, g), tables.anisotropic(tables.SURFACE, g)
    out = {air.name: (air, lambda: airlight.bake_airlight_table(air)),
           surf.name: (surf, lambda: surface.bake_surface_table(surf)),
           tables.LOBE_RESPONSE.name: (tables.LOBE_RESPONSE, spot.bake_lobe_response),
           tables.SPECULAR_ALBEDO.name: (tables.SPECULAR_ALBEDO, surface.bake_specular_albedo)}
    spot_spec = tables.anisotropic(tables.SPOT_MOMENTS, g)
    out[spot_spec.name] = (spot_spec, lambda: _spot_tables(float(g)))
    return out


@functools.lru_cache(maxsize=None)
def numpy_tables(g=0.0):
    """{name: float32 array} of every table for anisotropy g, baked (or read from the cache) once per process
    (read-only use)."""
    return {name: cached_bake(spec, bake) for name, (spec, bake) in bakers(g).items()}


def extra_baker(spec):
    """The baker of a table that depends on more than g (``multiple.table_spec``: g and the albedo;
    ``spot_multiple.table_spec``: and a spot's cone), for
    ``table_cache.cached_bake``."""
    if spec.name.startswith("AnalyticFog Multiple ("):
        return functools.partial(multiple.bake_table, spec)
    if is_spot_multiple(spec):
        return functools.partial(spot_multiple.bake_table, spec)
    raise KeyError(f"no baker for table {spec.name!r}")


def is_spot_multiple(spec):
    """True for a spot's multiply scattered table (``spot_multiple.table_spec``)."""
    return spec.name.startswith("AnalyticFog Spot Multiple (")


def table_array(spec, g=0.0):
    """The float32 array of any table the models read (``bakers`` or ``extra_baker``), through the cache."""
    known = bakers(g)
    if spec.name in known:
        return numpy_tables(float(g))[spec.name]
    return _extra_array(spec)


@functools.lru_cache(maxsize=None)
def _extra_array(spec):
    return cached_bake(spec, extra_baker(spec))
