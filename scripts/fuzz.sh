#!/usr/bin/env bash
# The libFuzzer targets (tests/fuzz: scene JSON, --set assignments, session files, impulse
# tables, EXR / HDR environment maps, VDB grids, run-store frames) built with clang, ASan and
# UBSan in build-sanitize/ (scripts/instrumented_build.sh), each run for FREQLAB_FUZZ_RUNS
# mutations (default 10000; by hand, e.g. FREQLAB_FUZZ_RUNS=1000000 bash scripts/fuzz.sh).
# Any crash, sanitizer report, leak, uncaught non-Error exception or input over 1 s fails.
# scripts/sanitize.sh runs them too (CI); this runs them alone. Run after scripts/setup.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/instrumented_build.sh
cmake --build build-sanitize -j "$jobs" --target "${fuzz_targets[@]}"
ctest --test-dir build-sanitize -L fuzz --output-on-failure -j "$jobs"
