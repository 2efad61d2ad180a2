# shellcheck shell=bash disable=SC2034  # the lists are read by the scripts that source this file
# The packages of boxmarch's two jobs (sourced by scripts/demo.sh and scripts/setup.sh; bash).
# The demo's lists hold only what `python3 -m boxmarch demo` and scripts/threejs_picture.py need;
# scripts/setup.sh (the test command's set-up) installs them and the test and lint tools.
# tests/test_packages.py checks that the demo's lists stay a strict subset of setup.sh's.

# Debian packages of the demo: a compiler, CMake and two header libraries to build the native
# module; the X11/GL client libraries the bpy module loads and Mesa's EGL for the GPU preview
# picture; Chromium and Debian's three.js r111 for the three.js picture.
DEMO_APT_PACKAGES=(g++ cmake libglm-dev libnanoflann-dev
                   libxi6 libxxf86vm1 libxfixes3 libxrender1 libgl1 libxkbcommon0 libsm6
                   libgl1-mesa-dri libegl1 libegl-mesa0
                   chromium libjs-three)
# Python packages of the demo: Blender 5.0 as a module and the build backend of the native module
# (BUILD_PIP_PACKAGES, pyproject.toml's build-system requires; NumPy comes with bpy).
BUILD_PIP_PACKAGES=("scikit-build-core>=0.10" "pybind11>=2.12")
DEMO_PIP_PACKAGES=("bpy==5.0.*" "${BUILD_PIP_PACKAGES[@]}")

# apt_install_missing PACKAGE...: installs those not installed yet (through sudo when not root);
# nothing runs when all are there.
apt_install_missing() {
  local missing=() pkg
  for pkg in "$@"; do
    dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed" || missing+=("$pkg")
  done
  [ ${#missing[@]} -gt 0 ] || return 0
  echo "[setup] apt-get install ${missing[*]}" >&2
  local sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq "${missing[@]}" >/dev/null
}
