"""Install/enable the built extension, or register the source package, and cycle it; report JSON.

Usage (run by tests/test_extension.py in a fresh process, with BLENDER_USER_RESOURCES
pointed at a temporary directory):

    python extension_install.py install ZIP      # package_install_files + fog.add + 3 x addon_utils enable/disable
    python extension_install.py source PARENT    # import fog_addon from PARENT, 3 x register()/unregister()

Every step runs with file descriptors 1 and 2 redirected to temporary files, so
anything it prints (Python tracebacks and Blender's own C-level messages alike)
is recorded against the step.  The last line of stdout is one JSON object.
"""
import contextlib
import ctypes
import json
import os
import sys
import tempfile
import traceback

import bpy  # noqa: I001 - bpy first: it puts addon_utils on sys.path
import addon_utils

INSTALLED_MODULE = "bl_ext.user_default.analytic_fog"
SOURCE_MODULE = "fog_addon"
CYCLES = 3

_libc = ctypes.CDLL(None)


def _flush():
    sys.stdout.flush()
    sys.stderr.flush()
    _libc.fflush(None)


@contextlib.contextmanager
def _fd_capture():
    """Redirect fds 1 and 2 to temp files; yields a dict filled with 'stdout'/'stderr' on exit."""
    got = {}
    _flush()
    saved = os.dup(1), os.dup(2)
    with tempfile.TemporaryFile() as fo, tempfile.TemporaryFile() as fe:
        os.dup2(fo.fileno(), 1)
        os.dup2(fe.fileno(), 2)
        try:
            yield got
        finally:
            _flush()
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            os.close(saved[0])
            os.close(saved[1])
            for key, f in (("stdout", fo), ("stderr", fe)):
                f.seek(0)
                got[key] = f.read().decode("utf-8", "replace")


class Steps:
    """Runs named steps, recording their result, printed output and exceptions."""

    def __init__(self):
        self.log = []      # [{"step", "stdout", "stderr", "exception"}] for every step
        self.problems = {}  # step -> text, for steps that raised or wrote to stderr

    def run(self, name, fn, *args, **kwargs):
        result, exc = None, None
        with _fd_capture() as out:
            try:
                result = fn(*args, **kwargs)
            except Exception:  # noqa: BLE001 - recorded and reported
                exc = traceback.format_exc()
        entry = {"step": name, "stdout": out["stdout"], "stderr": out["stderr"], "exception": exc}
        self.log.append(entry)
        bad = "".join(x for x in (out["stderr"], exc or "") if x)
        if bad.strip():
            self.problems[name] = bad[-2000:]
        return result


def _is_ours(fn, prefix):
    """Whether callable ``fn`` (function, bound method, partial, callable object) comes from ``prefix``."""
    cands = [fn, getattr(fn, "__func__", None), getattr(fn, "func", None), type(fn)]
    for c in cands:
        mod = getattr(c, "__module__", None) or ""
        if mod == prefix or mod.startswith(prefix + "."):
            return True
    return False


def leftover_handlers(prefix):
    """['list_name: module.qualname'] for functions from ``prefix`` in any bpy.app.handlers list."""
    found = []
    for name in dir(bpy.app.handlers):
        lst = getattr(bpy.app.handlers, name)
        if not isinstance(lst, list):
            continue
        for fn in lst:
            if _is_ours(fn, prefix):
                found.append(f"{name}: {getattr(fn, '__module__', '?')}.{getattr(fn, '__qualname__', repr(fn))}")
    return found


def _subclasses(cls):
    for sub in cls.__subclasses__():
        yield sub
        yield from _subclasses(sub)


def registered_classes(prefix):
    """Blender classes (operators, property groups, panels, ...) from ``prefix`` still registered."""
    return sorted({f"{c.__module__}.{c.__qualname__}" for c in _subclasses(bpy.types.bpy_struct)
                   if _is_ours(c, prefix) and getattr(c, "is_registered", False)})


def registered_state(prefix):
    """What of the add-on is visible in Blender right now."""
    return {
        "fog_ops": sorted(dir(bpy.ops.fog)),
        "scene_prop": hasattr(bpy.types.Scene, "analytic_fog"),
        "classes": registered_classes(prefix),
        "handlers": leftover_handlers(prefix),
    }


def build_tiny_scene():
    """A plane with a material, a point light, a camera and a world."""
    scene = bpy.context.scene
    mesh = bpy.data.meshes.new("Plane")
    h = 2.0
    mesh.from_pydata([(-h, -h, 0), (h, -h, 0), (h, h, 0), (-h, h, 0)], [], [(0, 1, 2, 3)])
    mesh.update()
    mat = bpy.data.materials.new("PlaneMat")
    mesh.materials.append(mat)
    plane = bpy.data.objects.new("Plane", mesh)
    scene.collection.objects.link(plane)
    light = bpy.data.objects.new("Lamp", bpy.data.lights.new("Lamp", "POINT"))
    light.location = (0.0, 0.0, 2.0)
    scene.collection.objects.link(light)
    cam = bpy.data.objects.new("Cam", bpy.data.cameras.new("Cam"))
    cam.location = (0.0, -6.0, 3.0)
    cam.rotation_euler = (1.1, 0.0, 0.0)
    scene.collection.objects.link(cam)
    scene.camera = cam
    if scene.world is None:
        scene.world = bpy.data.worlds.new("World")
    return mat


def _fogged(idblock):
    tree = idblock.node_tree
    return tree is not None and any(n.get("analytic_fog") is not None for n in tree.nodes)   # the fog's tag


def cycle(steps, label, enable, disable, prefix):
    """CYCLES x (enable, snapshot, disable, snapshot); returns the list of per-cycle snapshots."""
    out = []
    for i in range(CYCLES):
        ret = steps.run(f"{label} enable {i + 1}", enable)
        on = registered_state(prefix)
        steps.run(f"{label} disable {i + 1}", disable)
        off = registered_state(prefix)
        out.append({"enable_returned": ret is not None and ret is not False, "on": on, "off": off})
    return out


def main_install(zip_path):
    steps = Steps()
    res = {"mode": "install", "module": INSTALLED_MODULE}
    steps.run("factory settings", bpy.ops.wm.read_factory_settings, use_empty=True)
    mat = steps.run("build scene", build_tiny_scene)
    res["install_result"] = sorted(steps.run(
        "install", bpy.ops.extensions.package_install_files,
        filepath=zip_path, repo="user_default", enable_on_install=True) or [])
    mod = sys.modules.get(INSTALLED_MODULE)
    res["installed_file"] = getattr(mod, "__file__", None)
    res["user_default_dir"] = next((r.directory for r in bpy.context.preferences.extensions.repos
                                    if r.module == "user_default"), None)
    res["addon_check"] = list(addon_utils.check(INSTALLED_MODULE))  # (enabled by default, loaded)
    res["after_install"] = registered_state(INSTALLED_MODULE)

    if res["after_install"]["fog_ops"]:
        res["add_result"] = sorted(steps.run("fog.add", bpy.ops.fog.add, density=0.1) or [])
        res["surface_group"] = bpy.data.node_groups.get("AnalyticFog Surface") is not None
        res["material_fogged"] = mat is not None and _fogged(mat)
        res["remove_result"] = sorted(steps.run("fog.remove", bpy.ops.fog.remove) or [])
        res["groups_after_remove"] = sorted(g.name for g in bpy.data.node_groups if g.name.startswith("AnalyticFog"))
    steps.run("disable after install", addon_utils.disable, INSTALLED_MODULE, default_set=True)
    res["after_first_disable"] = registered_state(INSTALLED_MODULE)
    res["cycles"] = cycle(steps, "addon_utils",
                          lambda: addon_utils.enable(INSTALLED_MODULE, default_set=True),
                          lambda: addon_utils.disable(INSTALLED_MODULE, default_set=True),
                          INSTALLED_MODULE)
    res["final"] = registered_state(INSTALLED_MODULE)
    res["addon_check_final"] = list(addon_utils.check(INSTALLED_MODULE))
    res["problems"] = steps.problems
    res["log"] = steps.log
    return res


def main_source(parent):
    steps = Steps()
    res = {"mode": "source", "module": SOURCE_MODULE}
    sys.path.insert(0, parent)
    steps.run("factory settings", bpy.ops.wm.read_factory_settings, use_empty=True)
    pkg = steps.run("import", __import__, SOURCE_MODULE)
    res["imported_file"] = getattr(pkg, "__file__", None)
    res["before"] = registered_state(SOURCE_MODULE)
    if pkg is not None:
        def enable():
            pkg.register()
            return True
        res["cycles"] = cycle(steps, "register", enable, pkg.unregister, SOURCE_MODULE)
    res["final"] = registered_state(SOURCE_MODULE)
    res["problems"] = steps.problems
    res["log"] = steps.log
    return res


def main():
    mode, arg = sys.argv[1], sys.argv[2]
    res = main_install(arg) if mode == "install" else main_source(arg)
    _flush()
    print(json.dumps(res))
    sys.stdout.flush()


if __name__ == "__main__":
    main()
