"""What the fog costs as lights multiply: render time with fog over render time without, same scene, same process.

    .venv/bin/python benchmarks/overhead.py [--budget S] [--lights 1,4,16,64,256] [--methods ...]
                                            [--no-boulevard] [--repeats N] [--error E|exact] [--anisotropy G]
                                            [--samples N] [--resolution WxH] [--spots] [--out CSV] [--chart PNG]
    .venv/bin/python benchmarks/overhead.py --chart-only [--out CSV] [--chart PNG]

Scenes: fog_scenes/many_lights.py (a ground plane, matte, glossy and metallic
spheres, N point lights on a grid; here with the lights lighting the surfaces
as in any scene, fog beta = 0.1 1/m) for N in 1, 4, 16, 64, 256, and
demo_scenes/boulevard.py (45 lights, its default density).  ``--spots``: every light of the
many-lights scene a spot (60 degrees, blend 0.3) aimed straight down (issue 9's overhead with spots).  Cycles CPU at
320x180, 16 spp (Blender's default filter and no denoiser; cast shadows on),
EEVEE 16 samples at the same size.

Each (scene, method) runs in ONE worker process (this script with ``--worker``):
build the scene, render it without fog (a first "cold" render, then warm ones),
add the fog (``apply_fog``, timed), render it with fog (first render, then warm
ones); EEVEE takes its no-fog warm render last, after removing the fog.  A
"warm" time is the minimum of ``repeats`` renders (fewer once they have taken
``REPEAT_BUDGET_S``); Persistent Data stays off, as for a still render, so
every Cycles render syncs (and compiles) its shaders again.  With the OSL
method the no-fog renders use SVM (what the user had before adding the fog).

Every time is measured twice: wall clock (``*_s``) and the CPU time of the
worker process over the same span (``*_cpu_s``: ``time.process_time``, all
threads, Cycles' and llvmpipe's included).  The machine is shared: another
process on the cores stretches wall times, not CPU times, so the CPU ratios
(``ratio_*_cpu``) are the ones to read; the wall ratios are kept beside them.
(On an idle machine the two differ a little: Cycles samples on every core, its
shader set-up runs on one, so the CPU ratio weighs the set-up less.)

* ``ratio_warm(_cpu)`` = fog warm / no-fog warm: the price per frame;
* ``ratio_first(_cpu)`` = fog first / no-fog first: what an artist waits for
  the first picture (shader compilation included).  ``fog_first_setup_s``:
  the part of the first render with fog before Cycles' first sample (sync,
  shader compilation, images).  EEVEE's shader compilation is most of its
  cost: its first render is the figure to read (one warm render each, as
  EEVEE caches compiled shaders).  Here (llvmpipe) EEVEE's second render of a
  scene took longer than its first, with and without fog alike: compare first
  with first, warm with warm.
* ``status``: ok; ``partial`` (killed by the budget during the warm renders
  with fog: the first-render ratio stands); ``timeout`` (killed before the
  first render with fog finished; ``fog_first_s``/``_cpu_s`` are then what it
  had run, lower bounds, and ``fog_first_est_cpu_s`` an extrapolation from the
  samples done, if Cycles reported any: ``ratio_first_est_cpu``); ``apply
  only`` (the method timed out with fewer lights, or ``--apply-only``: the scene
  is built, rendered once without fog and the fog added, timed, but not
  rendered; killed while adding the fog: ``timeout``, and the note says how long
  ``apply_fog`` had run); ``not run`` (adding the fog timed out with fewer
  lights); ``error``.

The picture is checked two ways (``picture_ok`` False if either fails):
the worker's log (fog_scenes/render_harness.py ``log_errors``: shaders too big for
Cycles' SVM stack or EEVEE's uniform block, GPU/OSL shader errors), and the
pictures themselves (off the clock, the last render without and the first with
fog saved as EXR): ``mean_nofog``, ``mean_fog`` (mean luminance),
``surface_ratio`` (median fog / no-fog luminance over the pixels the no-fog
render lights, > 5 % of its 95th percentile) and ``dark_frac`` (share of
pixels the fog leaves darker than 1 % of the no-fog render's 95th percentile,
where the no-fog render was brighter than that).  The fog dims surfaces by its
transmittance and adds its own light, and it lights every pixel; a material
gone black (a broken closure chain, a shader that did not compile) shows as a
``surface_ratio`` near 0 or a large ``dark_frac``: ``picture_check`` "dark" when
``surface_ratio`` < ``DARK_SURFACE_RATIO`` or ``dark_frac`` > ``DARK_FRAC``.  A picture
can also be wrong without black materials (OSL from ~45 lights: its glow and fog light
several times too dark): every method renders the same fog, so a fogged picture whose
mean luminance is below ``DARK_VS_BRIGHTEST`` of another method's for the same scene
is "darker" (EEVEE and Cycles agree to ~3 % here); a scene only one method rendered
is "suspect" if its fogged mean is below ``DARK_GAIN`` times its no-fog mean (the
fog's glow brightens every scene here: measured 1.5-2.4x).

``--error`` (Quality: target error, a number, ``draft``, ``final`` or ``exact``) is passed to
``apply_fog(error=...)``; the CSV records it (``error``: what was asked, ``error_passed``: whether
it was passed).  Without ``--error`` the add-on's default is used.
With ``--error`` the outputs default to ``overhead_error-<E>.csv/png``, so a
run per Quality keeps the others.  ``--anisotropy G`` (Henyey-Greenstein g, default 0)
is passed to ``apply_fog(anisotropy=G)``; with G != 0 the outputs get ``_g<G>``
(``overhead_g0.85.csv``), and the CSV records it (``anisotropy``).

Each worker has a wall-clock budget (``--budget``): when it runs out the
worker is killed and the case recorded with whatever it measured (on a busy
machine the worker gets less than the budget in CPU time: ``process_cpu_s``).
Once a method times out, its cases with more lights are run "apply only".

Adding the fog to 1 000 materials: benchmarks/materials_1000.py.

Outputs: benchmarks/out/overhead.csv and docs/figures/overhead.png (ratio vs
number of lights, log-log, one line per method/engine, the issue's goals
drawn: 1 light <= 1.5x, 16 lights <= 2x, 64 lights <= 3x).

Smoke mode (``FOG_BENCH_SMOKE=1``, benchmarks/smoke.py): 1 light, no boulevard, Cycles' node groups and EEVEE,
8x4 px, 1 sample, one warm render; a row not "ok" or with log errors fails the run.
"""
import argparse
import csv
import json
import math
import os
import pathlib
import re
import resource
import subprocess
import sys
import tempfile
import time

import csv_rows
import smoke

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))   # a script run by path: the repository root (fog_addon, fog_scenes)

OUT = smoke.out(ROOT / "benchmarks" / "out")
CSV = OUT / "overhead.csv"
DATA = ROOT / "docs" / "measurements" / "data"   # the committed CSVs (benchmarks/out is not tracked)
PNG = smoke.out(ROOT / "docs" / "figures" / "overhead.png")

LIGHTS = smoke.pick((1, 4, 16, 64, 256), (1,))
BOULEVARD_LIGHTS = 45
# name: (engine, method preference); the order of the table and the chart
METHODS = {"cycles_nodes": ("CYCLES", "nodes"), "cycles_osl": ("CYCLES", "osl"), "eevee": ("BLENDER_EEVEE", "nodes"),
           "cycles_compositor": ("CYCLES", "compositor"), "eevee_compositor": ("BLENDER_EEVEE", "compositor"),
           "cycles_auto": ("CYCLES", "auto"), "eevee_auto": ("BLENDER_EEVEE", "auto")}
RESOLUTION = smoke.pick((320, 180), (8, 4))
SAMPLES = smoke.pick(16, 1)
DENSITY = 0.1                  # 1/m for the many-lights scenes (the boulevard uses its own default)
BUDGET_S = 200.0               # per worker
REPEATS = smoke.pick(3, 1)
REPEAT_BUDGET_S = 12.0         # no more warm repeats once they have taken this long
BEAT_S = 2.0                   # heartbeat period during a render (for timeouts)
DARK_SURFACE_RATIO = 0.05      # picture check: median fog / no-fog over lit pixels below this: "dark"
DARK_FRAC = 0.2                # ... or more than this share of lit pixels gone dark
DARK_VS_BRIGHTEST = 0.8        # fogged mean luminance below this share of another method's: "darker"
DARK_GAIN = 0.5                # alone: fogged mean below this share of the no-fog mean: "suspect"
GOALS = ((1, 1.5), (16, 2.0), (64, 3.0))   # the issue's: (lights, max fog / no fog)
FIELDS = ["case", "lights", "method", "engine", "error", "error_passed", "anisotropy", "spots", "status", "picture_ok",
          "picture_check", "log_errors",
          "ratio_warm_cpu", "ratio_first_cpu", "ratio_warm", "ratio_first", "ratio_first_est_cpu",
          "nofog_first_s", "nofog_first_cpu_s", "nofog_warm_s", "nofog_warm_cpu_s",
          "fog_apply_s", "fog_apply_cpu_s", "fog_first_s", "fog_first_cpu_s", "fog_first_setup_s",
          "fog_first_est_cpu_s", "fog_warm_s", "fog_warm_cpu_s", "repeats",
          "mean_nofog", "mean_fog", "surface_ratio", "dark_frac",
          "budget_s", "process_s", "process_cpu_s", "load_avg_start", "load_avg_end", "threads",
          "resolution", "samples", "source", "note"]
TEXT_FIELDS = ("case", "method", "engine", "error", "error_passed", "status", "picture_ok", "picture_check",
               "resolution", "source", "note")


def load_avg():
    try:
        return round(os.getloadavg()[0], 2)
    except OSError:
        return ""


def parse_error(text):
    """``--error`` value: None (not given: the add-on's default), "exact", a preset name or a float."""
    if text is None:
        return None
    if text.lower() in ("exact", "none"):
        return "exact"
    if text.lower() in ("draft", "final"):
        return text.lower()
    return float(text)


def error_tag(err):
    return "default" if err is None else (err if isinstance(err, str) else f"{err:g}")


def source_id():
    """The fog code measured: the commit (+ "-dirty" when fog_addon/ differs from it), or FOG_SOURCE."""
    if os.environ.get("FOG_SOURCE"):
        return os.environ["FOG_SOURCE"]
    try:
        head = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True,
                              text=True, check=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(ROOT), "status", "--porcelain", "--", "fog_addon"],
                               capture_output=True, text=True).stdout.strip()
        return head + ("-dirty" if dirty else "")
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


# ---------------------------------------------------------------- workers (inside bpy)

def as_spots(scene):
    """Every light of ``scene`` a spot (60 degrees, blend 0.3) aimed straight down: ``--spots``."""
    for ob in scene.objects:
        if ob.type == "LIGHT":
            ob.data.type = "SPOT"
            ob.data.spot_size, ob.data.spot_blend = math.radians(60.0), 0.3
            ob.rotation_euler = (0.0, 0.0, 0.0)   # local -Z: straight down


def _emit(result):
    print("OVERHEAD_JSON " + json.dumps(result), flush=True)


class _Beat:
    """render_stats handler: while a render runs, print its elapsed wall/CPU time and Cycles' last
    "Sample k/N" every BEAT_S (the driver reads the last one if it has to kill the worker); note when
    the first sample line came (the set-up before it: sync, shader compilation, images)."""

    def __init__(self):
        self.phase, self.t0, self.c0, self.last, self.first_sample = None, 0.0, 0.0, 0.0, None
        self.first_sample_cpu = None
        self.sample = None   # (k, n, wall, cpu) of the latest "Sample k/n" line

    def start(self, phase):
        self.phase, self.t0, self.c0 = phase, time.perf_counter(), time.process_time()
        self.last, self.first_sample, self.sample, self.first_sample_cpu = self.t0, None, None, None
        # when the render started (epoch) and the process's CPU time then: the driver's lower bounds if it
        # has to kill the worker (stats updates, hence beats, stop while Cycles works on a sample)
        self.started = time.time()
        self._print(self.t0, self.c0)

    def _print(self, now, cpu):
        print("OVERHEAD_BEAT " + json.dumps({"phase": self.phase, "started": self.started, "cpu_at_start": self.c0,
                                             "wall": now - self.t0, "cpu": cpu - self.c0, "sample": self.sample,
                                             "first_sample": self.first_sample,
                                             "first_sample_cpu": self.first_sample_cpu}), flush=True)

    def __call__(self, stats, *_):
        if self.phase is None:
            return
        now, cpu = time.perf_counter(), time.process_time()
        m = re.search(r"Sample (\d+)/(\d+)", str(stats))
        if m:
            if self.first_sample is None:
                self.first_sample, self.first_sample_cpu = now - self.t0, cpu - self.c0
            self.sample = (int(m.group(1)), int(m.group(2)), now - self.t0, cpu - self.c0)
        if now - self.last >= BEAT_S:
            self.last = now
            self._print(now, cpu)


BEAT = _Beat()


def _render(scene, phase):
    import bpy
    BEAT.start(phase)
    c, t = time.process_time(), time.perf_counter()
    bpy.ops.render.render(write_still=False, scene=scene.name)
    wall, cpu = time.perf_counter() - t, time.process_time() - c
    BEAT.phase = None
    return wall, cpu


def _warm(scene, repeats, phase):
    walls, cpus = [], []
    while len(walls) < repeats and (not walls or sum(walls) < REPEAT_BUDGET_S):
        w, c = _render(scene, phase)
        walls.append(w)
        cpus.append(c)
    return min(walls), min(cpus), len(walls)


def cost_settings(scene, cycles, resolution, samples):
    """A cost benchmark's render settings: Cycles on the CPU (or EEVEE, its light threshold at most 1e-4),
    ``resolution`` (w, h) and ``samples``, no denoiser, and EXR output for the picture check's save_render."""
    from fog_addon import measure
    scene.render.engine = "CYCLES" if cycles else "BLENDER_EEVEE"
    measure.set_resolution(scene, *resolution)
    measure.set_samples(scene, samples)
    measure.set_cycles_cpu(scene)
    scene.cycles.use_denoising = False
    if not cycles:
        scene.eevee.light_threshold = min(scene.eevee.light_threshold, 1e-4)
    im = scene.render.image_settings
    im.media_type, im.file_format, im.color_depth, im.color_mode = "IMAGE", "OPEN_EXR", "32", "RGB"


def _save_render(scene, path):
    """The last render (Render Result) as a float EXR, off the clock; its luminance (H, W)."""
    import bpy
    from fog_addon import imageio
    bpy.data.images["Render Result"].save_render(str(path), scene=scene)
    rgb = imageio.read(path, channels=3).astype("float64")
    return 0.2126 * rgb[..., 0] + 0.7152 * rgb[..., 1] + 0.0722 * rgb[..., 2]


def picture_stats(nofog, fog):
    """Mean luminances, the median fog / no-fog ratio over the pixels the no-fog render lights, and the
    share of those the fog leaves dark; and the verdict ("ok" or "dark")."""
    import numpy as np
    ref = float(np.percentile(nofog, 95))
    lit = nofog > 0.05 * ref
    out = {"mean_nofog": float(nofog.mean()), "mean_fog": float(fog.mean())}
    if ref > 0 and lit.any():
        out["surface_ratio"] = float(np.median(fog[lit] / nofog[lit]))
        was = nofog > 0.01 * ref
        out["dark_frac"] = float(np.mean(fog[was] < 0.01 * ref))
        dark = out["surface_ratio"] < DARK_SURFACE_RATIO or out["dark_frac"] > DARK_FRAC
    else:   # a black picture without fog: only "the fog lights something" can be checked
        dark = not out["mean_fog"] > 0
    out["picture_check"] = "dark" if dark else "ok"
    return out


def _apply_kwargs(error):
    """(kwargs for apply_fog, passed?): ``error=`` when a Quality was asked for."""
    if error is None:
        return {}, ""
    return {"error": None if error == "exact" else (error if isinstance(error, str) else float(error))}, True


def worker(spec):
    """Time one (scene, method): no fog (first, warm), apply, fog (first, warm); print results as they come."""
    import bpy
    from fog_addon import measure
    from fog_addon.ops import apply

    engine, method = METHODS[spec["method"]]
    if spec["case"] == "boulevard":
        from demo_scenes import boulevard
        bpy.ops.wm.read_factory_settings(use_empty=True)
        scene = bpy.context.scene
        boulevard.build(scene)
        density = boulevard.DEFAULT_DENSITY
    else:
        from fog_scenes import many_lights
        scene, _ = many_lights.build_scene(spec["lights"], direct_light=True)
        density = DENSITY
        if spec.get("spots"):
            as_spots(scene)
    scene.render.engine = engine
    measure.set_resolution(scene, *spec["resolution"])
    measure.set_samples(scene, spec["samples"])
    measure.set_cycles_cpu(scene)
    scene.cycles.use_denoising = False
    if engine == "BLENDER_EEVEE":
        scene.eevee.light_threshold = min(scene.eevee.light_threshold, 1e-4)
    im = scene.render.image_settings   # for the picture check's save_render (renders write nothing)
    im.media_type = "IMAGE"
    im.file_format = "OPEN_EXR"
    im.color_depth = "32"
    im.color_mode = "RGB"
    bpy.app.handlers.render_stats.append(BEAT)
    tmp = pathlib.Path(os.environ.get("TMPDIR") or tempfile.gettempdir())
    tag = f"{spec['case']}_{spec['lights']}_{spec['method']}_{os.getpid()}"
    kwargs, passed = _apply_kwargs(spec.get("error"))
    res = {"lights": len([o for o in scene.objects if o.type == "LIGHT"]), "error_passed": passed,
           "threads": scene.render.threads}
    res["nofog_first_s"], res["nofog_first_cpu_s"] = _render(scene, "nofog_first")
    _emit(res)
    cycles = engine == "CYCLES"
    repeats = spec["repeats"] if cycles else 1   # EEVEE renders are slow here (software GL)
    if cycles and not spec.get("apply_only"):
        res["nofog_warm_s"], res["nofog_warm_cpu_s"], _ = _warm(scene, repeats, "nofog_warm")
        _emit(res)
    nofog = _save_render(scene, tmp / f"{tag}_nofog.exr")
    _emit(dict(res, apply_started=time.time()))
    c, t = time.process_time(), time.perf_counter()
    apply.apply_fog(scene, density, anisotropy=spec.get("anisotropy", 0.0), method=method, **kwargs)
    res["fog_apply_s"], res["fog_apply_cpu_s"] = time.perf_counter() - t, time.process_time() - c
    res["note"] = apply.method_line(apply.stored_choice() or {}) or ""   # the method Auto chose, and why
    scene.cycles.use_denoising = False
    _emit(res)
    if spec.get("apply_only"):
        return 0
    res["fog_first_s"], res["fog_first_cpu_s"] = _render(scene, "fog_first")
    if BEAT.first_sample is not None:
        res["fog_first_setup_s"] = BEAT.first_sample
    _emit(res)
    res.update(picture_stats(nofog, _save_render(scene, tmp / f"{tag}_fog.exr")))
    _emit(res)
    res["fog_warm_s"], res["fog_warm_cpu_s"], res["repeats"] = _warm(scene, repeats, "fog_warm")
    _emit(res)
    if not cycles:   # EEVEE: the no-fog warm render last (the first-render ratio comes first within the budget)
        apply.remove_fog(scene)
        res["nofog_warm_s"], res["nofog_warm_cpu_s"], _ = _warm(scene, repeats, "nofog_warm")
        _emit(res)
    return 0


# ---------------------------------------------------------------- driver

def log_errors(text):
    from fog_scenes import render_harness as h
    return h.log_errors(text)


def run_worker(spec, budget):
    """Run a worker with a hard time limit; (last result, last heartbeat, log text, timed out?, wall s, CPU s)."""
    from fog_scenes import render_harness as h
    env = h._env()
    env["PYTHONUNBUFFERED"] = "1"
    cmd = [h.PYTHON, str(pathlib.Path(__file__).resolve()), "--worker", json.dumps(spec)]
    t = time.perf_counter()
    ru0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    try:
        proc = subprocess.run(cmd, cwd=str(ROOT), env=env, capture_output=True, text=True, timeout=budget)
        out, err, timed_out, rc = proc.stdout, proc.stderr, False, proc.returncode
    except subprocess.TimeoutExpired as exc:   # the child is killed and waited for: its CPU is counted
        dec = (lambda b: b.decode(errors="replace") if isinstance(b, bytes) else (b or ""))
        out, err, timed_out, rc = dec(exc.stdout), dec(exc.stderr), True, None
    wall = time.perf_counter() - t
    ended = time.time()
    ru1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (ru1.ru_utime - ru0.ru_utime) + (ru1.ru_stime - ru0.ru_stime)
    lines = [ln for ln in out.splitlines() if ln.startswith("OVERHEAD_JSON ")]
    res = json.loads(lines[-1].split(" ", 1)[1]) if lines else {}
    beats = [ln for ln in out.splitlines() if ln.startswith("OVERHEAD_BEAT ")]
    beat = json.loads(beats[-1].split(" ", 1)[1]) if beats else None
    if beat is not None:   # the running render's time up to the end (kill): wall, and CPU from the process total
        beat["wall"] = max(beat["wall"], ended - beat["started"])
        beat["cpu"] = max(beat["cpu"], cpu - beat["cpu_at_start"])
    if rc not in (0, None):
        res["error"] = f"exit {rc}: " + " | ".join((err.strip() or out.strip()).splitlines()[-3:])
    return res, beat, out + "\n" + err, timed_out, wall, cpu


def measure_case(case, n, method, args, apply_only=False):
    engine, _ = METHODS[method]
    spec = {"case": case, "lights": n, "method": method, "repeats": args.repeats, "error": args.error,
            "anisotropy": args.anisotropy, "spots": args.spots,
            "resolution": args.resolution, "samples": args.samples, "apply_only": apply_only}
    load0 = load_avg()
    res, beat, log, timed_out, wall, cpu = run_worker(spec, args.budget)
    errors = log_errors(log)
    smoke.echo(log)
    row = {"case": case, "lights": res.get("lights", n), "method": method, "engine": engine,
           "error": error_tag(args.error), "error_passed": res.get("error_passed", ""), "anisotropy": args.anisotropy,
           "spots": args.spots, "budget_s": args.budget, "process_s": wall, "process_cpu_s": cpu, "load_avg_start": load0,
           "load_avg_end": load_avg(), "resolution": "{}x{}".format(*args.resolution), "samples": args.samples,
           "source": args.source, "log_errors": len(errors)}
    for k in ("threads", "nofog_first_s", "nofog_first_cpu_s", "nofog_warm_s", "nofog_warm_cpu_s", "fog_apply_s",
              "fog_apply_cpu_s", "fog_first_s", "fog_first_cpu_s", "fog_first_setup_s", "fog_warm_s",
              "fog_warm_cpu_s", "repeats", "mean_nofog", "mean_fog", "surface_ratio", "dark_frac", "picture_check"):
        if k in res:
            row[k] = res[k]
    notes = []
    if apply_only:
        row["status"] = "error" if "error" in res else ("timeout" if timed_out else "apply only")
        notes.append(args.skip_note)
        if "error" in res:
            notes.append(res["error"])
        elif timed_out and "apply_started" in res:
            notes.append(f"killed while adding the fog: apply_fog ran > {time.time() - res['apply_started']:.0f} s")
        elif timed_out:
            notes.append("killed before the fog was added")
    elif timed_out and "fog_first_s" in res:
        row["status"] = "partial"   # the first render with fog finished; warm renders cut by the budget
        notes.append("killed during the warm renders with fog")
    elif timed_out:
        row["status"] = "timeout"
        if beat and beat["phase"] == "fog_first":   # killed during the first render with fog: lower bounds
            row["fog_first_s"], row["fog_first_cpu_s"] = beat["wall"], beat["cpu"]
            if beat.get("first_sample") is not None:
                row["fog_first_setup_s"] = beat["first_sample"]
            what = f"first render with fog still running at the budget: > {beat['wall']:.0f} s, > {beat['cpu']:.0f} s CPU"
            s = beat.get("sample")
            if s and s[0] > 0:   # Cycles' "Sample k/n" (k done): set-up + the samples, linear in samples
                k, total, _, cpu_k = s
                setup = beat.get("first_sample_cpu") or 0.0   # CPU before the first sample line
                row["fog_first_est_cpu_s"] = setup + (cpu_k - setup) * total / k
                what += (f"; set-up {setup:.0f} s CPU, then {k}/{total} samples done at {cpu_k:.0f} s CPU: about "
                         f"{row['fog_first_est_cpu_s']:.0f} s CPU in all")
            else:
                what += "; no sample finished"
            notes.append(what)
        elif "fog_apply_s" in res:
            notes.append("killed after adding the fog, before its first render started")
        elif "apply_started" in res:
            notes.append(f"killed while adding the fog: apply_fog ran > {time.time() - res['apply_started']:.0f} s")
        else:
            notes.append("killed before the fog was added")
    elif "error" in res:
        row["status"] = "error"
        notes.append(res["error"])
    else:
        row["status"] = "ok"
    for key, num, den in (("ratio_warm", "fog_warm_s", "nofog_warm_s"), ("ratio_first", "fog_first_s", "nofog_first_s"),
                          ("ratio_warm_cpu", "fog_warm_cpu_s", "nofog_warm_cpu_s"),
                          ("ratio_first_cpu", "fog_first_cpu_s", "nofog_first_cpu_s"),
                          ("ratio_first_est_cpu", "fog_first_est_cpu_s", "nofog_first_cpu_s")):
        if num in row and den in row and row[den] > 0:
            row[key] = row[num] / row[den]
    if row["status"] == "timeout" and "ratio_first" in row:
        notes.append("ratios are lower bounds")
    dark = row.get("picture_check") == "dark"
    row["picture_ok"] = False if (errors or dark) else (True if row.get("picture_check") == "ok" else "")
    if errors:
        notes.append(f"{len(errors)} log errors, e.g. {errors[0][:120]!r}: the picture is wrong")
    if dark:
        notes.append(f"picture dark with fog: surface ratio {row.get('surface_ratio', float('nan')):.3g}, "
                     f"{100 * row.get('dark_frac', float('nan')):.0f} % of lit pixels dark")
    if res.get("note"):
        notes.insert(0, res["note"])
    row["note"] = "; ".join(notes)
    return row


def cross_check(rows):
    """Each method renders the same fog: a fogged picture much darker than another method's of the same
    scene (mean luminance below ``DARK_VS_BRIGHTEST`` of the brightest) is wrong (e.g. OSL's long chain
    of Add Shader closures, nearly black from ~45 lights); with no other method to compare with, a
    fogged picture darker than ``DARK_GAIN`` times the same scene without fog is suspect (here the fog
    brightens every scene: its glow lights the black background)."""
    by_case = {}
    for r in rows:
        if isinstance(r.get("mean_fog"), float):
            by_case.setdefault((r["case"], r["lights"]), []).append(r)
    for group in by_case.values():
        best = max(group, key=lambda r: r["mean_fog"])
        for r in group:
            r.pop("cross_note", None)
            if r.get("picture_check") not in ("ok", "darker", "suspect"):
                continue
            rel = r["mean_fog"] / best["mean_fog"] if best["mean_fog"] > 0 else 1.0
            gain = r["mean_fog"] / r["mean_nofog"] if r.get("mean_nofog") else float("inf")
            if len(group) > 1 and rel < DARK_VS_BRIGHTEST:
                r["picture_check"], r["picture_ok"] = "darker", False
                r["cross_note"] = f"picture {rel:.2f}x as bright as {best['method']}'s (mean luminance): wrong"
            elif len(group) == 1 and gain < DARK_GAIN:
                r["picture_check"], r["picture_ok"] = "suspect", False
                r["cross_note"] = (f"fogged picture {gain:.2f}x as bright as without fog, no other method "
                                   "to compare with: suspect")
            else:
                r["picture_check"] = "ok"
                r["picture_ok"] = False if r.get("log_errors") else True
        for r in group:
            base = r["note"].split(" || ")[0]
            r["note"] = base + (" || " + r["cross_note"] if r.get("cross_note") else "")


def merged(new, old):
    """``old`` rows not re-measured in ``new``, and ``new``, in the table's order (method, lights)."""
    done = {(r["case"], int(r["lights"]), r["method"]) for r in new}
    rows = [r for r in old if (r["case"], int(r["lights"]), r["method"]) not in done] + list(new)
    order = list(METHODS)
    return sorted(rows, key=lambda r: (order.index(r["method"]) if r["method"] in order else 99, int(r["lights"])))


def read_csv(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    for r in rows:
        for k, v in r.items():
            try:
                r[k] = float(v) if k not in TEXT_FIELDS else v
            except ValueError:
                pass
        r["picture_ok"] = {"True": True, "False": False}.get(r["picture_ok"])
    return rows


def chart(rows, path):
    """Ratio (fog / no fog, CPU time) vs lights, log-log: per method the warm ratio (solid) and the
    first-render ratio (dashed), through the cases measured; the wall-clock ratios as small grey-edged
    dots.  Crosses: the picture is wrong (log errors or dark materials): that time is not the fog's
    (the lines skip them).
    Open markers with an arrow: timeouts (the ratio is at least this); a faint open marker: the
    extrapolated ratio.  The boulevard (45 lights) is a star.  Black squares: the issue's goals."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(12, 6.5))
    labels = {"cycles_nodes": "Cycles, node groups", "cycles_osl": "Cycles, OSL", "eevee": "EEVEE, node groups",
              "cycles_compositor": "Cycles, compositor", "eevee_compositor": "EEVEE, compositor",
              "cycles_auto": "Cycles, Auto (default)", "eevee_auto": "EEVEE, Auto (default)"}

    def point(x, y, r, colour, big, est=None):
        ms = 12 if big else 7
        if r["status"] == "timeout":
            ax.plot([x], [y], "*" if big else "o", mfc="none", mec=colour, ms=ms, mew=1.2)
            ax.annotate("", (x, y * 1.6), (x, y), arrowprops=dict(arrowstyle="->", color=colour))
            if isinstance(est, float):
                ax.plot([x], [est], "*" if big else "o", mfc="none", mec=colour, ms=ms, mew=0.8, alpha=0.5)
                ax.plot([x, x], [y, est], ":", color=colour, lw=0.8, alpha=0.5)
        elif r["picture_ok"] is False:
            ax.plot([x], [y], "X" if big else "x", color=colour, ms=ms + 2, mew=2)
        else:
            ax.plot([x], [y], "*" if big else "o", color=colour, ms=ms)

    for i, method in enumerate(METHODS):
        colour = f"C{i}"
        for key, ls, what in (("ratio_warm_cpu", "-", "warm render"), ("ratio_first_cpu", "--", "first render")):
            mine = [r for r in rows if r["method"] == method and isinstance(r.get(key), float)]
            done = sorted((r for r in mine if r["case"] == "lights" and r["status"] in ("ok", "partial")
                           and r.get("picture_ok") is not False),
                          key=lambda r: r["lights"])
            if done:
                ax.plot([r["lights"] for r in done], [r[key] for r in done], ls, color=colour, lw=1.2,
                        label=f"{labels[method]}: {what}")
            for r in mine:
                est = r.get("ratio_first_est_cpu") if key == "ratio_first_cpu" else None
                point(r["lights"], r[key], r, colour, r["case"] == "boulevard", est)
            wall = [r for r in rows if r["method"] == method and isinstance(r.get(key[:-4]), float)
                    and r["status"] != "timeout"]
            ax.plot([r["lights"] * (1.04 if ls == "--" else 0.96) for r in wall], [r[key[:-4]] for r in wall],
                    ".", color=colour, mec="grey", ms=5, alpha=0.8)
    gx, gy = zip(*GOALS)
    ax.plot(gx, gy, "s-", color="black", ms=7, lw=2, alpha=0.6, label="issue's goals: 1 light 1.5x, 16: 2x, 64: 3x")
    ax.plot([], [], "x", color="grey", ms=9, mew=2, ls="none",
            label="picture wrong (log errors or dark materials)")
    ax.plot([], [], "o", mfc="none", mec="grey", ms=7, ls="none", label="timeout: the ratio is at least this")
    ax.plot([], [], "o", mfc="none", mec="grey", ms=7, mew=0.8, alpha=0.5, ls="none",
            label="timeout: extrapolated from the samples done")
    ax.plot([], [], ".", color="grey", ms=5, ls="none", label="wall-clock ratio (shared machine)")
    ax.plot([], [], "*", color="grey", ms=12, ls="none", label=f"boulevard ({BOULEVARD_LIGHTS} lights)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xticks(list(LIGHTS) + [BOULEVARD_LIGHTS])
    ax.set_xticklabels([str(n) for n in LIGHTS] + [str(BOULEVARD_LIGHTS)])
    ax.set_xlim(0.7, 370)
    ax.set_xlabel("spots" if any(str(r.get("spots")) == "True" for r in rows) else "point lights")
    ax.set_ylabel("render CPU time with fog / without fog")
    res = rows[0].get("resolution", "") if rows else ""
    spp = rows[0].get("samples", "") if rows else ""
    err = rows[0].get("error", "") if rows else ""
    src = ", ".join(dict.fromkeys(str(r.get("source", "")) for r in rows))   # every commit the rows were measured at
    g = rows[0].get("anisotropy", "") if rows else ""
    err = f"{err}, g {g:g}" if isinstance(g, float) and g else err
    ax.set_title(f"Cost of the fog, {res}, {spp:g} spp, Cycles CPU (2 cores) / EEVEE (llvmpipe); Quality: {err}; "
                 f"code {src}\n(benchmarks/overhead.py)" if isinstance(spp, (int, float)) else "Cost of the fog", fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7.5, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0)
    skipped = {}
    for r in rows:
        unrendered = r["status"] == "timeout" and not isinstance(r.get("fog_first_s"), float)
        if r["status"] in ("apply only", "not run") or unrendered:
            what = "fog added" if r["status"] == "apply only" else (
                "killed before rendering with fog" if unrendered else "not run")
            skipped.setdefault(labels.get(r["method"], r["method"]), []).append(
                f"{int(r['lights'])}{' (boulevard)' if r['case'] == 'boulevard' else ''} ({what})")
    if skipped:
        fig.text(0.01, 0.005, "No render with fog (the method timed out with fewer lights):\n" + "\n".join(
            f"    {m}: {', '.join(v)}" for m, v in skipped.items()), fontsize=7, va="bottom")
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.tight_layout(rect=(0, 0.07, 1, 1))
    fig.savefig(path, dpi=130, bbox_inches="tight")
    plt.close(fig)


def fmt(v, unit=""):
    return f"{v:.3g}{unit}" if isinstance(v, float) else (str(v) if v not in (None, "") else "-")


def print_table(rows):
    print(f"\n{'case':10} {'lights':>6} {'method':13} {'status':10} {'pic':4} {'nofog cpu':>9} {'apply s':>8} "
          f"{'fog1 cpu':>9} {'fogw cpu':>9} {'warm cpu':>9} {'1st cpu':>8} {'warm wall':>9} {'1st wall':>8} "
          f"{'surf':>5}")
    for r in rows:
        print(f"{r['case']:10} {int(r['lights']):6d} {r['method']:13} {r['status']:10} "
              f"{ {True: 'ok', False: 'BAD'}.get(r.get('picture_ok'), '?'):4} "
              f"{fmt(r.get('nofog_warm_cpu_s') or r.get('nofog_first_cpu_s')):>9} {fmt(r.get('fog_apply_s')):>8} "
              f"{fmt(r.get('fog_first_cpu_s')):>9} {fmt(r.get('fog_warm_cpu_s')):>9} "
              f"{fmt(r.get('ratio_warm_cpu')):>9} {fmt(r.get('ratio_first_cpu')):>8} {fmt(r.get('ratio_warm')):>9} "
              f"{fmt(r.get('ratio_first')):>8} {fmt(r.get('surface_ratio')):>5}  {r.get('note', '')[:110]}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--budget", type=float, default=BUDGET_S, help="seconds per (scene, method) worker")
    ap.add_argument("--lights", default=",".join(map(str, LIGHTS)))
    ap.add_argument("--methods", default=smoke.pick(",".join(METHODS), "cycles_nodes,eevee"))
    ap.add_argument("--repeats", type=int, default=REPEATS)
    ap.add_argument("--no-boulevard", action="store_true", default=smoke.ON)
    ap.add_argument("--apply-only", action="store_true", help="only time adding the fog (no fog renders)")
    ap.add_argument("--update", action="store_true",
                    help="keep the CSV's other rows: replace only the (case, lights, method) rows run now")
    ap.add_argument("--error", help="Quality: target error passed to apply_fog(error=...) if it has that "
                                    "keyword: a number (0.05, 0.01), draft, final or exact; default: the add-on's")
    ap.add_argument("--anisotropy", type=float, default=0.0,
                    help="Henyey-Greenstein g passed to apply_fog(anisotropy=...); default 0 (isotropic)")
    ap.add_argument("--spots", action="store_true", help="the many-lights scene's lights as spots")
    ap.add_argument("--samples", type=int, default=SAMPLES, help="(the issue's protocol: 16)")
    ap.add_argument("--resolution", default="{}x{}".format(*RESOLUTION), help="(the issue's protocol: 320x180)")
    ap.add_argument("--out", help="CSV (default benchmarks/out/overhead[_error-E][_gG].csv)")
    ap.add_argument("--chart", help="PNG (default docs/figures/overhead[_error-E][_gG].png)")
    ap.add_argument("--chart-only", action="store_true", help="redraw the chart from the CSV")
    ap.add_argument("--worker", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.worker:
        spec = json.loads(args.worker)
        return worker(spec)
    args.error = parse_error(args.error)
    suffix = ("" if args.error is None else f"_error-{error_tag(args.error)}") + (
        f"_g{args.anisotropy:g}" if args.anisotropy else "") + ("_spots" if args.spots else "")
    csv_path = pathlib.Path(args.out) if args.out else OUT / f"overhead{suffix}.csv"
    png_path = pathlib.Path(args.chart) if args.chart else PNG.with_name(f"overhead{suffix}.png")
    # read a run of one's own in benchmarks/out if there is one, else the committed CSV of that name
    read_path = csv_path if args.out or csv_path.exists() else DATA / csv_path.name
    if args.chart_only:
        rows = read_csv(read_path)
        chart(rows, png_path)
        print_table(rows)
        return 0
    args.resolution = [int(v) for v in args.resolution.lower().split("x")]
    args.source = source_id()
    os.environ.setdefault("TMPDIR", tempfile.mkdtemp(prefix="overhead_"))
    t0 = time.perf_counter()
    print(f"code {args.source}, Quality {error_tag(args.error)}, g {args.anisotropy:g}, {args.resolution[0]}x{args.resolution[1]}, "
          f"{args.samples} spp, budget {args.budget:g} s per worker, load {load_avg()}, {os.cpu_count()} CPUs",
          flush=True)
    lights = sorted(int(x) for x in args.lights.split(",") if x.strip() and x.strip().lower() != "none")
    cases = [("lights", n) for n in lights]
    if not args.no_boulevard:
        cases.append(("boulevard", BOULEVARD_LIGHTS))
        cases.sort(key=lambda c: c[1])
    rows = []
    kept = read_csv(read_path) if args.update and read_path.exists() else []
    run_now = {(case, n, method) for method in args.methods.split(",") for case, n in cases}
    lost = [r for r in (read_csv(csv_path) if not args.update and csv_path.exists() else [])
            if (r["case"], int(r["lights"]), r["method"]) not in run_now]
    if lost:   # a run of some methods or cases would drop the others' rows (and the chart's curves)
        raise SystemExit(f"{csv_path} holds {len(lost)} rows this run would drop (e.g. {lost[0]['method']} at "
                         f"{int(lost[0]['lights'])} lights): pass --update to keep them, or --out for another CSV")
    for method in args.methods.split(","):
        stopped_at = apply_stopped_at = None
        args.skip_note = "--apply-only: no renders with fog"
        for case, n in cases:
            if apply_stopped_at is not None:
                rows.append({"case": case, "lights": n, "method": method, "engine": METHODS[method][0],
                             "error": error_tag(args.error), "anisotropy": args.anisotropy, "status": "not run",
                             "budget_s": args.budget,
                             "resolution": "{}x{}".format(*args.resolution), "samples": args.samples,
                             "source": args.source,
                             "note": f"adding the fog timed out with {apply_stopped_at} lights already"})
                print(f"{case:10} {n:4d} {method:13} not run (adding the fog timed out at {apply_stopped_at} lights)")
                continue
            if stopped_at is not None:
                args.skip_note = f"not rendered: the method timed out with {stopped_at} lights already"
            apply_only = args.apply_only or stopped_at is not None
            row = measure_case(case, n, method, args, apply_only=apply_only)
            rows.append(row)
            print(f"{case:10} {n:4d} {method:13} {row['status']:10} {row['process_s']:6.1f} s "
                  f"({row['process_cpu_s']:6.1f} s CPU)  warm {fmt(row.get('ratio_warm_cpu'), 'x')} CPU "
                  f"/ {fmt(row.get('ratio_warm'), 'x')} wall  first {fmt(row.get('ratio_first_cpu'), 'x')} CPU "
                  f"/ {fmt(row.get('ratio_first'), 'x')} wall  apply {fmt(row.get('fog_apply_s'), ' s')}  "
                  f"pic {row.get('picture_check', '-')} surf {fmt(row.get('surface_ratio'))}  "
                  f"{row['note'][:160]}  (load {row['load_avg_start']} -> {row['load_avg_end']})", flush=True)
            smoke.check(row["status"] == "ok" and not row["log_errors"], f"{case} {n} {method}: {row['status']}, "
                        f"{row['log_errors']} log errors: {row['note']}")
            if row["status"] == "timeout" and apply_only:
                apply_stopped_at = n
            elif row["status"] == "timeout" and stopped_at is None:
                stopped_at = n
            cross_check(rows)
            csv_rows.write(csv_path, merged(rows, kept), FIELDS, digits=4)
    rows = merged(rows, kept)
    cross_check(rows)
    csv_rows.write(csv_path, rows, FIELDS, digits=4)
    chart(rows, png_path)
    print_table(rows)
    print(f"\nwrote {csv_path}, {png_path} in {time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
