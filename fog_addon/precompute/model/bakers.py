"""Every table the models read, baked through the one registry of table kinds (numpy only).

A table's kind (``registry.kind_of``: a ``tables.TableKind``, found by the key its spec carries) gives its
baker, its bake-time estimate and its progress label; nothing here depends on a table's name.  Each baked
array goes through the on-disk table cache (``table_cache.cached_bake``): baking every table takes seconds in
every process that needs them, and is then kept for the process (``numpy_tables``, ``table_array``).

The Monte Carlo bakes of Dense Fog (``multiple``, ``spot_multiple``) and the glowing objects' weights
(``emitter_glow``) take seconds to tens of seconds: ``estimate_seconds`` says about how long a table's bake
takes before it starts (``missing``: the tables of a list not yet in the cache, with their estimates), and
their bakers take ``progress(done, total)``, which may raise ``BakeCancelled`` to stop (nothing is cached).
"""
import functools

from ..core import table_cache, tables
from ..core.table_cache import BakeCancelled, cached_bake, is_cached  # noqa: F401 - BakeCancelled: the callers'
from . import registry



def bakers(g=0.0):
    """{TableSpec.name: (TableSpec, baker)} of the tables every fog of Henyey-Greenstein anisotropy g reads
    (``registry.PER_G``; the lobe response and the specular albedo are the same for every g)."""
    out = {}
    for kind in registry.PER_G:
        spec = kind.make(g)
        out[spec.name] = (spec, lambda spec=spec, kind=kind: _bake(kind, spec))
    return out


@functools.lru_cache(maxsize=None)
def numpy_tables(g=0.0):
    """{name: float32 array} of every table for anisotropy g, baked (or read from the cache) once per process
    (read-only use)."""
    return {name: cached_bake(spec, bake) for name, (spec, bake) in bakers(g).items()}


def extra_baker(spec, progress=None):
    """The baker of ``spec``'s table (its kind's, ``registry.kind_of``), for ``table_cache.cached_bake``;
    ``progress(done, total)`` goes to the bake (it may raise ``BakeCancelled``).  KeyError for a table baked per
    scene (its kind has no baker)."""
    kind = registry.kind_of(spec)
    if kind.bake is None:
        raise KeyError(f"{spec.name!r} is baked per scene, not by its spec")
    return functools.partial(_bake, kind, spec, progress)


def _bake(kind, spec, progress=None):
    """``kind``'s bake of ``spec``, handed READER if it reads other tables (``TableKind.reads``)."""
    if kind.reads:
        return kind.bake(spec, progress=progress, tables=READER)
    return kind.bake(spec, progress=progress)


def _is(key):
    def test(spec):
        return spec.kind == key
    test.__doc__ = f"True for a table of the kind {key!r}."
    return test


is_multiple = _is("multiple")               # a point light's multiply scattered table (``multiple.table_spec``)
is_spot_multiple = _is("spot_multiple")     # a spot's or an area light's (``spot_multiple.table_spec``)
is_emitter_glow = _is("emitter_glow")       # the glowing objects' weights (``emitter_table.table_spec``)


def table_array(spec, g=0.0, progress=None):
    """The float32 array of any table with a baker, through the cache (and kept for the process): one of
    ``bakers(g)``'s from ``numpy_tables`` (that of spec.g if it is not one of g's), any other from its kind's
    baker (``extra_baker``); ``progress``: the bake's, if it bakes."""
    kind = registry.kind_of(spec)
    if kind.per_g:
        tabs = numpy_tables(float(g))
        return tabs[spec.name] if spec.name in tabs else numpy_tables(float(spec.g))[spec.name]
    if spec not in _EXTRA:
        _EXTRA[spec] = cached_bake(spec, extra_baker(spec, progress))
    return _EXTRA[spec]


_EXTRA = {}   # the arrays ``table_array`` read or baked this process, by spec


def _kept_from_cache(spec, kind):
    """True if ``spec``'s table is in the cache; an image's table outside ``bakers(g)`` is then kept for the process
    as read (it was read whole to check it: ``table_array`` need not read it again)."""
    if kind.per_g or not kind.image:
        return is_cached(spec)
    arr = table_cache.read(spec)
    if arr is not None:
        _EXTRA[spec] = arr
    return arr is not None


def _with_needs(specs):
    """``specs`` and, recursively, the tables their bakes read (``TableKind.needs``)."""
    out, todo = set(), list(specs)
    while todo:
        spec = todo.pop()
        if spec not in out:
            out.add(spec)
            todo += registry.kind_of(spec).needs(spec)
    return out


def estimate_seconds(spec, baked=()):
    """About how long baking ``spec``'s table takes from a cold cache on 2 cores, s (0 if it is in the cache): its
    kind's estimate (``TableKind.estimate``; ``registry.BASE_SECONDS`` for all of ``bakers(g)``'s), plus that of each table its
    bake reads (``TableKind.needs``: a point light's orders, the point light's table that the glowing objects'
    weights read under Dense Fog) unless that is cached or read by ``baked`` (tables baked before it) too."""
    return _seconds(spec, _with_needs(baked))


def _seconds(spec, baked):
    kind = registry.kind_of(spec)
    if kind.bake is None:
        raise KeyError(f"no estimate for table {spec.name!r}: it is baked per scene")
    if spec in baked or spec in _EXTRA or _kept_from_cache(spec, kind):
        return 0.0
    return kind.estimate(spec) + sum(_seconds(need, baked) for need in kind.needs(spec))


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
    """A short name of ``spec``'s table for a progress line (``TableKind.label``): "the spot table (cone 45 deg,
    blend 0.15)"."""
    return registry.kind_of(spec).label(spec)


READER = tables.TableReader(table_array, numpy_tables)   # how a bake reads other tables (``TableKind.reads``)
