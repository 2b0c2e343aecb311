#!/usr/bin/env bash
# jpcr_run's verdicts.txt (issue 11): one line per frame of trajectory.txt with the same
# timestamps, "timestamp front_end pair window trusted". On a single plane (a degenerate scene)
# every frame after the first is flagged, the run says so, and it still writes every output and
# exits 0.
set -uo pipefail
build=$1 src=$2
synth=$build/tools/jpcr_synth
run=$build/tools/jpcr_run
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
# shellcheck source=expect.sh
source "$src/tests/tools/expect.sh"

expect 0 "wrote 5 frames" -- "$synth" --scene single_plane --frames 5 --size 160x120 --seed 3 \
  --out "$tmp/plane"
expect 0 "wrote 5 poses" -- "$run" --dataset "$tmp/plane" --out "$tmp/run"
# ... and says so at the end, not only in verdicts.txt.
expect 0 "warning: 4 of 5 frames are not trusted (front end: 4 degenerate)" -- \
  "$run" --dataset "$tmp/plane" --out "$tmp/run"
# The error table never stands without the count (synthetic ground truth: the table is printed).
expect 0 "frames trusted: 1 of 5 (verdicts.txt)" -- "$run" --dataset "$tmp/plane" --out "$tmp/run"
verdicts=$tmp/run/verdicts.txt
[ -s "$verdicts" ] || { echo "FAIL: verdicts.txt missing"; exit 1; }
stamps() { grep -v '^#' "$1" | awk '{print $1}'; }
if [ "$(stamps "$verdicts")" != "$(stamps "$tmp/run/trajectory.txt")" ]; then
  echo "FAIL: verdicts.txt and trajectory.txt differ in their timestamps"; fail=1
fi
grep -v '^#' "$verdicts" | awk '
  NF != 5 { print "FAIL: line " NR " has " NF " fields: " $0; bad = 1 }
  NR == 1 && $2 != "ok" { print "FAIL: the first frame (the gauge) is " $2; bad = 1 }
  NR > 1 && ($2 != "degenerate" || $5 != "no") { print "FAIL: frame " NR - 1 " on a plane: " $0; bad = 1 }
  END { if (NR != 5) { print "FAIL: " NR " verdict lines, want 5"; bad = 1 } exit bad }' || fail=1
[ "$fail" = 0 ] && echo "ok: $(grep -vc '^#' "$verdicts") verdict lines, frames 1-4 degenerate"
exit $fail
