#!/usr/bin/env bash
# The default test suite under AddressSanitizer + UndefinedBehaviorSanitizer (+ LeakSanitizer):
# builds freqlab instrumented in build-sanitize/ and runs `ctest -LE slow` there: unit, table and
# integration (CLI) tests; without the workbench (FREQLAB_BUILD_UI=OFF), so not the window / gl
# tests (OSMesa's llvmpipe under ASan: minutes a frame, and its own leaks), nor the
# cancel-at-random test (label signals: 50 instrumented processes), nor cli.tables_generate when
# the release suite's table file is there (see below). Any report
# fails the run, also one raised inside a test that expects its command to fail (reports are
# logged to files and counted after ctest). Run after scripts/setup.sh (it installs packages).
set -euo pipefail
cd "$(dirname "$0")/.."

jobs=$(nproc 2>/dev/null || echo 2)
# -O1: compiles in about half the time of -O2 and runs the suite at a usable speed.
cmake -S . -B build-sanitize -DFREQLAB_MPI=OFF -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_FLAGS_RELEASE="-O1 -g1" \
  -DFREQLAB_SANITIZE=address,undefined -DFREQLAB_BUILD_UI=OFF >/dev/null
cmake --build build-sanitize -j "$jobs"

reports=$(mktemp -d)
trap 'rm -rf "$reports"' EXIT
export ASAN_OPTIONS="halt_on_error=1:abort_on_error=1:detect_leaks=1:log_path=$reports/asan"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1:log_path=$reports/ubsan"
export LSAN_OPTIONS="suppressions=$PWD/tests/sanitize/lsan.supp:print_suppressions=0"
# The table file the release suite generated (cli.tables_generate, build/tests/cache) serves the
# queries here too: generating it again under ASan took 378 s and tests nothing that
# unit.impulse_tables (the same tabulation, sanitized) does not. Without it, the fixture runs.
fixture_args=()
if compgen -G "build/tests/cache/tables/impulse_v*_b*.bin" >/dev/null; then
  mkdir -p build-sanitize/tests/cache/tables
  cp build/tests/cache/tables/impulse_v*_b*.bin build-sanitize/tests/cache/tables/
  fixture_args=(-FS tables_cache -E "^cli\.tables_generate$")
fi
status=0
ctest --test-dir build-sanitize -LE "slow|signals" "${fixture_args[@]}" --output-on-failure -j "$jobs" ||
  status=$?
if compgen -G "$reports/*" >/dev/null; then
  echo "sanitize: reports:" >&2
  cat "$reports"/* >&2
  exit 1
fi
exit $status
