#!/usr/bin/env bash
# run_target.sh FUZZER SEED_CORPUS RUNS: RUNS mutations (fixed seed: the same inputs every run)
# starting from a copy of SEED_CORPUS; -timeout 1: an input taking over a second is a finding.
set -euo pipefail
out=$PWD
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cp -r "$2"/. "$work"/
cd "$work"
exec "$1" -runs="$3" -seed=1 -timeout=1 -rss_limit_mb=2048 -max_len=16384 \
  -artifact_prefix="$out/$(basename "$1")-" "$work"
