# shellcheck shell=bash disable=SC2034  # the names are read by the scripts that source this file
# Where boxmarch's commands keep their Python packages and downloads (sourced by the scripts; bash).
# Nothing goes into the machine's Python: each command has its own virtual environment inside the
# checkout, made from the machine's python3 with none of its site-packages,
#   .venv-demo  scripts/demo.sh: bpy 5.0 and the build backend (BOXMARCH_DEMO_VENV)
#   .venv-test  scripts/setup.sh, for scripts/test.sh: those and the test and lint tools (BOXMARCH_TEST_VENV)
# and boxmarch is built into each from its own build folder (build/venv-demo, build/venv-test), so
# neither rebuilds the other's. Other releases of the bpy module (scripts/install_bpy.sh) go into
# .cache/bpy-MAJOR.MINOR (BOXMARCH_CACHE).
REPO_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
DEMO_VENV="${BOXMARCH_DEMO_VENV:-$REPO_ROOT/.venv-demo}"
TEST_VENV="${BOXMARCH_TEST_VENV:-$REPO_ROOT/.venv-test}"
BOXMARCH_CACHE="${BOXMARCH_CACHE:-$REPO_ROOT/.cache}"

# use_compiler_cache: every CMake build of the scripts (and of the tests they run) compiles through
# ccache where it is installed (scripts/setup.sh installs it), its cache in BOXMARCH_CACHE/ccache
# like every other cache (set here, since the tests give their subprocesses an XDG_CACHE_HOME of
# their own): a clean clone's set-up build fills it and the tests' builds of the same sources and
# flags reuse it. CCACHE_BASEDIR hashes the paths under the checkout relative to it and
# CCACHE_NOHASHDIR leaves the build folder out of -g builds' hashes, so clones that share one
# BOXMARCH_CACHE share their compiles too. CMake reads CMAKE_CXX_COMPILER_LAUNCHER from the
# environment. A failed compile is never cached; a compile's warnings are replayed with its hit.
use_compiler_cache() {
  if command -v ccache >/dev/null 2>&1; then
    export CMAKE_CXX_COMPILER_LAUNCHER="${CMAKE_CXX_COMPILER_LAUNCHER:-ccache}"
    export CCACHE_DIR="${CCACHE_DIR:-$BOXMARCH_CACHE/ccache}"
    export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$REPO_ROOT}" CCACHE_NOHASHDIR="${CCACHE_NOHASHDIR:-true}"
  fi
}
use_compiler_cache

# checkout_python: the Python a script of the checkout runs with: $PYTHON when set, else the test
# environment's, else the demo's (so the scripts work after either README command), else python3.
checkout_python() {
  local venv
  if [ -n "${PYTHON:-}" ]; then
    echo "$PYTHON"
    return
  fi
  for venv in "$TEST_VENV" "$DEMO_VENV"; do
    if [ -x "$venv/bin/python" ]; then
      echo "$venv/bin/python"
      return
    fi
  done
  echo python3
}

# venv_build_dir VENV: scikit-build-core's build folder for building boxmarch into VENV
# (build/venv-demo for .venv-demo): one CMake cache per environment's Python.
venv_build_dir() {
  local name="${1##*/}"
  echo "build/${name#.}"
}

# venv_apt_packages BASE_PYTHON: python3-venv when BASE_PYTHON cannot make a virtual environment
# (Debian's Python ships venv apart), else nothing.
venv_apt_packages() {
  "$1" -c "import ensurepip" 2>/dev/null || echo python3-venv
}
