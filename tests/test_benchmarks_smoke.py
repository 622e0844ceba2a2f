"""Every benchmark runs: each ``benchmarks/*.py`` in its smoke mode (``FOG_BENCH_SMOKE=1``, benchmarks/smoke.py: the
whole code path at the tiniest size, outputs in a scratch folder) in a fresh process, which must exit 0 with no
Blender log errors (``render_harness.log_errors``: shaders too big, shader compile errors, dependency cycles; the
benchmarks show their workers' output in smoke mode) and leave a measurement's outputs (benchmarks/out, docs/figures,
docs/measurements) untouched.

The scripts are found by glob, so a new benchmark is run without being listed here; ``NOT_BENCHMARKS`` names the
modules of benchmarks/ that are not scripts to run, each with its reason, and ``NO_SMOKE_MODE_YET`` the benchmarks
expected to fail until they have a smoke mode (a strict xfail: one that passes must leave the list).
The benchmarks/compositor_fog/ pipeline, whose scripts take arguments, has a test of its own.
"""
import time

import pytest

from fog_scenes import render_harness as h

pytestmark = [pytest.mark.render, pytest.mark.slow]

BENCHMARKS = h.ROOT / "benchmarks"
NOT_BENCHMARKS = {
    "csv_rows.py": "helper module: the benchmarks' CSV writer and reader",
    "worker_result.py": "helper module: a worker process's RESULT line",
    "cost_cli.py": "helper module: the cost benchmarks' shared command line",
    "cycles_timing.py": "helper module: Cycles CPU set-up and timed renders, imported by the workers",
    "smoke.py": "helper module: the smoke mode itself",
}
# Benchmarks without a smoke mode yet: expected to fail (strict: one that passes must leave this list).
NO_SMOKE_MODE_YET = {}
TIMEOUT_S = 300   # one benchmark's smoke run; they take seconds to about half a minute
# where a measurement writes; a smoke run writes into its own folder (``FOG_BENCH_OUT``) only
MEASUREMENT_OUTPUTS = [h.ROOT / "benchmarks" / "out", h.ROOT / "docs" / "figures", h.ROOT / "docs" / "measurements"]


def scripts():
    return [pytest.param(name, marks=pytest.mark.xfail(strict=True, reason=NO_SMOKE_MODE_YET[name]))
            if name in NO_SMOKE_MODE_YET else name
            for name in sorted(p.name for p in BENCHMARKS.glob("*.py") if p.name not in NOT_BENCHMARKS)]


def outputs():
    """{path: modification time} of the files where a measurement writes."""
    return {p: p.stat().st_mtime_ns for d in MEASUREMENT_OUTPUTS if d.is_dir() for p in d.rglob("*") if p.is_file()}


def test_skip_list_names_existing_files():
    """A stale entry would hide nothing, but a renamed helper would then run as a benchmark: keep the list true."""
    missing = [name for name in {**NOT_BENCHMARKS, **NO_SMOKE_MODE_YET} if not (BENCHMARKS / name).is_file()]
    assert not missing, f"NOT_BENCHMARKS or NO_SMOKE_MODE_YET names files that are gone: {missing}"


@pytest.mark.parametrize("script", scripts())
def test_benchmark_smoke(script, tmp_path, monkeypatch):
    monkeypatch.setenv("FOG_BENCH_SMOKE", "1")
    monkeypatch.setenv("FOG_BENCH_OUT", str(tmp_path / "out"))
    before = outputs()
    t = time.perf_counter()
    proc = h.run([BENCHMARKS / script], timeout=TIMEOUT_S, check=False)
    seconds = time.perf_counter() - t
    log = proc.stdout + "\n" + proc.stderr
    assert proc.returncode == 0, (f"{script} failed in smoke mode (exit {proc.returncode}, {seconds:.0f} s):\n"
                                  f"--- stdout ---\n{proc.stdout[-4000:]}\n--- stderr ---\n{proc.stderr[-4000:]}")
    errors = h.log_errors(log)
    assert not errors, f"{script}: Blender log errors in smoke mode: {errors[:5]}"
    after = outputs()
    touched = sorted(str(p.relative_to(h.ROOT)) for p in after if before.get(p) != after[p])
    assert not touched, f"{script} wrote a measurement's outputs in smoke mode: {touched[:5]}"
    written = [p for p in (tmp_path / "out").rglob("*") if p.is_file()]
    print(f"{script}: {seconds:.1f} s, {len(written)} files written")


def test_compositor_fog_pipeline_smoke(tmp_path, monkeypatch):
    """benchmarks/compositor_fog/, a pipeline whose scripts take arguments (so not in the glob): ``build.py`` renders
    one light's scene, ``compare.py`` and ``peaks.py`` read its EXR; each must exit 0 with no Blender log errors."""
    monkeypatch.setenv("FOG_BENCH_SMOKE", "1")
    monkeypatch.setenv("FOG_BENCH_OUT", str(tmp_path / "out"))
    exr = tmp_path / "exact.exr"
    folder = BENCHMARKS / "compositor_fog"
    for args in ([folder / "build.py", 1, exr], [folder / "compare.py", exr], [folder / "peaks.py", 1, exr]):
        proc = h.run(args, timeout=TIMEOUT_S, check=False)
        assert proc.returncode == 0, (f"{args[0].name} failed in smoke mode (exit {proc.returncode}):\n"
                                      f"{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}")
        errors = h.log_errors(proc.stdout + "\n" + proc.stderr)
        assert not errors, f"{args[0].name}: Blender log errors in smoke mode: {errors[:5]}"
