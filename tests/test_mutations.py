"""Each physical term of the fog, and each Cycles setting Remove must give back, has a test that fails without it.

tools/mutations.py removes one term at a time in a scratch copy of the
repository and runs the tests meant to catch it (README, "Tests that fail
when a term is missing").  A mutation that survives is a gap in the tests.
Each run is one pytest per mutation plus one unmutated baseline of their
killers.  The default tier runs ``mutations.QUICK`` (one mutation of each kind
of promise, cheap killers); the slow tier the rest (``-m mutation`` runs both:
every mutation once).
"""
import pathlib
import subprocess
import textwrap

import pytest

from conftest import ROOT
from tools import mutations


def test_every_mutation_still_applies():
    """Each mutation's symbol is defined once under fog_addon/, holds its old text exactly once, and its killers
    exist (cheap: no runs)."""
    names = [mu.name for mu in mutations.MUTATIONS]
    assert len(set(names)) == len(names)
    for mu in mutations.MUTATIONS:
        mutations.check(mu)
        assert mu.killers and mu.old != mu.new, mu.name
        for node in mu.killers:
            path, _, func = node.partition("::")
            name = func.split("[")[0]
            assert (ROOT / path).is_file() and f"def {name}(" in (ROOT / path).read_text(), (mu.name, node)


def _copy_package(dest):
    """The ``.py`` files of the add-on's package under ``dest`` (enough for ``mutations.check``)."""
    for src in (ROOT / mutations.PACKAGE).rglob("*.py"):
        rel = src.relative_to(ROOT)
        if "__pycache__" not in rel.parts:
            (dest / rel).parent.mkdir(parents=True, exist_ok=True)
            (dest / rel).write_text(src.read_text())
    return dest


def _outermost(sym, root):
    """The module-level definition that holds ``sym`` (itself when it is one)."""
    found, _ = mutations.symbols(root)
    module_parts = len(pathlib.PurePosixPath(sym.path).with_suffix("").parts)
    if sym.path.endswith("/__init__.py"):
        module_parts -= 1
    return next(s for s in found if s.path == sym.path and len(s.dotted.split(".")) == module_parts + 1
                and s.first <= sym.first and sym.last <= s.last)


@pytest.mark.parametrize("name", ["glow_on_surfaces", "spot_multiple_surface_cosine", "shaft_visibility",
                                  "nodes_left_unplaced"])
@pytest.mark.parametrize("into_class", [False, True], ids=["as_is", "into_a_class"])
def test_a_mutation_survives_a_pure_move(tmp_path, name, into_class):
    """Moving the code that holds a mutation's term to another module (or, indented, into a class there) does not
    change the mutation: its target is found in the new module and the term mutated there as it was in place."""
    mu = next(m for m in mutations.MUTATIONS if m.name == name)
    here = _copy_package(tmp_path / "here")
    top = _outermost(mutations.find_symbol(mu.target, here), here)
    original = (here / top.path).read_text()
    path, mutated = mutations.check(mu, here)
    assert path == top.path
    grew = len(mutated.split("\n")) - len(original.split("\n"))
    expected = "".join(mutated.splitlines(keepends=True)[top.first - 1:top.last + grew])

    moved = _copy_package(tmp_path / "moved")
    lines = original.splitlines(keepends=True)
    source = "".join(lines[top.first - 1:top.last])
    (moved / top.path).write_text("".join(lines[:top.first - 1] + lines[top.last:]))
    header = "import math\n\n\nclass Moved:\n" if into_class else "import math\n\n\n"
    shift = (lambda text: textwrap.indent(text, "    ")) if into_class else (lambda text: text)
    scratch = f"{mutations.PACKAGE}/scratch_moved_here.py"
    (moved / scratch).write_text(header + shift(source))

    path, text = mutations.check(mu, moved)
    assert path == scratch
    assert text == header + shift(expected)


def _write(root, files):
    for rel, text in files.items():
        (root / rel).parent.mkdir(parents=True, exist_ok=True)
        (root / rel).write_text(textwrap.dedent(text).lstrip("\n"))
    return root


def _mutation(target, old, new="pass"):
    return mutations.Mutation("synthetic", "a test of the lookup", target, old, new, ("tests/none.py::x",))


def test_lookup_by_symbol_on_synthetic_files(tmp_path):
    """A target is a def, class or constant found wherever it is defined under the package; ambiguous names are
    refused until qualified; the old text must occur once inside the symbol, not just once in the file."""
    root = _write(tmp_path, {
        "fog_addon/a.py": """
            SLOPE = 0.5

            def twice():
                x = 1
                x = 1

            def once():
                y = 2

            def shared():
                return 1

            class Box:
                def shared(self):
                    if self:
                        z = 3
                    return z
            """,
        "fog_addon/sub/__init__.py": """
            def shared():
                return 2

            w = 4
            """,
    })
    assert mutations.check(_mutation("once", "y = 2", "y = 0"), root) == \
        ("fog_addon/a.py", (root / "fog_addon/a.py").read_text().replace("y = 2", "y = 0"))
    assert mutations.find_symbol("SLOPE", root).kind == "constant"
    assert mutations.find_symbol("sub.shared", root).dotted == "fog_addon.sub.shared"
    assert mutations.find_symbol("fog_addon.a.shared", root).first == 10
    path, text = mutations.check(_mutation("Box.shared", "if self:\n        z = 3\n", "z = 0\n"), root)
    assert "    def shared(self):\n        z = 0\n        return z\n" in text

    with pytest.raises(ValueError, match=r"occurs 2 times in fog_addon\.a\.twice \(def, fog_addon/a\.py lines 3-5"):
        mutations.check(_mutation("twice", "x = 1"), root)
    with pytest.raises(ValueError, match=r"occurs 0 times in fog_addon\.a\.once"):
        mutations.check(_mutation("once", "x = 1"), root)   # in the file, not in the symbol
    with pytest.raises(ValueError, match=r"'shared' names 3 definitions"):
        mutations.check(_mutation("shared", "return"), root)
    with pytest.raises(ValueError, match=r"no def, class or constant 'gone'"):
        mutations.check(_mutation("gone", "x"), root)
    with pytest.raises(ValueError, match=r"no def, class or constant 'y'"):
        mutations.check(_mutation("y", "2"), root)   # a function's local variable is no constant


def test_readme_table_is_the_tools():
    """README's list of mutations and killers is ``tools/mutations.py --markdown`` (fix: ``--update-readme``)."""
    md = mutations.markdown(mutations.MUTATIONS)
    assert all(f"`{mu.name}`" in md for mu in mutations.MUTATIONS)
    assert mutations.readme_table(mutations.README.read_text()) == md, \
        "docs/testing.md's mutation table is stale: run .venv/bin/python tools/mutations.py --update-readme"


def _check_killed(chosen):
    """The killers of ``chosen`` pass on an unmutated copy, and each mutation makes one of them fail."""
    try:
        mutations.repo_files()
    except (OSError, subprocess.CalledProcessError):
        pytest.skip("not a git checkout: tools/mutations.py copies the files git ls-files lists")
    results, base = mutations.run_all(chosen, with_baseline=True)
    assert base["ok"], f"the killer tests fail without any mutation:\n{base['output']}"
    report = mutations.table(results)
    bad = [r for r in results if r["status"] != "killed"]
    assert not bad, report + "".join(f"\n--- {r['name']} {r['status']} ---\n{r['output']}" for r in bad)
    for r, mu in zip(results, chosen):   # killed by a test meant to kill it, not by something else
        assert r["killed_by"] and r["killed_by"].split("[")[0] in {k.split("[")[0] for k in mu.killers}, report


@pytest.mark.mutation
@pytest.mark.render
def test_quick_mutations_are_killed():
    """The default tier's subset (``mutations.QUICK``) is killed."""
    _check_killed(mutations.quick())


@pytest.mark.mutation
@pytest.mark.render
@pytest.mark.slow
def test_other_mutations_are_killed():
    """Every mutation not in ``mutations.QUICK`` is killed (with the quick ones: all of them)."""
    _check_killed(mutations.rest())
