#!/usr/bin/env bash
# Installs one release of the bpy module (PyPI, Python 3.11) into its own folder, never into this
# Python's site-packages, and prints the folder: the tests run it with BOXMARCH_BPY_PATH=FOLDER.
#   bash scripts/install_bpy.sh 4.2      -> $BOXMARCH_CACHE/bpy-4.2 (newest 4.2.x)
# A folder already complete is reused (a second run takes well under a second). --no-deps: bpy's
# dependencies (numpy, requests, zstandard, cython) come from this Python, where setup.sh put them
# with the default bpy, so one NumPy serves every release.
set -euo pipefail
VERSION="${1:?usage: install_bpy.sh MAJOR.MINOR}"
PYTHON="${PYTHON:-python3}"
CACHE="${BOXMARCH_CACHE:-/var/cache/boxmarch}"
mkdir -p "$CACHE" 2>/dev/null && [ -w "$CACHE" ] || CACHE="$HOME/.cache/boxmarch"
FOLDER="$CACHE/bpy-$VERSION"
if [ ! -f "$FOLDER/.complete" ]; then
  echo "[install_bpy] pip install --target $FOLDER bpy==$VERSION.*" >&2
  rm -rf "$FOLDER"
  mkdir -p "$CACHE"
  "$PYTHON" -m pip install -q --disable-pip-version-check --root-user-action=ignore --no-deps --target "$FOLDER" "bpy==$VERSION.*" >&2
  touch "$FOLDER/.complete"  # written last: an interrupted install is redone, never trusted
fi
echo "$FOLDER"
