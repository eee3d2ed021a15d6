#!/usr/bin/env bash
# The libFuzzer targets (tests/fuzz: scene JSON, --set assignments, session files, impulse
# tables, EXR / HDR environment maps, VDB grids) built with clang, ASan and
# UBSan in build-fuzz/, each run for FREQLAB_FUZZ_RUNS mutations (default 10000; by hand, e.g.
# FREQLAB_FUZZ_RUNS=1000000 bash scripts/fuzz.sh). Any crash, sanitizer report, leak, uncaught
# non-Error exception or input over 1 s fails. Run after scripts/setup.sh (it installs clang).
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc 2>/dev/null || echo 2)
runs=${FREQLAB_FUZZ_RUNS:-10000}
CC=clang CXX=clang++ cmake -S . -B build-fuzz -DFREQLAB_MPI=OFF -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_CXX_FLAGS_RELEASE="-O1 -g1" -DFREQLAB_SANITIZE=address,undefined -DFREQLAB_FUZZ=ON \
  -DFREQLAB_BUILD_UI=OFF -DFREQLAB_BUILD_TESTS=OFF -DFREQLAB_FUZZ_RUNS="$runs" >/dev/null
targets=(scene_json set_assignment session impulse_table env_exr env_hdr vdb run_store)
cmake --build build-fuzz -j "$jobs" --target "${targets[@]/#/fuzz_}"
ctest --test-dir build-fuzz -L fuzz --output-on-failure -j "$jobs"
