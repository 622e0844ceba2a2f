"""Shared test options.

``--regen-references`` recomputes cached reference data (path-traced renders,
quadrature samples) instead of reading it, as Blender's own render tests do
with BLENDER_TEST_UPDATE.  Failing image tests write diffs to tests/_failures/.
"""
import os
import pathlib
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

FAILURES = ROOT / "tests" / "_failures"
REFERENCES = ROOT / "tests" / "references"


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
