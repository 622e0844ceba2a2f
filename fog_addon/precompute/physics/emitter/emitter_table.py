"""The glowing objects' tables (``emitter_glow``): their layouts, names, kinds and how long they bake.

What the registry (``registry.py``) must know of the tables without importing their bakers: ``table_spec`` names
and sizes the weights' table, ``facing_spec`` the facing factor's, ``multiple_albedo_of`` gives the Dense Fog albedo
a weights' table was made for, ``estimate_seconds`` how long its bake takes, ``needs`` the table its bake reads.  The
weights themselves, the field they are fitted to, the facing factor and the tables' ``TableKind`` records are
``emitter_glow``'s.
"""
from ...core import tables

SIZES = tuple(2 ** k for k in range(0, 10))   # the Blur nodes' sizes, px (sigma = size / 3: 0.33 to 171 px)
T_MIN, T_MAX = 1e-3, 30.0     # the weights' table's optical depths
T_COUNT = 32                  # its columns, single scattering (uniform in ln T + T: ``emitter_glow.table_x``)
T_COUNT_DENSE = 48            # its columns with Dense Fog (the halo's shape changes faster with T)


def table_spec(g, pixel_angle, multiple_albedo=None):
    """The TableSpec of the weights for anisotropy ``g``, ``pixel_angle`` (rad/px) and, with Dense Fog, the
    multiply scattered field's albedo: one row per size (its share), and the normalisation's row
    (``emitter_glow.bake_weights``), of the kernel's near part (``emitter_glow.far_window``)."""
    albedo = None if multiple_albedo is None else float(multiple_albedo)
    dense = "" if albedo is None else f", multiple W0 {albedo:.3f}"
    count = T_COUNT if albedo is None else T_COUNT_DENSE
    return tables.TableSpec(f"AnalyticFog Emitter Glow Near (g {float(g):+.3f}, {float(pixel_angle):.6g} rad/px{dense})",
                            count, len(SIZES) + 1, g=float(g), kind=KIND_KEY,
                            args=(float(g), float(pixel_angle), albedo))


COLUMN_SECONDS = 0.05   # ``bake_weights``' time a column on 2 cores (docs/measurements/2026-11-29-bake-time.md)


def multiple_albedo_of(spec):
    """The Dense Fog albedo a ``table_spec`` was made for, or None (single scattering)."""
    return spec.args[2]


def estimate_seconds(spec):
    """About how long ``emitter_glow.bake_table`` of ``spec`` (``table_spec``) takes, s: COLUMN_SECONDS a column
    (the Dense Fog field's own table not counted: ``bakers.estimate_seconds`` adds it)."""
    return 0.3 + COLUMN_SECONDS * spec.width


def needs(spec):
    """The Dense Fog field's table the weights' bake reads (``emitter_glow.glow_field``), if any."""
    from ..point import multiple
    albedo = multiple_albedo_of(spec)
    return () if albedo is None else (multiple.table_spec(spec.g, albedo),)


FACING_COUNT = 64    # the facing table's samples over c = |cos| in [0, 1] (``emitter_glow.facing_mean``)


def facing_spec(g):
    """The TableSpec of the facing table for anisotropy ``g``: FACING_COUNT samples over c in [0, 1]; row 0
    ``emitter_glow.facing_mean``, row 1 ``emitter_glow.facing_dipole``."""
    return tables.TableSpec(f"AnalyticFog Emitter Facing (g {float(g):+.3f})", FACING_COUNT, 2, g=float(g),
                            kind=FACING_KIND_KEY, args=(float(g),))


KIND_KEY, FACING_KIND_KEY = "emitter_glow", "emitter_facing"
