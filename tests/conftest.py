"""Shared test options.

Markers (registered in pytest.ini): ``render``, ``slow``, ``mutation``; scripts/test.sh runs
``-m "not slow"`` by default and everything with ``--all``.  A ``-m`` expression naming a marker
that is not registered is a usage error here (pytest itself would silently select nothing, or
everything under ``not``).

The repository root goes on ``sys.path`` once, here: tests import ``fog_addon``, ``fog_scenes``
(shared scenes and the render harness), ``demo_scenes`` and ``tools`` as packages.

``--regen-references`` recomputes cached reference data (path-traced renders,
quadrature samples) instead of reading it, as Blender's own render tests do
with BLENDER_TEST_UPDATE.  Failing image tests write diffs to tests/_failures/.
"""
import os
import pathlib
import re
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

FAILURES = ROOT / "tests" / "_failures"
REFERENCES = ROOT / "tests" / "references"


def pytest_configure(config):
    """Refuse a ``-m`` expression that names an unregistered marker (a typo would select nothing or all)."""
    expr = config.getoption("markexpr", default="") or ""
    known = {line.split(":")[0].split("(")[0].strip() for line in config.getini("markers")}
    names = set(re.findall(r"[A-Za-z_][A-Za-z0-9_]*", expr)) - {"and", "or", "not", "True", "False"}
    unknown = sorted(names - known)
    if unknown:
        raise pytest.UsageError(f"-m {expr!r} names unregistered marker(s) {unknown}; "
                                f"registered (tests/pytest.ini): {sorted(known)}")


def pytest_sessionfinish(session, exitstatus):
    """The numpy tier (``scripts/test.sh --numpy``) must not have imported Blender in this process."""
    if os.environ.get("FOG_NUMPY_TIER") == "1" and "bpy" in sys.modules and exitstatus == 0:
        session.exitstatus = 1
        print("\nthe numpy tier imported bpy: the test that did must be marked render")


def pytest_addoption(parser):
    parser.addoption("--regen-references", action="store_true", default=False,
                     help="recompute cached references (quadrature, path-traced renders)")


@pytest.fixture(scope="session")
def regen(request):
    return request.config.getoption("--regen-references") or os.environ.get("FOG_REGEN_REFERENCES") == "1"


@pytest.fixture(autouse=True, scope="session")
def _private_tmpdir(tmp_path_factory):
    """OSL compilation leaves .oso files in TMPDIR: keep them out of the system temp folder."""
    d = tmp_path_factory.mktemp("tmpdir")
    old = os.environ.get("TMPDIR")
    os.environ["TMPDIR"] = str(d)
    yield
    if old is None:
        os.environ.pop("TMPDIR", None)
    else:
        os.environ["TMPDIR"] = old
