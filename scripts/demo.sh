#!/usr/bin/env bash
# The demo: installs only what it needs, then builds, bakes, exports and checks the 16,000-box world
# headless (python3 -m boxmarch demo) and renders its .glb in three.js (Debian's r111 in headless
# Chromium). Debian packages through apt-get (root: sudo when not root; scripts/packages.sh lists
# them); Python packages into a virtual environment, .venv-demo (scripts/environments.sh), never
# into the system's Python. Safe to run again: a second run installs nothing. Arguments go to the
# demo (.venv-demo/bin/python -m boxmarch demo --help).
set -euo pipefail
cd "$(dirname "$0")/.."
PYTHON="${PYTHON:-python3}"  # the Python the environment is made from
source scripts/packages.sh
source scripts/environments.sh
VENV="$DEMO_VENV"
started=$SECONDS

# shellcheck disable=SC2046  # one word or none
apt_install_missing "${DEMO_APT_PACKAGES[@]}" $(venv_apt_packages "$PYTHON")
[ -x "$VENV/bin/python" ] || "$PYTHON" -m venv "$VENV"
DEMO_PYTHON="$VENV/bin/python"
pip_quiet=(-q --disable-pip-version-check)
if ! "$DEMO_PYTHON" -c "import bpy, scikit_build_core, pybind11" 2>/dev/null; then
  echo "[demo] pip install ${DEMO_PIP_PACKAGES[*]} into $VENV" >&2
  "$DEMO_PYTHON" -m pip install "${pip_quiet[@]}" "${DEMO_PIP_PACKAGES[@]}"
fi
echo "[demo] building boxmarch into $VENV" >&2
"$DEMO_PYTHON" -m pip install "${pip_quiet[@]}" --no-build-isolation -C build-dir="$(venv_build_dir "$VENV")" .
echo "[demo] set up in $((SECONDS - started)) s" >&2

"$DEMO_PYTHON" -m boxmarch demo "$@"
"$DEMO_PYTHON" -m scripts.threejs_picture "$@"
echo "[demo] done in $((SECONDS - started)) s (set-up included)" >&2
