#!/usr/bin/env bash
# The test command: set up (idempotent, scripts/setup.sh), then run every test tier, each announced
# and timed: the everyday tier, the slow tier (engines, Blender 3.4 program runs, renders, CLI and
# install runs) beside the quick Blender-facing selection under bpy 4.2 LTS
# (scripts/blender_matrix.py), then the native tier (sanitizers; fuzzer and cross compile) in two
# halves side by side, all with the test environment's Python (.venv-test, scripts/environments.sh).
# The everyday and slow tiers run on WORKERS processes
# (pytest-xdist; BOXMARCH_TEST_WORKERS, default the machine's cores), each test file on one worker
# (--dist loadfile: the Blender or Chromium run a module's fixture makes for its tests runs once);
# the slow tier names each test as it finishes (-v) and lists its slowest at the end. Arguments
# select tests for one pytest run instead.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
source scripts/environments.sh
PYTHON="$TEST_VENV/bin/python"
if [ $# -gt 0 ]; then
  exec "$PYTHON" -m pytest -q "$@"
fi
status=0
started=$SECONDS
run_tier() {  # NAME COMMAND...: one tier, then its result and time; fails when the tier failed
  local name="$1" start=$SECONDS result=passed
  shift
  echo "[test] $name" >&2
  "$@" || result=FAILED
  echo "[test] $name: $result in $((SECONDS - start)) s" >&2
  [ "$result" = passed ]
}
WORKERS="${BOXMARCH_TEST_WORKERS:-$(nproc)}"
parallel=(-n "$WORKERS" --dist loadfile)
run_tier "everyday tier (-m 'not slow')" "$PYTHON" -m pytest "${parallel[@]}" -m "not slow" || status=1
logs="$(mktemp -d)"
trap 'rm -rf "$logs"' EXIT
# The bpy 4.2 selection (one Blender process at a time) beside the slow tier, into its own log,
# shown at the end.
run_tier "bpy 4.2 LTS selection" "$PYTHON" scripts/blender_matrix.py --quick 4.2 >"$logs/bpy" 2>&1 &
bpy=$!
run_tier "slow tier (-m 'slow and not native')" "$PYTHON" -m pytest "${parallel[@]}" -v --durations=25 \
  -m "slow and not native" || status=1
# The native tier in two halves side by side, each about 300 s of CPU: the sanitizer checks (their
# build, then the C++ tests and the Python suites on it) and the rest (the fuzzer's minute of one
# core, the cross compile), each into its own log.
run_tier "native tier: sanitizer checks" "$PYTHON" -m pytest -m native tests/test_native_checks.py \
  >"$logs/sanitizers" 2>&1 &
sanitizers=$!
run_tier "native tier: the rest (-m native)" "$PYTHON" -m pytest -m native --ignore=tests/test_native_checks.py \
  >"$logs/native" 2>&1 &
native=$!
wait "$sanitizers" || status=1
wait "$native" || status=1
wait "$bpy" || status=1
cat "$logs/sanitizers" "$logs/native" "$logs/bpy" >&2
echo "[test] every tier $([ "$status" -eq 0 ] && echo passed || echo FAILED) in $((SECONDS - started)) s" >&2
exit "$status"
