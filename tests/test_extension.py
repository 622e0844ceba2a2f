"""The add-on as a Blender extension: the manifest (at the repository root, which is the
extension's source directory) validates, the built zip holds only the add-on,
``extensions.package_install_files`` installs and enables it so ``fog.add`` works, and
enabling/disabling (or register()/unregister()) three times leaves nothing behind.

Every Blender process runs with BLENDER_USER_RESOURCES and HOME in a pytest tmp_path, so
nothing is installed into (or read from) the user's ~/.config.
"""
import importlib.util
import json
import os
import pathlib
import subprocess
import sys
import tomllib
import zipfile

import pytest

from conftest import ROOT

pytestmark = pytest.mark.render   # every test here starts Blender (bpy) in a subprocess

SRC = ROOT                  # the extension's source directory: blender_manifest.toml, __init__.py
ADDON = ROOT / "fog_addon"  # the add-on package the root __init__.py hands on
SCRIPT = ROOT / "tests" / "scenes" / "extension_install.py"
# Blender's extension CLI, found without importing bpy (find_spec only locates the package).
_BPY = importlib.util.find_spec("bpy")
BLENDER_EXT = (pathlib.Path(_BPY.submodule_search_locations[0]) if _BPY else pathlib.Path("bpy-not-installed")) \
    / "5.0" / "scripts" / "addons_core" / "bl_pkg" / "cli" / "blender_ext.py"
CYCLES = 3


def _isolated_env(base):
    """Environment for a child process whose Blender user directories all live under ``base``."""
    env = dict(os.environ)
    for k in ("BLENDER_USER_CONFIG", "BLENDER_USER_SCRIPTS", "BLENDER_USER_DATAFILES", "BLENDER_USER_EXTENSIONS"):
        env.pop(k, None)   # each of these would override BLENDER_USER_RESOURCES
    env["BLENDER_USER_RESOURCES"] = str(base / "user_resources")
    env["HOME"] = str(base / "home")
    env["PYTHONDONTWRITEBYTECODE"] = "1"   # don't leave __pycache__ in the source tree
    (base / "user_resources").mkdir(parents=True, exist_ok=True)
    (base / "home").mkdir(parents=True, exist_ok=True)
    return env


def _blender_ext(*args, env, cwd):
    assert BLENDER_EXT.is_file(), f"blender_ext.py not found at {BLENDER_EXT}"
    return subprocess.run([sys.executable, str(BLENDER_EXT), *args], capture_output=True, text=True,
                          timeout=120, env=env, cwd=cwd)


def _run_script(mode, arg, base):
    r = subprocess.run([sys.executable, str(SCRIPT), mode, str(arg)], capture_output=True, text=True,
                       timeout=300, env=_isolated_env(base), cwd=base)
    assert r.returncode == 0, f"{SCRIPT.name} {mode} exited {r.returncode}:\n{r.stderr[-3000:]}"
    lines = r.stdout.strip().splitlines()
    assert lines, f"{SCRIPT.name} {mode} printed nothing; stderr:\n{r.stderr[-3000:]}"
    res = json.loads(lines[-1])
    # Output outside the script's captured steps (e.g. at import or exit) is an error too.
    assert not r.stderr.strip(), f"{mode}: stderr outside the recorded steps:\n{r.stderr[-3000:]}"
    return res


def _problems(res):
    """The script's record of steps that raised or wrote to stderr, readable."""
    return "".join(f"\n--- {step}:\n{text}" for step, text in res["problems"].items()) or " (none recorded)"


def _assert_clean(res, where):
    """No step raised or wrote to stderr; nothing of the add-on is registered any more."""
    assert not res["problems"], f"{where}: steps raised or wrote to stderr:{_problems(res)}"
    chatty = {e["step"]: e["stdout"] for e in res["log"]
              if e["stdout"].strip() and ("enable" in e["step"] or "register" in e["step"])}
    assert not chatty, f"{where}: enable/disable printed output (warnings?): {chatty}"
    final = res["final"]
    assert final["fog_ops"] == [], f"{where}: bpy.ops.fog still has {final['fog_ops']} after the last disable"
    assert final["scene_prop"] is False, f"{where}: Scene.analytic_fog is still defined after the last disable"
    assert final["classes"] == [], f"{where}: classes still registered after the last disable: {final['classes']}"
    assert final["handlers"] == [], f"{where}: add-on functions left in bpy.app.handlers: {final['handlers']}"


def _assert_cycles(res, where):
    assert len(res.get("cycles", [])) == CYCLES, f"{where}: expected {CYCLES} enable/disable cycles: {res}"
    for i, c in enumerate(res["cycles"], 1):
        assert c["enable_returned"], f"{where}: enable #{i} failed:{_problems(res)}"
        assert {"add", "remove"} <= set(c["on"]["fog_ops"]), (
            f"{where}: after enable #{i} bpy.ops.fog = {c['on']['fog_ops']}")
        assert c["on"]["scene_prop"], f"{where}: after enable #{i} Scene.analytic_fog is missing"
        for key, empty in (("fog_ops", []), ("scene_prop", False), ("classes", []), ("handlers", [])):
            assert c["off"][key] == empty, f"{where}: after disable #{i} {key} = {c['off'][key]!r}, expected {empty!r}"


def _build(src, base):
    """Validate ``src`` and build its zip with Blender's own blender_ext.py; return the zip's path."""
    env = _isolated_env(base)
    r = _blender_ext("validate", str(src), env=env, cwd=base)
    assert r.returncode == 0, f"blender_ext.py validate {src} failed ({r.returncode}):\n{r.stdout}\n{r.stderr}"
    out = base / "dist"
    out.mkdir()
    r = _blender_ext("build", "--source-dir", str(src), "--output-dir", str(out), env=env, cwd=base)
    assert r.returncode == 0, f"blender_ext.py build failed ({r.returncode}):\n{r.stdout}\n{r.stderr}"
    zips = sorted(out.glob("*.zip"))
    assert len(zips) == 1, f"build should produce one zip, got {zips}; output:\n{r.stdout}\n{r.stderr}"
    return zips[0]


@pytest.fixture(scope="module")
def built_zip(tmp_path_factory):
    """The extension zip built from the repository root, as scripts/build_extension.sh does."""
    return _build(SRC, tmp_path_factory.mktemp("ext_build"))


def _zip_names(path):
    with zipfile.ZipFile(path) as z:
        return set(z.namelist())


def _addon_files(root=SRC):
    """The add-on's python files under ``root`` as zip names: fog_addon/**/*.py (no bytecode, no hidden files)."""
    return {p.relative_to(root).as_posix() for p in (root / "fog_addon").rglob("*.py")
            if not any(part == "__pycache__" or part.startswith(".") for part in p.relative_to(root).parts)}


def test_built_zip_contents(built_zip):
    manifest = tomllib.loads((SRC / "blender_manifest.toml").read_text())
    assert built_zip.name == f"{manifest['id']}-{manifest['version']}.zip", built_zip.name
    names = _zip_names(built_zip)
    with zipfile.ZipFile(built_zip) as z:
        zipped_manifest = tomllib.loads(z.read("blender_manifest.toml").decode())
        root_init = z.read("__init__.py").decode() if "__init__.py" in names else ""
    assert zipped_manifest == manifest, "the zipped manifest differs from blender_manifest.toml"
    assert "from .fog_addon import" in root_init, "the zip's root __init__.py does not hand on fog_addon"
    addon = _addon_files()
    assert {"fog_addon/__init__.py", "fog_addon/props.py", "fog_addon/ops/apply.py",
            "fog_addon/precompute/physics/point/model.py", "fog_addon/nodes/groups.py"} <= addon, sorted(addon)
    expected = {"__init__.py", "blender_manifest.toml"} | addon
    missing = sorted(expected - names)
    assert not missing, (f"add-on files missing from {built_zip.name}: {missing}; "
                         "see [build] paths_exclude_pattern in blender_manifest.toml")
    # Only the add-on ships: no tests, demo scenes, benchmarks, tools, docs, scripts, .venv, out/,
    # bytecode, hidden files or built zips.
    extra = sorted(names - expected)
    assert not extra, f"{built_zip.name} holds files the add-on doesn't need: {extra}"


def test_build_leaves_out_junk(tmp_path):
    """A source tree littered with what development leaves behind still builds the add-on only."""
    src = tmp_path / "src"
    src.mkdir()
    for name in ("__init__.py", "blender_manifest.toml"):
        (src / name).write_bytes((SRC / name).read_bytes())
    for py in _addon_files():
        (src / py).parent.mkdir(parents=True, exist_ok=True)
        (src / py).write_bytes((SRC / py).read_bytes())
    junk = ["tests/test_x.py", "tests/conftest.py", "demo_scenes/__init__.py", "benchmarks/b.py", "tools/t.py",
            "docs/figures/f.png", "scripts/s.sh", ".venv/lib/site.py", "out/analytic_fog-0.1.0.zip", "old.zip",
            "README.md", "requirements-dev.txt", "setup.py", ".gitignore", ".git/HEAD", "scene.blend",
            "fog_addon/__pycache__/cli.cpython-311.pyc", "fog_addon/nodes/__pycache__/groups.cpython-311.pyc",
            "fog_addon/cli.pyc", "fog_addon/.cli.py.swp", "fog_addon/notes.txt", "fog_addon/nodes/fog.oso",
            "fog_addon/ops/apply.py~", "fog_addon/precompute/table.npz", "fog_addon/test.blend1"]
    for name in junk:
        (src / name).parent.mkdir(parents=True, exist_ok=True)
        (src / name).write_text("junk\n")
    names = _zip_names(_build(src, tmp_path / "build"))
    expected = {"__init__.py", "blender_manifest.toml"} | _addon_files(src)
    assert names == expected, (f"zip built from a littered tree: extra {sorted(names - expected)}, "
                               f"missing {sorted(expected - names)}")


def test_install_enable_add_and_cycle(built_zip, tmp_path):
    res = _run_script("install", built_zip, tmp_path)
    where = "installed extension"
    assert res["install_result"] == ["FINISHED"], (
        f"package_install_files returned {res['install_result']}:{_problems(res)}")
    user_res = (tmp_path / "user_resources").resolve()
    assert res["installed_file"], f"module {res['module']} not imported after install:{_problems(res)}"
    assert pathlib.Path(res["installed_file"]).resolve().is_relative_to(user_res), (
        f"installed module is {res['installed_file']}, not under BLENDER_USER_RESOURCES={user_res}")
    assert pathlib.Path(res["user_default_dir"]).resolve().is_relative_to(user_res), res["user_default_dir"]
    assert res["addon_check"] == [True, True], (
        f"addon_utils.check after install (default, loaded) = {res['addon_check']}")
    after = res["after_install"]
    assert {"add", "remove"} <= set(after["fog_ops"]), f"after install bpy.ops.fog = {after['fog_ops']}"
    assert after["scene_prop"], "after install bpy.types.Scene.analytic_fog is missing"
    # The operators come from the installed copy (the root package hands on fog_addon's register()).
    for op in ("FOG_OT_add", "FOG_OT_remove"):
        assert any(c.startswith(f"{res['module']}.fog_addon.") and c.endswith("." + op)
                   for c in after["classes"]), f"{op} not registered from {res['module']}.fog_addon: {after['classes']}"
    assert res["add_result"] == ["FINISHED"], f"fog.add(density=0.1) returned {res['add_result']}:{_problems(res)}"
    assert res["surface_group"], "fog.add did not create the node group 'AnalyticFog Surface'"
    assert res["material_fogged"], "fog.add did not insert the fog into the plane's material"
    assert res["remove_result"] == ["FINISHED"], f"fog.remove returned {res['remove_result']}"
    assert res["groups_after_remove"] == [], f"fog.remove left node groups {res['groups_after_remove']}"
    first = res["after_first_disable"]
    assert first["fog_ops"] == [] and not first["scene_prop"] and first["classes"] == first["handlers"] == [], (
        f"disabling after install left {first}")
    _assert_cycles(res, where)
    _assert_clean(res, where)
    assert res["addon_check_final"] == [False, False], f"addon_utils.check after disable = {res['addon_check_final']}"


def test_source_register_unregister_cycle(tmp_path):
    res = _run_script("source", ADDON.parent, tmp_path)
    where = "fog_addon from source"
    assert res["imported_file"] and pathlib.Path(res["imported_file"]).resolve().is_relative_to(ADDON.resolve()), (
        f"imported {res['imported_file']}, not the source tree {ADDON}:{_problems(res)}")
    assert res["before"]["fog_ops"] == [] and not res["before"]["scene_prop"], (
        f"registered before register(): {res['before']}")
    _assert_cycles(res, where)
    _assert_clean(res, where)
