"""A benchmark's measurement in a fresh Blender process: the script run with ``--worker <spec as JSON>`` prints
one line ``RESULT <json>``; ``run`` returns that dict (or None, printing the process's output tail; in smoke mode,
benchmarks/smoke.py, a worker without a result stops the run and its whole output is shown)."""
import json
import pathlib
import subprocess
import sys
import time

import smoke

ROOT = pathlib.Path(__file__).resolve().parents[1]


def emit(result):
    """Print ``result`` (a dict) as the worker's RESULT line."""
    print("RESULT " + json.dumps(result), flush=True)


def run(script, spec):
    """``script --worker <spec>`` in a fresh process from the repository root: its RESULT dict, or None."""
    proc = subprocess.run([sys.executable, str(script), "--worker", json.dumps(spec)], capture_output=True,
                          text=True, cwd=str(ROOT))
    smoke.echo(proc.stdout, proc.stderr)
    lines = [ln for ln in proc.stdout.splitlines() if ln.startswith("RESULT ")]
    smoke.check(proc.returncode == 0 and lines, f"{pathlib.Path(script).name} worker {spec} failed "
                f"(exit {proc.returncode})")
    if not lines:
        print(proc.stdout[-2000:], proc.stderr[-2000:])
        return None
    return json.loads(lines[-1].split(" ", 1)[1])


def run_code(code, what):
    """``python -c code`` in a fresh process from the repository root (a worker written inline): its RESULT dict,
    or None (``what`` names it in a smoke run's failure)."""
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=str(ROOT))
    smoke.echo(proc.stdout[-3000:] + proc.stderr[-3000:])
    line = next((ln for ln in proc.stdout.splitlines() if ln.startswith("RESULT ")), None)
    smoke.check(proc.returncode == 0 and line is not None, f"{what}: exit {proc.returncode}")
    return json.loads(line.split(" ", 1)[1]) if line else None


def fastest_renders(setup, tags, repeats, out, render=None):
    """{tag: the fastest of ``repeats`` render times, s} of the scenes ``setup(tag)`` builds (not timed), rendered
    by turns (every tag once, then again: a machine's drift touches all alike) to the file ``out(tag)``;
    ``render(tag, scene, path)`` renders one (default: ``measure.render_to_file``).  Runs inside Blender."""
    from fog_addon import measure   # noqa: PLC0415 (Blender's, in the worker)
    render = render or (lambda tag, scene, path: measure.render_to_file(scene, path))
    times = {tag: [] for tag in tags}
    for _ in range(repeats):
        for tag in tags:
            scene = setup(tag)
            t = time.perf_counter()
            render(tag, scene, out(tag))
            times[tag].append(time.perf_counter() - t)
    return {tag: min(v) for tag, v in times.items()}
