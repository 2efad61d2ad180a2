#!/usr/bin/env bash
# The main job: set up (idempotent), then build, bake and check the 16,000-box world headless.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
exec "${PYTHON:-python3}" -m boxmarch demo "$@"
