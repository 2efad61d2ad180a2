#!/usr/bin/env bash
# The main job: set up (idempotent), then build, bake, export and check the 16,000-box world
# headless, then render its .glb in three.js (Debian's r111 in headless Chromium).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
"${PYTHON:-python3}" -m boxmarch demo "$@"
exec "${PYTHON:-python3}" -m scripts.threejs_picture "$@"
