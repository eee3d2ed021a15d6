#!/usr/bin/env bash
# Every file of folder A but stats.json is in folder B with the same bytes, and B has no other
# file (no temporary left behind); with N, B's stats.json records N ranks or N merged parts.
# A study's JSON / CSV carries wall-clock times (keys and columns named *_ms), which no two
# runs share: those files must be byte-identical once the times are removed.
# usage: same_outputs.sh A B [N]
set -euo pipefail
a=$1 b=$2 n=${3:-}
(cd "$a" && find . -type f ! -name stats.json | sort) > "$b.files_a"
(cd "$b" && find . -type f ! -name stats.json | sort) > "$b.files_b"
if ! diff "$b.files_a" "$b.files_b"; then
  echo "FAIL: the two folders hold different files"; exit 1
fi
count=0 timed=0
while read -r f; do
  if ! cmp -s "$a/$f" "$b/$f"; then
    case "$f" in
      *.json | *.csv)
        python3 "$(dirname "$0")/without_times.py" "$a/$f" > "$b.norm_a"
        python3 "$(dirname "$0")/without_times.py" "$b/$f" > "$b.norm_b"
        cmp "$b.norm_a" "$b.norm_b" || { echo "FAIL: $f differs (times apart)"; exit 1; }
        timed=$((timed + 1)) ;;
      *) echo "FAIL: $f differs"; exit 1 ;;
    esac
  fi
  count=$((count + 1))
done < "$b.files_a"
[ "$count" -gt 0 ] || { echo "FAIL: no output files"; exit 1; }
if [ -n "$n" ] && [ -e "$b/stats.json" ]; then  # a study's folder has no stats.json
  got=$(python3 -c "import json,sys; d=json.load(open('$b/stats.json')); print(len(d.get('ranks', d.get('merged_parts', []))))")
  [ "$got" = "$n" ] || { echo "FAIL: stats.json records $got ranks / parts, expected $n"; exit 1; }
fi
echo "identical: $count files (stats.json apart; $timed of them once their *_ms times are removed)"
