#!/usr/bin/env bash
# Set up if needed, build the "street lamps" demo scene and render it with fog to out/street_lamps_fog.png.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
mkdir -p out
export TMPDIR="${TMPDIR:-/tmp}"
.venv/bin/python demo_scenes/street_lamps.py out/street_lamps.blend
.venv/bin/python -m fog_addon render out/street_lamps.blend --engine cycles --preset fog \
    --samples 16 --resolution 640x360 --out out/street_lamps_fog.png
echo "wrote out/street_lamps_fog.png"
