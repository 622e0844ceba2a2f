"""The one map from every table the shaders read to its baker (numpy only).

Each baked array goes through the on-disk table cache (``table_cache.cached_bake``): baking every table
takes seconds in every process that needs them.

The Monte Carlo bakes of Dense Fog (``multiple``, ``spot_multiple``) and the glowing objects' weights
(``emitter_glow``) take seconds to tens of seconds: ``estimate_seconds`` says about how long a table's bake
takes before it starts (``missing``: the tables of a list not yet in the cache, with their estimates), and
their bakers take ``progress(done, total)``, which may raise ``BakeCancelled`` to stop (nothing is cached).
"""
import functools

from . import airlight, emitter_glow, multiple, spot, spot_multiple, surface, table_cache, tables
from .table_cache import BakeCancelled, cached_bake, is_cached  # noqa: F401 - BakeCancelled: the callers'

BASE_SECONDS = (1.5, 8.0)   # ``bakers(g)``'s tables cold on 2 cores at g 0, at any other g (its 256 x 256 airlight
                           # table): docs/measurements/2026-11-29-bake-time.md


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


def extra_baker(spec, progress=None):
    """The baker of a table that depends on more than g (``multiple.table_spec``: g and the albedo;
    ``spot_multiple.table_spec``: and a spot's cone), for ``table_cache.cached_bake``; ``progress(done,
    total)`` goes to the bake (it may raise ``BakeCancelled``)."""
    if is_multiple(spec):
        return functools.partial(multiple.bake_table, spec, progress=progress)
    if is_spot_multiple(spec):
        return functools.partial(spot_multiple.bake_table, spec, progress=progress)
    raise KeyError(f"no baker for table {spec.name!r}")


def is_multiple(spec):
    """True for a point light's multiply scattered table (``multiple.table_spec``)."""
    return spec.name.startswith("AnalyticFog Multiple (")


def is_spot_multiple(spec):
    """True for a spot's multiply scattered table (``spot_multiple.table_spec``)."""
    return spec.name.startswith("AnalyticFog Spot Multiple (")


def is_emitter_glow(spec):
    """True for the glowing objects' weights (``emitter_glow.table_spec``)."""
    return spec.name.startswith("AnalyticFog Emitter Glow (")


def table_array(spec, g=0.0, progress=None):
    """The float32 array of any table the models read (``bakers`` or ``extra_baker``), through the cache (and
    kept for the process); ``progress``: the bake's, if it bakes (``extra_baker``)."""
    known = bakers(g)
    if spec.name in known:
        return numpy_tables(float(g))[spec.name]
    if spec not in _EXTRA:
        _EXTRA[spec] = cached_bake(spec, extra_baker(spec, progress))
    return _EXTRA[spec]


_EXTRA = {}   # the arrays ``table_array`` read or baked this process, by spec


def _kept_from_cache(spec):
    """True if ``spec``'s table is in the cache; one of ``table_array``'s extra tables is then kept for the process
    as read (it was read whole to check it: ``table_array`` need not read it again)."""
    if spec.name in bakers(spec.g):
        return is_cached(spec)
    arr = table_cache.read(spec)
    if arr is not None:
        _EXTRA[spec] = arr
    return arr is not None


def estimate_seconds(spec, baked=()):
    """About how long baking ``spec``'s table takes from a cold cache on 2 cores, s (0 if it is in the cache):
    a spot's or an area light's multiply scattered table (``spot_multiple.estimate_seconds``), a point light's
    (``multiple.estimate_seconds``: with its orders' bake if they are not cached), the glowing objects' weights
    (``emitter_glow.estimate_seconds``, with the point light's table they read under Dense Fog unless it is in
    ``baked``: tables baked before it) or one of ``bakers(g)``'s (BASE_SECONDS for them all)."""
    if spec in _EXTRA or _kept_from_cache(spec):
        return 0.0
    if is_spot_multiple(spec):
        return spot_multiple.estimate_seconds(spec)
    if is_multiple(spec):
        orders = multiple.orders_spec(spec.g)
        cached = is_cached(orders) or any(is_multiple(b) and b.g == spec.g for b in baked)
        return multiple.estimate_seconds(spec, orders_cached=cached)
    if is_emitter_glow(spec):
        albedo = emitter_glow.multiple_albedo_of(spec)
        field = None if albedo is None else multiple.table_spec(spec.g, albedo)
        extra = 0.0 if field is None or field in baked else estimate_seconds(field, baked)
        return emitter_glow.estimate_seconds(spec) + extra
    if spec.name in bakers(spec.g):
        return BASE_SECONDS[0] if spec.g == 0.0 else BASE_SECONDS[1]
    raise KeyError(f"no estimate for table {spec.name!r}")


def missing(specs):
    """[(spec, seconds)] of ``specs`` not yet in the cache, in order, each with ``estimate_seconds`` (a spec
    listed twice, once; what an earlier one bakes not counted again): what a caller bakes, and announces,
    before building."""
    out = []
    for spec in dict.fromkeys(specs):
        seconds = estimate_seconds(spec, [s for s, _ in out])
        if seconds > 0.0:
            out.append((spec, seconds))
    return out


def label(spec):
    """A short name of ``spec``'s table for a progress line: "the spot table (cone 45 deg, blend 0.15)"."""
    inside = spec.name.split("(", 1)[1].rstrip(")") if "(" in spec.name else ""
    if is_spot_multiple(spec):
        kind = "the area light table" if "lambert" in spec.name else "the spot table"
        return f"{kind} ({inside})"
    if is_multiple(spec):
        return f"the point light table ({inside})"
    if is_emitter_glow(spec):
        return f"the glowing objects' table ({inside})"
    return f"the table {spec.name}"
