#!/usr/bin/env bash
# Developer build: compiles boxmarch._core in place (addon/boxmarch/_core*.so) so a checkout can be
# tested with PYTHONPATH=addon without installing it; several checkouts can live side by side.
# Assumes scripts/setup.sh has installed the system packages once.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/environments.sh
PYTHON="$(checkout_python)"  # PYTHON, else the test or the demo environment's
cmake -S . -B build/dev -DCMAKE_BUILD_TYPE=Release -DBOXMARCH_BUILD_PYTHON=ON \
  -DPython_EXECUTABLE="$(command -v "$PYTHON")" \
  -Dpybind11_DIR="$("$PYTHON" -c 'import pybind11; print(pybind11.get_cmake_dir())')" >/dev/null
cmake --build build/dev -j2 >/dev/null
cp build/dev/_core*.so addon/boxmarch/
echo "[dev_build] addon/boxmarch/$(basename build/dev/_core*.so)" >&2
