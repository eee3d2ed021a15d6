#!/usr/bin/env bash
# A Slurm job array emulated: the array script's N tasks one after another with the variables
# Slurm sets, then the merge script; the merged run must equal one process's byte for byte.
# usage: slurm_emulation.sh FREQLAB SOURCE_DIR WORKDIR N SUBCOMMAND ARGS...   (no --out)
set -euo pipefail
fl=$1 src=$2 work=$3 n=$4
shift 4
rm -rf "$work"
mkdir -p "$work"
"$fl" "$@" --quiet --out "$work/one"
for ((i = 0; i < n; ++i)); do
  FREQLAB="$fl" SLURM_ARRAY_JOB_ID=4242 SLURM_ARRAY_TASK_ID=$i SLURM_ARRAY_TASK_COUNT=$n \
    SLURM_ARRAY_TASK_MIN=0 SLURM_ARRAY_TASK_MAX=$((n - 1)) SLURM_CPUS_PER_TASK=1 \
    bash "$src/scripts/slurm/freqlab_array.sbatch" "$work/array" "$@"
done
FREQLAB="$fl" SLURM_JOB_ID=4243 bash "$src/scripts/slurm/freqlab_merge.sbatch" "$work/array"
exec bash "$src/tests/mpi/same_outputs.sh" "$work/one" "$work/array/run" "$n"
