"""The one list of table kinds (numpy only): every table the add-on bakes or packs belongs to exactly one.

A ``tables.TableKind`` is one phenomenon's tables: its spec constructor, its baker, its bake-time estimate and its
progress label.  Each phenomenon's module defines its own (``TABLE_KINDS``); the tables every fog of anisotropy g
reads (``bakers.bakers(g)``) are defined here beside their layouts' constants in ``tables.py``, and so is the pixel
filter's, whose two specs are constants of ``pixel.py`` (``TableKind.fixed``).  ``kind_of`` finds a spec's kind
by the key its constructor gave it (``TableSpec.kind``), or for a constant spec by equality: never from its name.
``bakers`` bakes, times and labels every table through it.
"""
import functools

from ..physics.daylight import daylight_tables
from ..physics.emitter import emitter_glow
from ..physics.point import airlight, multiple, surface
from ..physics.spot import spot, spot_multiple
from ..core import tables
from . import pixel


def _bake_airlight(spec, progress=None):
    return airlight.bake_airlight_table(spec)


def _bake_surface(spec, progress=None):
    return surface.bake_surface_table(spec)


def _bake_lobe_response(spec, progress=None):
    return spot.bake_lobe_response()


def _bake_specular_albedo(spec, progress=None):
    return surface.bake_specular_albedo()


@functools.lru_cache(maxsize=None)
def _spot_tables(g):
    return spot.bake_scatter_tables(g)


def _bake_spot_moments(spec, progress=None):
    return _spot_tables(float(spec.g))


def _bake_pixel_filter(spec, progress=None):
    """The pixel filter's table of ``spec`` (one of ``pixel.FILTERS``)."""
    return {s: bake for s, bake in pixel.FILTERS.values()}[spec]()


BASE_SECONDS = (1.5, 2.5)   # ``bakers.bakers(g)``'s tables cold in a new process at g 0, at any other g (its
                           # 256 x 256 airlight table): docs/measurements/2026-11-30-test-time.md


def _per_g_seconds(spec):
    """BASE_SECONDS shared by the tables of ``bakers.bakers(g)``: about how long they all bake, s."""
    return BASE_SECONDS[0] if spec.g == 0.0 else BASE_SECONDS[1]


def _anisotropic(spec):
    return lambda g=0.0: tables.anisotropic(spec, g)


def _constant(spec):
    return lambda g=0.0: spec


# the tables of bakers(g), in its order
PER_G = (
    tables.TableKind("airlight", make=_anisotropic(tables.AIRLIGHT), bake=_bake_airlight, estimate=_per_g_seconds,
                     per_g=True),
    tables.TableKind("surface", make=_anisotropic(tables.SURFACE), bake=_bake_surface, estimate=_per_g_seconds,
                     per_g=True),
    tables.TableKind("lobe_response", make=_constant(tables.LOBE_RESPONSE), bake=_bake_lobe_response,
                     estimate=_per_g_seconds, per_g=True),
    tables.TableKind("specular_albedo", make=_constant(tables.SPECULAR_ALBEDO), bake=_bake_specular_albedo,
                     estimate=_per_g_seconds, per_g=True),
    tables.TableKind("spot_moments", make=_anisotropic(tables.SPOT_MOMENTS), bake=_bake_spot_moments,
                     estimate=_per_g_seconds, per_g=True),
)

PIXEL_FILTER = tables.TableKind("pixel_filter", bake=_bake_pixel_filter, estimate=lambda spec: 1.5,   # s, 2 cores
                                fixed=tuple(s for s, _ in pixel.FILTERS.values()))

KINDS = (*PER_G, PIXEL_FILTER, *multiple.TABLE_KINDS, *spot_multiple.TABLE_KINDS, *emitter_glow.TABLE_KINDS,
         *daylight_tables.TABLE_KINDS)
BY_KEY = {kind.key: kind for kind in KINDS}
_FIXED = {spec: kind for kind in KINDS for spec in kind.fixed}
assert len(BY_KEY) == len(KINDS), "two table kinds share a key"


def kinds_of(spec):
    """Every registered kind ``spec`` belongs to: the one its key names, and any that lists it as a constant (one,
    for every table the add-on makes: tests/test_table_registry.py)."""
    return [kind for kind in KINDS if kind.key == spec.kind or spec in kind.fixed]


def kind_of(spec):
    """The ``TableKind`` of ``spec``: by its key (``TableSpec.kind``), else the kind listing it as a constant;
    KeyError for a table no kind makes (a shadow map: ``shadow_maps.py`` bakes it from the scene)."""
    if spec.kind:
        return BY_KEY[spec.kind]
    try:
        return _FIXED[spec]
    except KeyError:
        raise KeyError(f"no table kind makes {spec.name!r}") from None
