#!/usr/bin/env bash
# Cache checkpoints (issue "The timeline as a recorded run", acceptance 2): method cache
# rendered 0..11 in order with --checkpoint-every 4; resumed at frames 6 and 8 (from the
# checkpoints before 4 and 8) every frame kept is byte-identical to the sequential run's EXR and
# PNG. A run with another setting, a damaged checkpoint, a stateless method are refused naming
# the field, and nothing is written for them.
# usage: resume_identical.sh FREQLAB SCENE OUT
set -euo pipefail
fl=$1 scene=$2 out=$3
rm -rf "$out"
mkdir -p "$out"
common=(--method cache --size 160x90 --quiet)
"$fl" render "$scene" "${common[@]}" --frames 0:12 --checkpoint-every 4 --out "$out/seq"
for f in 4 8 12; do
  test -s "$out/seq/checkpoints/$(printf 'state_before_%04d.bin' $f)" ||
    { echo "no checkpoint before frame $f"; exit 1; }
done
for first in 6 8; do
  # The same --checkpoint-every: the period is in every file's provenance (the settings used).
  "$fl" render "$scene" "${common[@]}" --frames "$first:12" --resume-from "$out/seq" \
    --checkpoint-every 4 --out "$out/resumed_$first"
  for ((f = first; f < 12; ++f)); do
    name=$(printf 'frame_%04d' $f)
    cmp "$out/seq/$name.exr" "$out/resumed_$first/$name.exr"
    cmp "$out/seq/$name.png" "$out/resumed_$first/$name.png"
  done
  # Frames before the first are rendered (from the checkpoint) but not kept.
  test ! -e "$out/resumed_$first/$(printf 'frame_%04d' $((first - 1))).exr"
done
# A cold start at frame 6 (no --resume-from) is not the sequential run: the test can fail.
"$fl" render "$scene" "${common[@]}" --frames 6:7 --checkpoint-every 4 --out "$out/cold"
if cmp -s "$out/seq/frame_0007.exr" "$out/cold/frame_0006.exr" ||
  cmp -s "$out/seq/frame_0006.exr" "$out/cold/frame_0006.exr"; then
  echo "a cold start gave the sequential run's frame: the comparison proves nothing"
  exit 1
fi
expect_refusal() {  # expect_refusal PATTERN DIR ARGS...
  local pattern=$1 dir=$2
  shift 2
  if "$fl" render "$scene" "$@" --quiet --out "$dir" 2>"$out/err.txt"; then
    echo "accepted: $*"
    exit 1
  fi
  grep -q -- "$pattern" "$out/err.txt" || { echo "expected '$pattern' in:"; cat "$out/err.txt"; exit 1; }
  if compgen -G "$dir/frame_*" >/dev/null; then
    echo "frames written by a refused run"
    exit 1
  fi
}
expect_refusal "key.settings" "$out/other" --method cache --size 160x90 --frames 9:10 \
  --resume-from "$out/seq" --set cache.q_eps_x=0.001
cp -r "$out/seq" "$out/damaged"
printf 'x' | dd of="$out/damaged/checkpoints/state_before_0008.bin" bs=1 seek=200 conv=notrunc \
  2>/dev/null
expect_refusal "checksum" "$out/damaged_run" --method cache --size 160x90 --frames 9:10 \
  --resume-from "$out/damaged"
expect_refusal "keeps nothing across frames" "$out/mis" --method mis --size 160x90 \
  --frames 0:1 --checkpoint-every 4
echo "resumed frames identical; bad checkpoints refused"
