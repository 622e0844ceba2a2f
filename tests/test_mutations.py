"""Each physical term of the fog, and each Cycles setting Remove must give back, has a test that fails without it.

tools/mutations.py removes one term at a time in a scratch copy of the
repository and runs the tests meant to catch it (README, "Tests that fail
when a term is missing").  A mutation that survives is a gap in the tests.
Each run is one pytest per mutation plus one unmutated baseline of their
killers.  The default tier runs ``mutations.QUICK`` (one mutation of each kind
of promise, cheap killers); the slow tier the rest (``-m mutation`` runs both:
every mutation once).
"""
import subprocess

import pytest

from conftest import ROOT
from tools import mutations


def test_every_mutation_still_applies():
    """Each mutation's old text is in its file exactly once and its killers exist (cheap: no runs)."""
    names = [mu.name for mu in mutations.MUTATIONS]
    assert len(set(names)) == len(names)
    for mu in mutations.MUTATIONS:
        mutations.check(mu)
        assert mu.killers and mu.old != mu.new, mu.name
        for node in mu.killers:
            path, _, func = node.partition("::")
            name = func.split("[")[0]
            assert (ROOT / path).is_file() and f"def {name}(" in (ROOT / path).read_text(), (mu.name, node)


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
