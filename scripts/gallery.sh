#!/usr/bin/env bash
# Regenerate the seed paper's figures, the Section IV-B interaction examples and the Section V
# closed-loop table (simulated vs the paper) into a directory: PNG + SVG per figure, index.html.
# Usage: scripts/gallery.sh [OUT_DIR]   (default: ./gallery; same as `thrustshape gallery --out DIR`)
set -euo pipefail
cd "$(dirname "$0")/.."
VENV=${THRUSTSHAPE_VENV:-.venv}
exec "$VENV/bin/python" -m ocp.gallery --out "${1:-gallery}"
