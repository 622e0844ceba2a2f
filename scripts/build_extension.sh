#!/usr/bin/env bash
# Validate the extension and build the installable zip into out/ with Blender's own tool.
# The repository root is the extension's source directory (blender_manifest.toml and an
# __init__.py that hands on fog_addon's register/unregister); the manifest's [build] paths
# allow-list keeps tests, demo scenes, tools, docs, .venv, out/ ... out of the zip.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
TOOL=$(.venv/bin/python -c "import importlib.util, pathlib; print(next(pathlib.Path(importlib.util.find_spec('bpy').origin).parent.glob('*/scripts/addons_core/bl_pkg/cli/blender_ext.py')))")
mkdir -p out
.venv/bin/python "$TOOL" validate .
.venv/bin/python "$TOOL" build --source-dir . --output-dir out
