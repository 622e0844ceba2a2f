#!/usr/bin/env bash
# Set up if needed, then run the tests (docs/testing.md):
#   bash scripts/test.sh             the default tier, -m "not slow": every contract once (what .ci/run runs)
#   bash scripts/test.sh --all       everything: the slow tier and the whole mutation check too
#   bash scripts/test.sh --numpy     the numpy tier: no Blender (-m "not render and not slow and not mutation"),
#                                    under 2 minutes; a test there that starts Blender fails (mark it render)
#   bash scripts/test.sh ARGS...     ARGS go to pytest as well (e.g. -k NAME, -x; a -m of yours replaces
#                                    the tier's, e.g. -m mutation)
# The exit code is pytest's, and any non-zero code fails: 5 means no test was collected or selected (a
# marker expression that selects nothing, a wrong -k) and is an error, never a pass.  tests/conftest.py
# also refuses a -m expression that names an unregistered marker (tests/pytest.ini lists them).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
export TMPDIR="${TMPDIR:-/tmp}"
# One BLAS thread a process: the two workers (and the Blender processes they start) already fill the two cores, and
# OpenBLAS's second thread only spins waiting for one (measured: the numpy-heavy files 12 % faster, a third less
# system time; docs/measurements/2026-11-30-test-time.md).
export OPENBLAS_NUM_THREADS="${OPENBLAS_NUM_THREADS:-1}"
tier=(-m "not slow")
args=()
for a in "$@"; do
  if [[ "$a" == "--all" ]]; then tier=()
  elif [[ "$a" == "--numpy" ]]; then tier=(-m "not render and not slow and not mutation"); export FOG_NUMPY_TIER=1
  else args+=("$a"); fi
done
# Two workers (the machine's 2 cores: most tests wait on a Blender process's start and Python, which one core
# cannot overlap), each test file on one worker (its module-scoped scenes are built once).  FOG_TEST_WORKERS=0
# runs in this process (pytest's -x and --pdb want that).
workers=(-n "${FOG_TEST_WORKERS:-2}" --dist loadfile)
if [[ "${FOG_TEST_WORKERS:-2}" == "0" ]]; then workers=(); fi
exec .venv/bin/python -m pytest -q ${workers[@]+"${workers[@]}"} ${tier[@]+"${tier[@]}"} ${args[@]+"${args[@]}"} tests
