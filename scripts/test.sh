#!/usr/bin/env bash
# The test command: set up (idempotent), then run every test (Blender 5.0 as the bpy module, Debian's
# Blender 3.4 program), then the quick Blender-facing selection under bpy 4.2 LTS
# (scripts/blender_matrix.py). Arguments select tests for the first run and skip the second.
set -euo pipefail
cd "$(dirname "$0")/.."
PYTHON="${PYTHON:-python3}"
bash scripts/setup.sh
if [ $# -gt 0 ]; then
  exec "$PYTHON" -m pytest -q "$@"
fi
status=0
"$PYTHON" -m pytest -q || status=$?
"$PYTHON" scripts/blender_matrix.py --quick 4.2 || status=$?
exit "$status"
