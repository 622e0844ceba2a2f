#!/usr/bin/env bash
# Set up if needed, then run every test.  Exit code is pytest's (5 = no tests = failure).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
export TMPDIR="${TMPDIR:-/tmp}"
exec .venv/bin/python -m pytest -q "$@" tests
