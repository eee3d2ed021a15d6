#!/usr/bin/env bash
# Sourced by scripts/sanitize.sh and scripts/fuzz.sh: configures build-sanitize/, the one
# instrumented build both use: clang, -O1, AddressSanitizer + UndefinedBehaviorSanitizer, the
# libFuzzer targets (freqlab_core with -fsanitize=fuzzer-no-link), no workbench, no MPI.
# One build instead of two (a gcc sanitized one and a clang fuzzing one): the instrumented
# builds were ~880 s of CI's ~1920 s; merged they compile in ~430 s on 2 cores.
# Sets `jobs`. FREQLAB_FUZZ_RUNS: mutations each fuzz test runs (default 10000).
jobs=$(nproc 2>/dev/null || echo 2)
# A build-sanitize/ configured by gcc (before session 25) is configured again from scratch.
if [[ -f build-sanitize/CMakeCache.txt ]] &&
  ! grep -q '^CMAKE_CXX_COMPILER:[A-Z]*=.*clang++' build-sanitize/CMakeCache.txt; then
  rm -rf build-sanitize
fi
# -O1: compiles in about half the time of -O2 and runs the suite at a usable speed.
CC=clang CXX=clang++ cmake -S . -B build-sanitize -DFREQLAB_MPI=OFF -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_CXX_FLAGS_RELEASE="-O1 -g1" -DFREQLAB_SANITIZE=address,undefined -DFREQLAB_FUZZ=ON \
  -DFREQLAB_BUILD_UI=OFF -DFREQLAB_FUZZ_RUNS="${FREQLAB_FUZZ_RUNS:-10000}" >/dev/null
fuzz_targets=(fuzz_scene_json fuzz_set_assignment fuzz_session fuzz_impulse_table fuzz_env_exr
  fuzz_env_hdr fuzz_vdb fuzz_run_store)
