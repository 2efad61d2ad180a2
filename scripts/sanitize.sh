#!/usr/bin/env bash
# AddressSanitizer + UndefinedBehaviorSanitizer build of the core, its Python module and its C++
# tests (build/sanitize), then the checks under it:
#   bash scripts/sanitize.sh [build|cpp|python|all]     (default: all)
# cpp: ctest (C++ tests and the fuzz corpus replay). python: the native Python test suite
# (tests/test_core.py, test_core_properties.py, test_raymarch_core.py, test_tools_core.py,
# test_nearest_rows.py, test_hostile_core3.py) importing the
# sanitized module, with the ASan runtime preloaded into Python (leak detection off: CPython
# keeps its objects to the end).
# Any sanitizer report aborts with a nonzero exit. Assumes scripts/setup.sh ran once.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/environments.sh
PYTHON="$(checkout_python)"  # PYTHON, else the test or the demo environment's
stage="${1:-all}"
build=build/sanitize
export ASAN_OPTIONS="detect_leaks=0:abort_on_error=1:strict_string_checks=1:detect_stack_use_after_return=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
SANITIZE_FLAGS="-O1 -g1 -DNDEBUG"

configure_and_build() {
  # -O1 with line tables (ASan's own advice): the checks and the reports' file:line stay, and the
  # build takes 104 s instead of -O2 -g's 270 s on 2 cores (pybind11's bindings most of it), the
  # checks' run no slower (ctest 22 s, the Python suites 26 s).
  cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="$SANITIZE_FLAGS" \
    -DBOXMARCH_SANITIZE=ON -DBOXMARCH_TESTS=ON \
    -DBOXMARCH_BUILD_PYTHON=ON -DPython_EXECUTABLE="$(command -v "$PYTHON")" \
    -Dpybind11_DIR="$("$PYTHON" -c 'import pybind11; print(pybind11.get_cmake_dir())')" >/dev/null
  cmake --build "$build" -j2 >/dev/null
  # A package folder beside the build: the add-on's Python files (linked) and the sanitized module.
  local pkg="$build/pkg/boxmarch"
  rm -rf "$build/pkg"
  mkdir -p "$pkg/operators" "$pkg/formats"
  for f in addon/boxmarch/*.py; do ln -s "$PWD/$f" "$pkg/"; done
  for f in addon/boxmarch/operators/*.py; do ln -s "$PWD/$f" "$pkg/operators/"; done
  for f in addon/boxmarch/formats/*; do ln -s "$PWD/$f" "$pkg/formats/"; done
  cp "$build"/_core*.so "$pkg/"
}

run_cpp() {
  (cd "$build" && ctest --output-on-failure -V)
}

run_python() {
  # The ASan runtime must come first; libstdc++ too, or ASan cannot intercept C++ throws in a
  # process (Python) that loaded no C++ library at start-up.
  local runtime stdcxx
  runtime="$(${CXX:-g++} -print-file-name=libasan.so)"
  stdcxx="$(${CXX:-g++} -print-file-name=libstdc++.so)"
  [ -f "$runtime" ] && [ -f "$stdcxx" ] || { echo "[sanitize] ASan runtime or libstdc++ not found" >&2; exit 1; }
  LD_PRELOAD="$runtime $stdcxx" PYTHONPATH="$build/pkg" "$PYTHON" -c "import boxmarch._core as c, sys; sys.exit(0 if '/$build/pkg/' in c.__file__ else 'not the sanitized module: ' + c.__file__)"
  local suites=(tests/test_core.py tests/test_core_properties.py)
  [ -f tests/test_raymarch_core.py ] && suites+=(tests/test_raymarch_core.py)  # the CPU raymarcher (issue 4)
  [ -f tests/test_tools_core.py ] && suites+=(tests/test_tools_core.py)  # the submesh tools (issue 3)
  # The hierarchy's nearest-point searches and the index checks of every id argument.
  [ -f tests/test_nearest_rows.py ] && suites+=(tests/test_nearest_rows.py tests/test_hostile_core3.py)
  LD_PRELOAD="$runtime $stdcxx" PYTHONPATH="$build/pkg" "$PYTHON" -m pytest -q -p no:cacheprovider \
    "${suites[@]}" "${@}"
}

case "$stage" in
  build) configure_and_build ;;
  cpp) configure_and_build; run_cpp ;;
  python) configure_and_build; shift || true; run_python "$@" ;;
  all) configure_and_build; run_cpp; run_python ;;
  *) echo "usage: $0 [build|cpp|python|all]" >&2; exit 2 ;;
esac
