#!/usr/bin/env bash
# A rank killed mid-run (SIGKILL: no chance to clean up): the job must end non-zero within 10 s,
# say which rank died, and leave no partial file (rank 0 writes frames atomically, stats.json
# only at the end).
# usage: rank_killed.sh FREQLAB SOURCE_DIR WORKDIR
set -uo pipefail
fl=$1 src=$2 work=$3
rm -rf "$work"
mkdir -p "$work"
mpirun --oversubscribe --allow-run-as-root -np 3 "$fl" render "$src/scenes/rotor.json" \
  --method reference --set reference.use_cache=0 --spp 64 --frames 0:60 --size 320x180 \
  --threads 1 --quiet --out "$work/out" 2> "$work/stderr" &
job=$!
victim=""
for _ in $(seq 600); do  # up to 60 s for rank 0 to write its first frame
  for p in $(pgrep -f "freqlab render $src/scenes/rotor.json" || true); do
    tr '\0' '\n' < "/proc/$p/environ" 2>/dev/null | grep -qx "OMPI_COMM_WORLD_RANK=1" && victim=$p
  done
  [ -n "$victim" ] && [ -e "$work/out/frame_0000.exr" ] && break
  sleep 0.1
done
[ -n "$victim" ] || { echo "FAIL: rank 1 never started"; kill -9 $job; exit 1; }
kill -9 "$victim"
start=$(date +%s.%N)
wait $job
rc=$?
elapsed=$(python3 -c "import time; print(f'{time.time() - $start:.2f}')")
echo "job exit code $rc, $elapsed s after the kill"
sed 's/^/  stderr: /' "$work/stderr" | grep -v "^  stderr: *$" | head -n 12
[ "$rc" -ne 0 ] || { echo "FAIL: the job exited 0"; exit 1; }
python3 -c "import sys; sys.exit(0 if $elapsed < 10 else 1)" || { echo "FAIL: over 10 s"; exit 1; }
grep -q "rank 1" "$work/stderr" || { echo "FAIL: stderr does not name rank 1"; exit 1; }
[ ! -e "$work/out/stats.json" ] || { echo "FAIL: stats.json of an unfinished run"; exit 1; }
bad=$(cd "$work/out" && ls -A | grep -Ev '^frame_[0-9]{4}\.(exr|png)$' || true)
[ -z "$bad" ] || { echo "FAIL: files other than whole frames: $bad"; exit 1; }
for f in "$work"/out/frame_*.exr; do
  "$fl" compare "$f" "$f" --metrics rmse > /dev/null || { echo "FAIL: $f does not decode"; exit 1; }
done
echo "no partial file: $(ls "$work/out" | wc -l) complete frame files"
