"""Helpers for render tests: build demo scenes, cache path-traced references,
render test images and compare them -- each Blender job in a fresh process.

Typical use in a test::

    from fog_scenes.render_harness import ensure_reference, render_test, assert_close

    def test_street_lamps_nodes(regen, tmp_path):
        ref = ensure_reference("street_lamps", 0.08, regen=regen)
        img = render_test("street_lamps", 0.08, tmp_path / "nodes.exr", engine="cycles", method="nodes")
        assert_close(img, ref, name="street_lamps_0.08_cycles_nodes", rel_rmse=0.02)

References live in ``tests/references/<scene>_<density>.exr``: 64x36, RGBA float32,
Cycles path-traced single scattering with cast shadows and interreflection
disabled (the analytic model has neither; see fog_addon/reference.py).  They are
rendered only when missing or when pytest runs with ``--regen-references``
(fixture ``regen``) or FOG_REGEN_REFERENCES=1.
"""
import os
import pathlib
import re
import subprocess
import sys
import tempfile

from fog_addon import compare as _compare   # (pure numpy)

ROOT = pathlib.Path(__file__).resolve().parents[1]
REFERENCES = ROOT / "tests" / "references"
FAILURES = ROOT / "tests" / "_failures"
DEMO_SCENES = ROOT / "demo_scenes"

PYTHON = os.environ.get("FOG_PYTHON") or str(ROOT / ".venv" / "bin" / "python")
if not os.path.exists(PYTHON):
    PYTHON = sys.executable

# Test resolution and the sample counts that keep reference noise < 0.5 %.
TEST_RESOLUTION = (64, 36)
REFERENCE_SAMPLES = {"street_lamps": 4096, "spheres": 8192, "boulevard": 16384}
# Forward-scattering fog (g = 0.85): Cycles does not sample the phase function's peak towards its lights,
# so its noise at the counts above was 14x (street lamps: 3.7 %) and 3.5x (spheres: 0.87 %) the isotropic.
REFERENCE_SAMPLES_ANISOTROPIC = {"street_lamps": 131072, "spheres": 65536, "concert_stage": 65536,
                                 "headlights": 65536}
# Measured noise of ONE cached reference (from a second seed; difference / sqrt 2), as
# (relative RMSE, p95 per-pixel relative error, max per-pixel relative error).
# Airlight-only pixels are nearly exact (QMC); the noise sits on fog-lit surfaces
# (ground, spheres) and, with three lamps, in the street's airlight (light selection).
# Render times on 2 cores: 17-26 s (street_lamps, 4096 spp), 34-39 s (spheres, 8192 spp),
# 136-185 s (boulevard, 16384 spp: 45 lamps light the surfaces and the fog that lights them;
# 1024 spp left 1.8 % noise).
REFERENCE_NOISE = {
    ("street_lamps", 0.08): (0.0026, 0.011, 0.08),
    ("street_lamps", 0.03): (0.0020, 0.006, 0.04),
    ("spheres", 0.15): (0.0025, 0.006, 0.08),
    ("spheres", 0.05): (0.0017, 0.004, 0.04),
    ("boulevard", 0.015): (0.0049, 0.0086, 0.050),
}

# One density per scene at optical thickness <= 2 to the farthest lit object,
# plus a thinner one.  (scene, density in 1/m)
REFERENCE_CASES = [
    ("street_lamps", 0.08),
    ("street_lamps", 0.03),
    ("spheres", 0.15),
    ("spheres", 0.05),
    ("boulevard", 0.015),   # 45 lamps (issue 8): optical thickness 1.7 to the far end of the rows
]

# Log lines that mean a render is wrong whatever its picture looks like: a shader too big
# (Cycles: "ERROR Shader graph: out of SVM stack space, shader "x" too big."; EEVEE:
# "Error: Uniform block node_tree too big (76960/65536)"), GPU shader errors (compile, link),
# shader compile errors (GLSL, OSL), dependency cycles.  EGL_BAD_MATCH and "Not freed memory blocks", printed
# by every EEVEE run here, are harmless and do not match; nor does the fog's own note that EEVEE's
# uniform block limited its choice of models (it chose to fit the block).
LOG_ERRORS = [re.compile(p) for p in (
    r"too big",
    r"out of SVM stack space",
    r"(?i)\berror\b.*uniform block|uniform block.*(too big|exceed)",
    r"gpu\.shader\s*\|\s*ERROR",
    r"(?i)shader graph.*error|error.*shader graph",
    r"(?i)\bcompil\w*\b.*\b(error|failed)\b|\berror\b.*\bcompil",
    r"(?i)\bosl\b.*\berror\b",
    r"(?i)dependency cycle",   # drivers in a cycle read stale values (tests/test_dependency_cycles.py)
)]


def log_errors(text):
    """The lines of ``text`` (a Blender process's stdout + stderr) matching ``LOG_ERRORS``."""
    return [line.strip() for line in text.splitlines() if any(p.search(line) for p in LOG_ERRORS)]


NUMPY_TIER = "FOG_NUMPY_TIER"   # set by ``scripts/test.sh --numpy``: a test that starts Blender there is mis-marked


def _env():
    if os.environ.get(NUMPY_TIER) == "1":
        raise RuntimeError("a test of the numpy tier started Blender: mark it pytest.mark.render")
    env = dict(os.environ)
    env.setdefault("TMPDIR", tempfile.gettempdir())
    env["PYTHONPATH"] = str(ROOT) + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    env.setdefault("BLENDER_USER_RESOURCES", str(pathlib.Path(env["TMPDIR"]) / "blender_user"))
    return env


def bpy_flow(code, workdir, timeout=600):
    """Run Python ``code`` in a fresh Blender (bpy) process with its own user folders in ``workdir`` (no user
    preferences, presets or add-ons of the machine's) and return the JSON its last printed line holds."""
    import json
    workdir = pathlib.Path(workdir)
    _env()   # (refused in the numpy tier)
    env = dict(os.environ, BLENDER_USER_RESOURCES=str(workdir / "user"), HOME=str(workdir / "home"),
               PYTHONPATH=str(ROOT))
    r = subprocess.run([PYTHON, "-c", code], capture_output=True, text=True, timeout=timeout, cwd=workdir, env=env)
    assert r.returncode == 0, r.stderr[-3000:]
    return json.loads(r.stdout.strip().splitlines()[-1])


def run(args, timeout=600, check=True):
    """Run ``PYTHON *args`` in a fresh process from the repo root; return CompletedProcess."""
    cmd = [PYTHON] + [str(a) for a in args]
    proc = subprocess.run(cmd, cwd=str(ROOT), env=_env(), capture_output=True, text=True, timeout=timeout)
    if check and proc.returncode != 0:
        raise RuntimeError(f"command failed (exit {proc.returncode}): {' '.join(cmd)}\n"
                           f"--- stdout ---\n{proc.stdout[-4000:]}\n--- stderr ---\n{proc.stderr[-4000:]}")
    return proc


def run_bpy_code(code, *args, timeout=600, check=True):
    """Run a Python snippet (which may import bpy) in a fresh process; ``sys.argv[1:]`` = args."""
    return run(["-c", code] + [str(a) for a in args], timeout=timeout, check=check)


def density_tag(density):
    """File-name form of a density: 0.08 -> '0.08', 0.1 -> '0.1'."""
    return f"{float(density):g}"


def reference_path(scene, density, anisotropy=0.0):
    tag = f"_g{float(anisotropy):g}" if anisotropy else ""
    return REFERENCES / f"{scene}_{density_tag(density)}{tag}.exr"


def build_scene(scene, out_blend):
    """Build demo scene ``scene`` (demo_scenes/<scene>.py) into ``out_blend``; return its path."""
    script = DEMO_SCENES / f"{scene}.py"
    if not script.is_file():
        raise FileNotFoundError(f"no demo scene script {script}")
    out_blend = pathlib.Path(out_blend)
    out_blend.parent.mkdir(parents=True, exist_ok=True)
    run([script, out_blend])
    return out_blend


def _scratch():
    d = pathlib.Path(_env()["TMPDIR"]) / "fog_render_harness"
    d.mkdir(parents=True, exist_ok=True)
    return pathlib.Path(tempfile.mkdtemp(dir=d))


def scene_blend(scene, workdir=None):
    """A freshly built .blend of demo scene ``scene`` in ``workdir`` (a temp dir by default)."""
    workdir = pathlib.Path(workdir) if workdir else _scratch()
    blend = workdir / f"{scene}.blend"
    if not blend.exists():
        build_scene(scene, blend)
    return blend


def render_reference(scene, density, out, samples=None, resolution=TEST_RESOLUTION,
                     cast_shadows=False, interreflection=False, blend=None, anisotropy=0.0):
    """Path-trace the reference for ``scene`` at ``density`` (and Henyey-Greenstein ``anisotropy``)
    into ``out`` (.exr) via the CLI."""
    blend = blend or scene_blend(scene)
    samples = samples or (REFERENCE_SAMPLES_ANISOTROPIC if anisotropy else REFERENCE_SAMPLES).get(scene, 1024)
    args = ["-m", "fog_addon", "reference", blend, "--density", repr(float(density)),
            "--samples", int(samples), "--resolution", f"{resolution[0]}x{resolution[1]}", "--out", out]
    if anisotropy:
        args += ["--anisotropy", repr(float(anisotropy))]
    if not cast_shadows:
        args.append("--no-cast-shadows")
    if not interreflection:
        args.append("--no-interreflection")
    run(args, timeout=7200)   # references are slow by nature (anisotropic ones: tens of minutes)
    return pathlib.Path(out)


_REGENERATED = set()   # references re-rendered in this process (regen renders each once)


def ensure_reference(scene, density, regen=False, **kw):
    """Path of the cached reference, rendering it if missing, or if ``regen`` and it
    has not been re-rendered yet in this test session."""
    return cached_reference(reference_path(scene, density, kw.get("anisotropy", 0.0)).stem,
                            lambda out: render_reference(scene, density, out, **kw), regen)


def cached_reference(name, render, regen=False):
    """Path of the committed reference ``tests/references/<name>.exr`` (with the ``.npz`` of masks its scene script
    writes beside it, if any), made by ``render(out)`` (a path-traced render into ``out``) if missing, or if
    ``regen`` and not re-rendered yet in this test session: a scene's own path-traced reference is rendered once,
    not in every run."""
    path = REFERENCES / f"{name}.exr"
    if not path.is_file() or (regen and path not in _REGENERATED):
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(path.stem + ".tmp.exr")
        render(tmp)
        if tmp.with_suffix(".npz").is_file():
            os.replace(tmp.with_suffix(".npz"), path.with_suffix(".npz"))
        os.replace(tmp, path)
        _REGENERATED.add(path)
    return path


def render_test(scene, density, out, engine="cycles", method=None, samples=None,
                resolution=TEST_RESOLUTION, extra=(), blend=None, cast_shadows=False,
                interreflection=False, log=None, timeout=600, multiple_scattering="off"):
    """Render demo ``scene`` with the analytic fog via ``python -m fog_addon render``
    (pixel-centre sampling, cast shadows and interreflection off like the references, and single scattering
    like theirs, 0 volume bounces: ``multiple_scattering`` "off"; "on", or None for the file's setting, Dense
    Fog by the Quality by default; a ``--multiple-scattering`` in ``extra`` wins).
    ``log``: a list to which the process's stdout + stderr is appended."""
    blend = blend or scene_blend(scene)
    args = ["-m", "fog_addon", "render", blend, "--engine", engine, "--density", repr(float(density)),
            "--resolution", f"{resolution[0]}x{resolution[1]}", "--pixel-centre", "--out", out]
    if not interreflection:
        args.append("--no-interreflection")
    if method:
        args += ["--method", method]
    if samples:
        args += ["--samples", int(samples)]
    if not cast_shadows:
        args.append("--no-cast-shadows")
    if multiple_scattering is not None and "--multiple-scattering" not in extra:
        args += ["--multiple-scattering", multiple_scattering]
    args += list(extra)
    proc = run(args, timeout=timeout)
    if log is not None:
        log.append(proc.stdout + "\n" + proc.stderr)
    return pathlib.Path(out)


def compare_files(test, ref):
    """Metrics dict from fog_addon.compare for two image files."""
    return _compare.compare_files(test, ref)


def assert_close(test, ref, name, rel_rmse=0.02, p95=None, mean_ratio_tol=None, mask=None):
    """Compare ``test`` to ``ref`` (paths); on failure write tests/_failures/<name>_diff.png
    (test | reference | relative-error map) and raise AssertionError with the metrics."""
    from fog_addon import imageio
    a = imageio.read_rgb(test)
    b = imageio.read_rgb(ref)
    m = _compare.metrics(a, b, mask=mask)
    problems = []
    if not m["rel_rmse"] <= rel_rmse:
        problems.append(f"rel_rmse {m['rel_rmse']:.4g} > {rel_rmse}")
    if p95 is not None and not m["p95_rel"] <= p95:
        problems.append(f"p95_rel {m['p95_rel']:.4g} > {p95}")
    if mean_ratio_tol is not None and not abs(m["mean_ratio"] - 1.0) <= mean_ratio_tol:
        problems.append(f"mean_ratio {m['mean_ratio']:.5f} off by > {mean_ratio_tol}")
    if problems:
        FAILURES.mkdir(parents=True, exist_ok=True)
        diff = FAILURES / f"{name}_diff.png"
        _compare.write_diff(a, b, diff)
        imageio.write_exr(FAILURES / f"{name}_test.exr", a)
        raise AssertionError(f"{name}: " + "; ".join(problems) + f"\n{_compare.format_metrics(m)}\n"
                             f"diff image: {diff}")
    return m


def save_blend(path):
    """Save the open Blender file (compressed) as ``path``, its folder made; say so; returns the absolute path
    (the scene modules' ``python -m fog_scenes.<scene> OUT.blend``; needs bpy)."""
    import bpy
    out = os.path.abspath(path)
    os.makedirs(os.path.dirname(out), exist_ok=True)
    bpy.ops.wm.save_as_mainfile(filepath=out, compress=True)
    print(f"saved {out}")
    return out


# -- references of several seeds --------------------------------------------------------------------------

def render_seconds(proc):
    """The seconds a reference script printed as ``RENDER_SECONDS <s>`` (its render alone), or None."""
    return next((float(line.split()[1]) for line in proc.stdout.splitlines()
                 if line.startswith("RENDER_SECONDS")), None)


def seed_path(path, seed):
    """Where seed ``seed``'s render of a multi-seed reference ``path`` is kept (beside it): the reference's name
    without its ``_x<seeds>`` count, so a reference of more seeds reuses the renders of one of fewer."""
    path = pathlib.Path(path)
    stem = path.stem.rsplit("_x", 1)[0]
    return path.with_name(f"{stem}.seed{int(seed)}.exr")


def mean_of_seeds(path, render_seed, seeds, regen=False, times=None, keep_seeds=True):
    """Write ``path`` (an EXR) as the mean of the renders of seeds 0 .. ``seeds``-1 and return it.  A seed's
    render is ``render_seed(seed, out)`` (returning its seconds, appended to ``times``), kept beside the mean
    (``seed_path``; removed with ``keep_seeds`` False) and reused from there unless ``regen``."""
    import numpy as np
    from fog_addon import imageio
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    parts = []
    for seed in range(int(seeds)):
        kept = seed_path(path, seed)
        if kept.is_file() and not regen:
            parts.append(imageio.read(kept))
            continue
        tmp = path.with_name(f"{path.stem}.seed{seed}.tmp.exr")
        secs = render_seed(seed, tmp)
        if times is not None:
            times.append(secs)
        parts.append(imageio.read(tmp))
        if keep_seeds:
            os.replace(tmp, kept)
        else:
            os.remove(tmp)
    tmp = path.with_name(path.stem + ".tmp.exr")
    imageio.write_exr(tmp, np.mean(parts, axis=0, dtype=np.float64).astype(np.float32))
    os.replace(tmp, path)
    return path
