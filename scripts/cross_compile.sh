#!/usr/bin/env bash
# Compile-and-link check of the native code for Windows x64 and macOS arm64 from this Linux machine,
# with zig's clang (PyPI `ziglang`). Nothing built here is run; the wheels for those platforms are
# built and tested by .github/workflows/wheels.yml on their own runners.
#   bash scripts/cross_compile.sh [--compile-only] [OUT]   (default OUT build/cross)
# Per target, with -Wall -Wextra -Wpedantic -Werror (a warning fails the check):
#   - every cpp/src/*.cpp compiled to an object file and archived into libboxmarch_core.a;
#   - macOS arm64 only: the bindings (bindings/*.cpp) compiled against this machine's Python 3.11
#     and pybind11 headers. The Windows bindings are not compiled here: this machine's pyconfig.h
#     describes Linux (it includes <sys/select.h>, which Windows lacks); the Windows wheel job
#     compiles them with MSVC;
#   - unless --compile-only: the C++ tests (tests/cpp/test_core.cpp) linked with the library into
#     an executable (test_core.exe, PE32+; test_core, Mach-O): the core links without Python,
#     threads and the C++ runtime included; on macOS arm64 the bindings and the core linked into
#     the extension module _core.cpython-311-darwin.so (-undefined dynamic_lookup, as macOS
#     extension modules link). The first link per target builds zig's libc++ for it (minutes on
#     2 cores; cached in .cache/zig of the checkout afterwards, scripts/environments.sh).
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/environments.sh
PYTHON="$(checkout_python)"  # PYTHON, else the test or the demo environment's
LINK=1
if [ "${1:-}" = "--compile-only" ]; then
  LINK=0
  shift
fi
OUT="${1:-build/cross}"
# zig's caches in the checkout's cache folder, not in the home folder.
export ZIG_GLOBAL_CACHE_DIR="$BOXMARCH_CACHE/zig" ZIG_LOCAL_CACHE_DIR="$BOXMARCH_CACHE/zig"
ZIG=("$PYTHON" -m ziglang)
"${ZIG[@]}" version >/dev/null 2>&1 || { echo "cross_compile: zig is missing (pip install ziglang)" >&2; exit 1; }
PY_INCLUDE="$("$PYTHON" -c 'import sysconfig; print(sysconfig.get_paths()["include"])')"
PYBIND11_INCLUDE="$("$PYTHON" -c 'import pybind11; print(pybind11.get_include())')"
# Only the two header libraries from the system include folder: the rest of it is Linux's libc.
HEADERS="$OUT/headers"
mkdir -p "$HEADERS"
GLM="$(dirname "$(find /usr/include /usr/local/include -maxdepth 3 -path '*/glm/glm.hpp' -print -quit)")"
NANOFLANN="$(find /usr/include /usr/local/include -maxdepth 2 -name nanoflann.hpp -print -quit)"
if [ ! -d "$GLM" ] || [ ! -f "$NANOFLANN" ]; then
  echo "cross_compile: GLM or nanoflann headers missing (scripts/setup.sh)" >&2
  exit 1
fi
ln -sfn "$GLM" "$HEADERS/glm"
ln -sfn "$NANOFLANN" "$HEADERS/nanoflann.hpp"

CXXFLAGS=(-std=c++17 -O0 -Wall -Wextra -Wpedantic -Werror -DGLM_FORCE_XYZW_ONLY -D_USE_MATH_DEFINES
          -Icpp/include -Icpp/src -isystem "$HEADERS")

compile() {  # TARGET SOURCE: one source into OUT/TARGET/NAME.o (a binding source with the Python headers)
  local target="$1" source="$2" extra=()
  case "$source" in
    bindings/*) extra=(-isystem "$PY_INCLUDE" -isystem "$PYBIND11_INCLUDE" -fvisibility=hidden) ;;
  esac
  "${ZIG[@]}" c++ -target "$target" "${CXXFLAGS[@]}" "${extra[@]}" -c "$source" \
    -o "$OUT/$target/$(basename "$source" .cpp).o"
}

# Every compile, one per core at a time from one queue (the two targets' lists differ in length:
# macOS compiles the bindings too), the bindings (pybind11, the longest) first so none is left to
# run alone at the end. A failed compile prints its errors and marks the run failed.
TARGETS=(x86_64-windows-gnu aarch64-macos)
jobs_list=()
for source in bindings/*.cpp; do jobs_list+=("aarch64-macos $source"); done
for target in "${TARGETS[@]}"; do
  mkdir -p "$OUT/$target"
  rm -f "$OUT/$target"/*.o "$OUT/$target/libboxmarch_core.a"
  for source in cpp/src/*.cpp; do jobs_list+=("$target $source"); done
  [ "$LINK" = 1 ] && jobs_list+=("$target tests/cpp/test_core.cpp")
done
failed="$OUT/compile_failed"
rm -f "$failed"
start=$SECONDS
for job in "${jobs_list[@]}"; do
  while [ "$(jobs -rp | wc -l)" -ge "$(nproc)" ]; do wait -n || true; done
  # shellcheck disable=SC2086  # TARGET SOURCE, two words
  (compile $job || { echo "[cross_compile] FAILED: $job" >&2; touch "$failed"; }) &
done
wait
[ ! -e "$failed" ] || exit 1
echo "[cross_compile] ${#jobs_list[@]} sources compiled for ${TARGETS[*]} in $((SECONDS - start)) s" >&2

link_target() {  # TARGET: the core archive, and unless --compile-only the links
  local target="$1" dir="$OUT/$1" exe
  local objects=("$dir"/*.o) core=() bindings=()
  for object in "${objects[@]}"; do
    case "$(basename "$object" .o)" in
      test_core) ;;
      *) if [ -e "bindings/$(basename "$object" .o).cpp" ]; then bindings+=("$object"); else core+=("$object"); fi ;;
    esac
  done
  "${ZIG[@]}" ar rcs "$dir/libboxmarch_core.a" "${core[@]}"
  echo "[cross_compile] $target: ${#core[@]} core sources and ${#bindings[@]} binding sources compiled, $dir/libboxmarch_core.a" >&2
  if [ "$LINK" = 1 ]; then
    exe="$dir/test_core"
    [ "$target" = x86_64-windows-gnu ] && exe="$dir/test_core.exe"
    "${ZIG[@]}" c++ -target "$target" "$dir/test_core.o" "$dir/libboxmarch_core.a" -o "$exe"
    echo "[cross_compile] $target: linked $exe (not run)" >&2
    if [ "$target" = aarch64-macos ]; then
      "${ZIG[@]}" c++ -target "$target" -shared -Wl,-undefined,dynamic_lookup "${bindings[@]}" \
        "$dir/libboxmarch_core.a" -o "$dir/_core.cpython-311-darwin.so"
      echo "[cross_compile] $target: linked $dir/_core.cpython-311-darwin.so (not run)" >&2
    fi
  fi
}

# The two targets' links side by side (the first link per target builds zig's libc++ for it).
pids=()
for target in "${TARGETS[@]}"; do
  link_target "$target" &
  pids+=($!)
done
status=0
for pid in "${pids[@]}"; do
  wait "$pid" || status=1
done
exit "$status"
