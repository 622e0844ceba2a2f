"""The table of capabilities (``precompute/model/capabilities.py``) is the one place that says what each method models.

* The README's table "What each engine supports" is the table's ``readme_table`` (regenerate it from there).
* Outside ``fog_addon/methods/`` and the table no code compares a method's name with a literal: what a method
  can do is asked of the table (``capabilities.can``), so a feature moved to another method is one cell.
* The lookups: ``only``, ``methods_with``, ``suggestion``, ``runs`` read the cells (an independent reading of
  the README's rows, written out here for a few).
"""
import pathlib
import re

import pytest

from conftest import ROOT
from fog_addon.precompute.model import capabilities as c, rungs


def test_readme_table_is_the_capabilities_table():
    readme = (ROOT / "README.md").read_text()
    assert c.readme_table() in readme, ("README's engine table is stale: paste "
                                        "fog_addon.precompute.model.capabilities.readme_table() over it")


NAME_COMPARISON = re.compile(r"""(==|!=|\bin)\s*\(?\s*["'](nodes|osl|compositor)["']""")


def test_no_method_name_is_compared_outside_methods():
    offenders = []
    for path in sorted((ROOT / "fog_addon").rglob("*.py")):
        rel = path.relative_to(ROOT).as_posix()
        if rel.startswith("fog_addon/methods/") or rel.endswith("capabilities.py"):
            continue
        for k, line in enumerate(path.read_text().splitlines(), 1):
            code = line.split("#")[0]
            if NAME_COMPARISON.search(code) and "backends" not in code:
                offenders.append(f"{rel}:{k}: {line.strip()}")
    assert not offenders, "ask capabilities.can instead:\n" + "\n".join(offenders)


@pytest.mark.parametrize("feature, engine, expected", [
    ("shafts", c.CYCLES, ["compositor"]), ("shafts", c.EEVEE, ["compositor"]),
    ("emitters", c.CYCLES, ["compositor"]), ("dense_shaped", c.EEVEE, ["compositor"]),
    ("dense_point", c.CYCLES, ["nodes", "compositor"]), ("passes", c.CYCLES, ["nodes", "compositor"]),
    ("passes", c.EEVEE, ["nodes", "compositor"]), ("glass", c.CYCLES, ["nodes", "compositor"]), ("glass", c.EEVEE, []),
    ("panoramic", c.CYCLES, ["nodes", "osl", "compositor"]), ("panoramic", c.EEVEE, ["nodes"]), ("strong_backscatter", c.CYCLES, ["osl"]),
])
def test_who_models_what(feature, engine, expected):
    assert c.methods_with(feature, engine) == expected
    assert c.only(feature, engine) == (expected[0] if len(expected) == 1 else None)


def test_lookups():
    assert c.runs("osl", c.CYCLES) and not c.runs("osl", c.EEVEE) and c.engines_of("osl") == ["Cycles"]
    assert not c.can("osl", "shafts", c.EEVEE)   # a method that does not run there models nothing there
    assert c.suggestion("shafts", c.CYCLES) == "Method Compositor (or Auto)"
    assert c.suggestion("glass", c.EEVEE) == "no method"
    with pytest.raises(KeyError):
        c.can("nodes", "no such feature")
    assert all(len(f.cells) == len(c.COLUMNS) for f in c.FEATURES)


def test_the_ladder_grants_dense_fog_where_the_table_says():
    """``rungs.choose`` gives a spot's Dense Fog models only to the methods the table lets model it."""
    cone = (0.92, 0.15)
    for method in ("nodes", "osl", "compositor"):
        spot = rungs.choose(method, 0, 0.0, kind="spot", multiple_albedo=1.0, cone=cone)
        point = rungs.choose(method, 0, 0.0, multiple_albedo=1.0)
        has = [any("multiple" in r.name for r in m) for m in (spot, point)]
        assert has == [c.can(method, "dense_shaped"), c.can(method, "dense_point")], (method, has)
