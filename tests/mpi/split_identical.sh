#!/usr/bin/env bash
# One process, then `mpirun -np NP`, of the same freqlab command: every output file but
# stats.json (times) must be byte-identical, and the split run's stats must list NP ranks.
# usage: split_identical.sh FREQLAB WORKDIR NP SUBCOMMAND ARGS...   (no --out: it adds one)
set -euo pipefail
fl=$1 work=$2 np=$3
shift 3
rm -rf "$work"
mkdir -p "$work"
"$fl" "$@" --quiet --out "$work/one"
mpirun --oversubscribe --allow-run-as-root -np "$np" "$fl" "$@" --quiet --out "$work/split"
exec bash "$(dirname "$0")/same_outputs.sh" "$work/one" "$work/split" "$np"
