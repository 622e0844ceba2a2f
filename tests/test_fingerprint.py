"""The code version stamped on what the add-on builds covers all of its source (``precompute/core/fingerprint.py``).

Expected values come from the file system, not from the code under test: the set of files is what
``rglob("*.py")`` finds, and a one-byte edit of any of them (in a copy of the package) must change the
fingerprint.  The builders' stamps (node groups, compositor groups, kernel groups, OSL texts, table images)
are checked in a Blender process against a copy of the package whose ``nodes/comp_fog.py`` is edited.
"""
import json
import pathlib
import shutil
import subprocess
import sys

import pytest

from conftest import ROOT
from fog_addon.precompute.core import fingerprint

PACKAGE = ROOT / "fog_addon"


def _fresh(root):
    """The fingerprint of ``root`` computed now (not the per-process cached value)."""
    return fingerprint.tree_fingerprint.__wrapped__(pathlib.Path(root))


@pytest.fixture
def copy(tmp_path):
    """A copy of the package's source (``*.py`` only) in tmp_path / "a" / "fog_addon"."""
    dst = tmp_path / "a" / "fog_addon"
    shutil.copytree(PACKAGE, dst, ignore=lambda d, names: [n for n in names if n == "__pycache__"
                                                            or ((pathlib.Path(d) / n).is_file()
                                                                and not n.endswith(".py"))])
    return dst


def test_covers_every_python_file_of_the_package(copy):
    files = fingerprint.source_files(copy)
    assert files == sorted(p.relative_to(copy).as_posix() for p in copy.rglob("*.py"))
    assert {"nodes/comp_fog.py", "precompute/model/pixel.py", "nodes/groups.py", "__init__.py"} <= set(files)
    base = _fresh(copy)
    for rel in files:
        path = copy / rel
        data = path.read_bytes()
        path.write_bytes(data[:-1] + bytes([data[-1] ^ 1]) if data else b"#")
        try:
            assert _fresh(copy) != base, f"an edit of {rel} leaves the fingerprint unchanged"
        finally:
            path.write_bytes(data)
    assert _fresh(copy) == base


def test_new_renamed_and_removed_files_change_it(copy):
    base = _fresh(copy)
    (copy / "nodes" / "new_module.py").write_text("")
    assert _fresh(copy) != base
    (copy / "nodes" / "new_module.py").unlink()
    assert _fresh(copy) == base
    (copy / "nodes" / "comp_fog.py").rename(copy / "nodes" / "comp_fog2.py")
    assert _fresh(copy) != base
    (copy / "nodes" / "comp_fog2.py").unlink()
    assert _fresh(copy) != base


def test_independent_of_where_the_package_lies(copy, tmp_path):
    """An installed extension (``extensions/user_default/analytic_fog/fog_addon``) has the source tree's
    fingerprint: paths are relative to the package; bytecode and other files play no part."""
    other = tmp_path / "extensions" / "user_default" / "analytic_fog" / "fog_addon"
    shutil.copytree(copy, other)
    (other / "precompute" / "model" / "__pycache__").mkdir(exist_ok=True)
    (other / "precompute" / "model" / "__pycache__" / "pixel.cpython-311.pyc").write_bytes(b"\0" * 16)
    (other / "notes.txt").write_text("x")
    assert _fresh(other) == _fresh(copy)
    assert fingerprint.PACKAGE == PACKAGE.resolve() and fingerprint.PRECOMPUTE == PACKAGE.resolve() / "precompute"


def test_precompute_fingerprint_follows_precompute_only(copy):
    base = _fresh(copy / "precompute")
    (copy / "nodes" / "comp_fog.py").write_text("# edited\n", encoding="utf-8")
    assert _fresh(copy / "precompute") == base
    with open(copy / "precompute" / "model" / "pixel.py", "a", encoding="utf-8") as f:
        f.write("# edited\n")
    assert _fresh(copy / "precompute") != base


def test_cached_per_process_and_cheap():
    import time
    t = time.perf_counter()
    _fresh(PACKAGE)
    cold = time.perf_counter() - t
    fingerprint.package_fingerprint()
    t = time.perf_counter()
    for _ in range(1000):
        fingerprint.package_fingerprint()
    warm = (time.perf_counter() - t) / 1000
    assert cold < 0.5 and warm < 1e-4, (cold, warm)
    assert fingerprint.package_fingerprint("a") != fingerprint.package_fingerprint("b")


_STAMPS = r"""
import json, pathlib, sys
sys.path.insert(0, sys.argv[1])
import bpy
from fog_addon.nodes import groups, images, osl
from fog_addon.precompute.core import fingerprint, tables
from fog_addon.precompute.model import rungs
rung = next(r for r in rungs.RUNGS if "osl" in r.backends)
out = {}
for key, root in (("real", fingerprint.PACKAGE), ("copy", sys.argv[2]), ("edited", sys.argv[3])):
    fingerprint.PACKAGE = pathlib.Path(root)
    out[key] = {"package": fingerprint.package_fingerprint(), "groups": groups.code_fingerprint(),
                "image": images.table_version(tables.AIRLIGHT),
                "osl": osl.kernel_source(rung).splitlines()[0]}
print(json.dumps(out))
"""


@pytest.mark.render
def test_builders_stamp_the_package_fingerprint(copy, tmp_path):
    """Node and compositor groups (``groups.code_fingerprint``), table images and OSL texts change with an
    edit of ``nodes/comp_fog.py``, which the hand-kept list of modules used to leave out."""
    edited = tmp_path / "b" / "fog_addon"
    shutil.copytree(copy, edited)
    with open(edited / "nodes" / "comp_fog.py", "a", encoding="utf-8") as f:
        f.write("# edited\n")
    r = subprocess.run([sys.executable, "-c", _STAMPS, str(ROOT), str(copy), str(edited)],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-3000:]
    s = json.loads(r.stdout.strip().splitlines()[-1])
    assert s["copy"]["package"] == _fresh(copy) and s["edited"]["package"] == _fresh(edited)
    for key in ("copy", "edited"):
        assert s[key]["groups"] == s[key]["package"]
        assert s[key]["osl"].split()[3].rstrip(":") == s[key]["package"], s[key]["osl"]
    for what in ("package", "groups", "image", "osl"):
        assert s["copy"][what] != s["edited"][what], what
