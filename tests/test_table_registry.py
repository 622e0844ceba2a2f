"""Every table the add-on makes belongs to exactly one registered kind (``precompute/core/registry.py``), found by the
key its spec carries, never by its name."""
import ast
import math
import pathlib
import re

import pytest

from fog_addon.precompute.core import tables
from fog_addon.precompute.model import bakers, registry
from fog_addon.precompute.model import pixel
from fog_addon.precompute.physics.daylight import daylight_tables
from fog_addon.precompute.physics.emitter import emitter_glow, emitter_table
from fog_addon.precompute.physics.point import multiple
from fog_addon.precompute.physics.spot import spot_multiple

PACKAGE = pathlib.Path(__file__).resolve().parent.parent / "fog_addon"

# ``TableSpec(...)`` calls without a ``kind=``: the pixel filter's constants (``registry.PIXEL_FILTER.fixed``), the
# scene's shadow maps (baked from the scene's geometry, not tables of the registry), the viewport preview's sampled
# lights (the scene's lamps, written by the handlers) and airlight's look-up of an array it already holds
UNKINDED_CALLS = {"precompute/model/pixel.py": 2, "shadow_maps.py": 4, "sun_maps.py": 3,
                  "precompute/physics/point/airlight.py": 1, "nodes/preview_sampled.py": 1}


def _specs():
    """A spec of every constructor at a few arguments each (g 0, forward, backward, and off the 3-decimal grid)."""
    out = [tables.LOBE_RESPONSE, tables.SPECULAR_ALBEDO, pixel.FILTER, pixel.EEVEE_FILTER, daylight_tables.sky_spec()]
    for g in (0.0, 0.85, -0.3, 0.4567891):
        out += [spec for spec, _ in bakers.bakers(g).values()]
        out += [multiple.orders_spec(g), multiple.table_spec(g, 0.8004),
                spot_multiple.table_spec(g, 0.9, math.cos(0.4), 0.153), spot_multiple.lambert_table_spec(g, 0.95),
                emitter_table.table_spec(g, 0.00123), emitter_table.table_spec(g, 0.00123, 0.8),
                emitter_glow.facing_spec(g),
                daylight_tables.table_spec(0.05, 10.0, 2.0, (0.1, 0.2, 0.97), g),
                daylight_tables.table_spec(0.05, 10.0, 2.0, (0.1, 0.2, 0.97), g, (0.01, 8.0, 0.9)),
                daylight_tables.glow_table(0.1).spec, daylight_tables.glow_table(0.1, (0.01, 0.02, 0.03)).spec]
    out += [spec for _, spec in sorted(_kind_makes().items())]
    return out


def _kind_makes():
    """Each kind's own constructor called once (``TableKind.make``), by kind key."""
    args = {"multiple": (0.5, 0.9), "multiple_orders": (0.5,), "spot_multiple": (0.5, 0.9, 0.8, 0.2),
            "emitter_glow": (0.5, 0.002), "emitter_facing": (0.5,),
            "daylight_fog_light": (0.05, 10.0, 2.0, (0.0, 0.0, 1.0), 0.5), "daylight_glow": (0.1,), "world_sky": ()}
    out = {}
    for kind in registry.KINDS:
        if kind.make is not None:
            out[kind.key] = kind.make(*args.get(kind.key, (0.5,) if kind.per_g else ()))
    return out


def test_every_spec_resolves_to_exactly_one_kind():
    """Each spec (every constructor, every constant) belongs to one kind, the one ``kind_of`` returns; a kind's
    constructor makes specs of that kind."""
    for spec in _specs():
        kinds = registry.kinds_of(spec)
        assert len(kinds) == 1, (spec, [k.key for k in kinds])
        assert registry.kind_of(spec) is kinds[0]
    for key, spec in _kind_makes().items():
        assert registry.kind_of(spec).key == key


def test_every_kind_is_reachable_and_labelled():
    """Every registered kind has specs (a constructor or constants) and a label; the baked kinds an estimate."""
    keys = {registry.kind_of(spec).key for spec in _specs()}
    assert keys == set(registry.BY_KEY), set(registry.BY_KEY) - keys
    for spec in _specs():
        kind = registry.kind_of(spec)
        assert kind.label(spec)
        if kind.bake is not None:
            assert kind.estimate(spec) > 0.0, kind.key


def test_kind_is_not_part_of_a_specs_identity():
    """The kind and arguments a spec carries stay out of its repr, equality and hash: the table cache's keys and
    the images' versions (``repr(spec)``) are those of the name, size, g and channels."""
    spec = multiple.table_spec(0.85, 0.9)
    bare = tables.TableSpec(spec.name, spec.width, spec.height, spec.g, spec.channels)
    assert repr(bare) == repr(spec) and bare == spec and hash(bare) == hash(spec)
    assert "kind" not in repr(spec) and "args" not in repr(spec)


def test_every_table_spec_call_names_its_kind():
    """Every ``TableSpec(...)`` call under fog_addon passes ``kind=`` but the few listed in UNKINDED_CALLS."""
    unkinded = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if (isinstance(node, ast.Call) and getattr(node.func, "attr", getattr(node.func, "id", None)) == "TableSpec"
                    and not any(k.arg == "kind" for k in node.keywords)):
                rel = path.relative_to(PACKAGE).as_posix()
                unkinded[rel] = unkinded.get(rel, 0) + 1
    assert unkinded == UNKINDED_CALLS


def test_no_dispatch_on_a_table_names_prefix():
    """No code under fog_addon tells tables apart by the start of their names."""
    pattern = re.compile(r"""startswith\(\s*f?["']AnalyticFog""")
    hits = [f"{p.relative_to(PACKAGE)}:{n}" for p in sorted(PACKAGE.rglob("*.py"))
            for n, line in enumerate(p.read_text().splitlines(), 1) if pattern.search(line)]
    assert hits == []


@pytest.mark.parametrize("spec", [daylight_tables.glow_table(0.1).spec, daylight_tables.sky_spec()],
                         ids=lambda s: s.name)
def test_a_scene_table_has_no_baker(spec):
    """The tables baked per scene (a camera's height, the World's probe) are no function of their spec."""
    with pytest.raises(KeyError):
        bakers.extra_baker(spec)
