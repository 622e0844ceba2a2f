"""The benchmarks' smoke mode: ``FOG_BENCH_SMOKE=1`` runs a benchmark's whole code path at the tiniest size (a few
pixels, 1 sample, 1-2 lights, one repetition), its outputs in a scratch folder, so that it cannot rot unseen
(tests/test_benchmarks_smoke.py runs every benchmark so).

One environment variable, not a flag: a benchmark's worker processes inherit it, and so do the scripts a figure
runs.  A benchmark reads it through this module:

* ``pick(full, tiny)``: a default (size, samples, lights, repeats, cases) for the measurement or the smoke run;
* ``out(path)``: where an output (a CSV, a chart, a figure under docs/, a cache of renders) goes: ``path`` itself,
  or in smoke mode the same path under the smoke folder (``FOG_BENCH_OUT``, else a fresh temporary folder that
  the process's children share), so a smoke run never touches the committed figures or a measurement's CSV;
* ``check(ok, what)``: a failed row or worker, which a measurement records and goes on past, stops a smoke run
  (exit code 1, ``what`` printed);
* ``echo(text)``: a worker's output shown in a smoke run, so the caller sees its Blender log (its errors).
"""
import os
import pathlib
import sys
import tempfile

ENV = "FOG_BENCH_SMOKE"
OUT_ENV = "FOG_BENCH_OUT"
ROOT = pathlib.Path(__file__).resolve().parents[1]
ON = os.environ.get(ENV) == "1"


def pick(full, tiny):
    """``tiny`` in smoke mode, else ``full``."""
    return tiny if ON else full


def folder():
    """The smoke run's output folder (made; shared with child processes through ``FOG_BENCH_OUT``)."""
    if not os.environ.get(OUT_ENV):
        os.environ[OUT_ENV] = tempfile.mkdtemp(prefix="fog_bench_smoke_")
    path = pathlib.Path(os.environ[OUT_ENV])
    path.mkdir(parents=True, exist_ok=True)
    return path


def out(path):
    """``path`` (a file or folder of the repository) as a measurement writes it, or its place in the smoke
    folder (the same path relative to the repository) in smoke mode."""
    path = pathlib.Path(path)
    if not ON:
        return path
    try:
        rel = path.resolve().relative_to(ROOT)
    except ValueError:
        rel = pathlib.Path(path.name)
    return folder() / rel


def check(ok, what):
    """In smoke mode, exit with code 1 printing ``what`` unless ``ok``; a measurement goes on."""
    if ON and not ok:
        print(f"smoke: {what}", file=sys.stderr, flush=True)
        raise SystemExit(1)


def echo(*texts):
    """In smoke mode, print a worker's output (stdout, stderr) on this process's, for the caller's log check."""
    if ON:
        for text in texts:
            if text:
                print(text if isinstance(text, str) else text.decode(errors="replace"), flush=True)
