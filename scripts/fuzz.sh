#!/usr/bin/env bash
# libFuzzer run of fuzz/fuzz_core (clang, ASan + UBSan) for a bounded time:
#   bash scripts/fuzz.sh [SECONDS] [--keep]      (default 60 s)
# Starts from the kept corpus fuzz/corpus (read only); new interesting inputs go to a scratch
# directory. --keep merges them into fuzz/corpus afterwards (minimised: only inputs that add
# coverage), to commit as regression tests. A crash leaves its input in build/fuzz/artifacts and
# exits nonzero. Assumes scripts/setup.sh ran once (clang-14, libclang-rt-14-dev).
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-60}"
keep="${2:-}"
build=build/fuzz
CXX="${FUZZ_CXX:-clang++-14}" cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DBOXMARCH_FUZZ=ON >/dev/null
cmake --build "$build" -j2 --target fuzz_core >/dev/null
scratch="$(mktemp -d)"
trap 'rm -rf "$scratch"' EXIT
mkdir -p "$build/artifacts"
export ASAN_OPTIONS="abort_on_error=1:detect_leaks=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
"$build/fuzz_core" -max_total_time="$seconds" -max_len=1024 -timeout=10 -rss_limit_mb=2048 \
  -artifact_prefix="$build/artifacts/" -print_final_stats=1 "$scratch" fuzz/corpus >"$scratch.log" 2>&1 || {
  tail -60 "$scratch.log"; rm -f "$scratch.log"; echo "[fuzz] FAILED: input kept in $build/artifacts" >&2; exit 1; }
tail -25 "$scratch.log"
rm -f "$scratch.log"
if [ "$keep" = "--keep" ]; then
  "$build/fuzz_core" -merge=1 fuzz/corpus "$scratch" 2>&1 | tail -2
fi
