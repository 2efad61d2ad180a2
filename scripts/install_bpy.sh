#!/usr/bin/env bash
# Installs one release of the bpy module (PyPI, Python 3.11) into its own folder, never into a
# Python's site-packages, and prints the folder: the tests run it with BOXMARCH_BPY_PATH=FOLDER.
#   bash scripts/install_bpy.sh 4.2      -> .cache/bpy-4.2 in the checkout (newest 4.2.x; BOXMARCH_CACHE
#                                           names another folder for .cache)
# A folder already complete is reused (a second run takes well under a second). --no-deps: bpy's
# dependencies (numpy, requests, zstandard, cython) come from the Python that runs the tests (PYTHON,
# else the test environment's: scripts/environments.sh), where setup.sh put them with the default
# bpy, so one NumPy serves every release.
set -euo pipefail
VERSION="${1:?usage: install_bpy.sh MAJOR.MINOR}"
source "$(dirname "$0")/environments.sh"
PYTHON="$(checkout_python)"
FOLDER="$BOXMARCH_CACHE/bpy-$VERSION"
if [ ! -f "$FOLDER/.complete" ]; then
  echo "[install_bpy] pip install --target $FOLDER bpy==$VERSION.*" >&2
  rm -rf "$FOLDER"
  mkdir -p "$BOXMARCH_CACHE"
  "$PYTHON" -m pip install -q --disable-pip-version-check --root-user-action=ignore --no-deps --target "$FOLDER" "bpy==$VERSION.*" >&2
  touch "$FOLDER/.complete"  # written last: an interrupted install is redone, never trusted
fi
echo "$FOLDER"
