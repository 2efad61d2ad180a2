#!/usr/bin/env bash
# libFuzzer run of fuzz/fuzz_core (clang, ASan + UBSan) for a bounded time:
#   bash scripts/fuzz.sh [SECONDS]      (default 60 s)
# Starts from the seed corpus in git, fuzz/corpus (read only, a few dozen inputs), and the corpus
# grown by earlier runs on this machine, build/fuzz/corpus (not in git), where new interesting
# inputs go. A crash leaves its input in build/fuzz/artifacts and exits nonzero; copy that input
# into fuzz/corpus to keep it as a regression test (ctest replays fuzz/corpus). Assumes
# scripts/setup.sh ran once (clang-14, libclang-rt-14-dev).
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-60}"
build=build/fuzz
CXX="${FUZZ_CXX:-clang++-14}" cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DBOXMARCH_FUZZ=ON >/dev/null
cmake --build "$build" -j2 --target fuzz_core >/dev/null
grown="$build/corpus"
log="$(mktemp)"
trap 'rm -f "$log"' EXIT
mkdir -p "$build/artifacts" "$grown"
export ASAN_OPTIONS="abort_on_error=1:detect_leaks=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
"$build/fuzz_core" -max_total_time="$seconds" -max_len=1024 -timeout=10 -rss_limit_mb=2048 \
  -artifact_prefix="$build/artifacts/" -print_final_stats=1 "$grown" fuzz/corpus >"$log" 2>&1 || {
  tail -60 "$log"; echo "[fuzz] FAILED: input kept in $build/artifacts" >&2; exit 1; }
tail -25 "$log"
