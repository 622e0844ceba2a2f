#!/usr/bin/env bash
# Idempotent set-up: a virtual environment in .venv with bpy 5.0.1 (Blender as a
# Python module) and the test tools.  Re-running is cheap.
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PYTHON:-python3.11}
command -v "$PY" >/dev/null || PY=python3
if [ ! -x .venv/bin/python ]; then
  "$PY" -m venv .venv
fi
if ! .venv/bin/python -c "import bpy, numpy, scipy, pytest, matplotlib, xdist" 2>/dev/null; then
  .venv/bin/python -m pip install --quiet --upgrade pip
  .venv/bin/python -m pip install --quiet -r requirements-dev.txt
fi
