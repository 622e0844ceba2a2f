#!/usr/bin/env bash
# Validate fog_addon/ and build the installable extension zip into out/ with Blender's own tool.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
TOOL=$(.venv/bin/python -c "import importlib.util, pathlib; print(next(pathlib.Path(importlib.util.find_spec('bpy').origin).parent.glob('*/scripts/addons_core/bl_pkg/cli/blender_ext.py')))")
mkdir -p out
.venv/bin/python "$TOOL" validate fog_addon
.venv/bin/python "$TOOL" build --source-dir fog_addon --output-dir out
