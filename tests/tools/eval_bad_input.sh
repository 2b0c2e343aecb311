#!/usr/bin/env bash
# jpcr_eval on bad input: one clear message naming the file (and line), a non-zero exit, and no
# partial output file.
set -uo pipefail
build=$1 src=$2 data=$3
eval_bin=$build/tools/jpcr_eval
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
# shellcheck source=expect.sh
source "$src/tests/tools/expect.sh"
printf '1 0 0 0 0 0 0 1\n2 0 0 0 0 0 0 1\n3 1 0 0 0 0 0 1\n4 1 1 0 0 0 0 1\n' > "$tmp/gt.txt"
printf '1 0 0 0 0 0 0 1\n2 0 0 nan 0 0 0 1\n' > "$tmp/nan.txt"
printf '2 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n' > "$tmp/unsorted.txt"
printf '# only a comment\n' > "$tmp/empty.txt"
expect 1 "missing.txt: file does not exist" -- "$eval_bin" traj --gt "$tmp/gt.txt" --est "$tmp/missing.txt"
expect 1 "nan.txt:2: field 4 is NaN/Inf" -- "$eval_bin" traj --gt "$tmp/gt.txt" --est "$tmp/nan.txt"
expect 1 "unsorted.txt:2: timestamps are not sorted" -- "$eval_bin" traj --gt "$tmp/gt.txt" --est "$tmp/unsorted.txt"
expect 1 "empty.txt: no poses" -- "$eval_bin" traj --gt "$tmp/gt.txt" --est "$tmp/empty.txt" --out "$tmp/report.json"
# The report never replaces an input (here by another name for it).
cp "$tmp/gt.txt" "$tmp/gt_before.txt"
expect 1 "is --gt .*gt.txt itself" -- "$eval_bin" traj --gt "$tmp/gt.txt" --est "$tmp/gt.txt" --out "$tmp/../$(basename "$tmp")/gt.txt"
cmp -s "$tmp/gt.txt" "$tmp/gt_before.txt" || { echo "FAIL: --gt was overwritten"; fail=1; }
printf '1 0 0 0 0 0 0 1\n2 1e308 0 0 0 0 0 1\n3 -1e308 0 0 0 0 0 1\n4 1e308 1e308 0 0 0 0 1\n' > "$tmp/huge.txt"
expect 1 "huge.txt: the errors against .* are not finite" -- "$eval_bin" traj --gt "$tmp/gt.txt" --est "$tmp/huge.txt"
expect 2 "max-difference must be a positive number" -- "$eval_bin" traj --gt "$tmp/gt.txt" --est "$tmp/gt.txt" --max-difference inf
expect 2 "est is required" -- "$eval_bin" traj --gt "$tmp/gt.txt"
expect 2 "unknown option --bogus" -- "$eval_bin" traj --bogus
expect 2 "unknown command" -- "$eval_bin" frobnicate
expect 2 "--noise: noise 'bogus'" -- "$eval_bin" noise --noise bogus
expect 0 "usage: jpcr_eval traj" -- "$eval_bin" traj --help
# Ground truth at 10 Hz, the estimate at 30 Hz: a third of it is evaluated (said), and no two
# consecutive estimated poses both have ground truth, so the relative errors are n/a (null), not 0.
for i in $(seq 0 30); do echo "$(awk "BEGIN{print $i/10}") 0.$i 0 0 0 0 0 1"; done > "$tmp/gt10hz.txt"
for i in $(seq 0 89); do echo "$(awk "BEGIN{printf \"%.6f\", $i/30}") 0.$i 0 0 0 0 0 1"; done > "$tmp/est30hz.txt"
expect 0 "warning: only 30 of 90 estimated poses have ground truth" -- "$eval_bin" traj --gt "$tmp/gt10hz.txt" --est "$tmp/est30hz.txt"
expect 0 "relative (paper Tables I-III) n/a (no two consecutive" -- "$eval_bin" traj --gt "$tmp/gt10hz.txt" --est "$tmp/est30hz.txt"
expect 0 '"relative": null' -- "$eval_bin" traj --gt "$tmp/gt10hz.txt" --est "$tmp/est30hz.txt" --json
# --baseline: a second estimate compared pair by pair; bad ones are named.
expect 1 "missing.txt: file does not exist" -- "$eval_bin" traj --gt "$tmp/gt.txt" --est "$tmp/gt.txt" --baseline "$tmp/missing.txt"
expect 1 "gt.txt: only 3 frame pairs are common to the estimate and the baseline (need 10)" -- \
  "$eval_bin" traj --gt "$tmp/gt.txt" --est "$tmp/gt.txt" --baseline "$tmp/gt.txt"
for i in $(seq 1 30); do echo "$i $((i % 7)) $((i % 3)).$i 0 0 0 0 1"; done > "$tmp/gt30.txt"
for i in $(seq 1 30); do echo "$i $((i % 7)).0$((i % 5)) $((i % 3)).$i 0 0.0$((i % 4)) 0 0 1"; done > "$tmp/est30.txt"
expect 1 "baseline's relative errors are all zero" -- "$eval_bin" traj --gt "$tmp/gt30.txt" --est "$tmp/est30.txt" --baseline "$tmp/gt30.txt"
expect 0 "translation 1.0000  \[1.0000, 1.0000\]  indistinguishable" -- \
  "$eval_bin" traj --gt "$tmp/gt30.txt" --est "$tmp/est30.txt" --baseline "$tmp/est30.txt"
expect 0 '"verdict": "indistinguishable"' -- \
  "$eval_bin" traj --gt "$tmp/gt30.txt" --est "$tmp/est30.txt" --baseline "$tmp/est30.txt" --json
[ -e "$tmp/report.json" ] && { echo "FAIL: partial report written"; fail=1; }
# Nor a file of another run's results or of a dataset, whatever the inputs.
mkdir -p "$tmp/run1" "$tmp/seq" && echo '{}' > "$tmp/run1/report.json" && touch "$tmp/seq/depth.txt"
touch "$tmp/run1/verdicts.txt"
expect 1 "run1/report.json: is a file of the dataset or results in" -- \
  "$eval_bin" traj --gt "$tmp/gt30.txt" --est "$tmp/est30.txt" --out "$tmp/run1/report.json"
expect 1 "seq/depth.txt: is a file of the dataset or results in" -- \
  "$eval_bin" traj --gt "$tmp/gt30.txt" --est "$tmp/est30.txt" --out "$tmp/seq/depth.txt"
[ "$(cat "$tmp/run1/report.json")" = "{}" ] && [ ! -s "$tmp/seq/depth.txt" ] ||
  { echo "FAIL: a results or dataset file was overwritten"; fail=1; }
# jpcr_eval's own report.json (no verdicts.txt beside it) is replaced by a second run.
expect 0 "translation" -- "$eval_bin" traj --gt "$tmp/gt30.txt" --est "$tmp/est30.txt" --out "$tmp/mine/report.json"
expect 0 "translation" -- "$eval_bin" traj --gt "$tmp/gt30.txt" --est "$tmp/est30.txt" --out "$tmp/mine/report.json"
# Nothing associates: the message names both files.
printf '100 0 0 0 0 0 0 1\n101 0 0 0 0 0 0 1\n102 0 0 0 0 0 0 1\n' > "$tmp/later.txt"
expect 1 "later.txt against .*gt30.txt: ATE: only 0 poses associate" -- \
  "$eval_bin" traj --gt "$tmp/gt30.txt" --est "$tmp/later.txt"
# --out in a directory not made yet: made, as the other tools do.
expect 0 "translation" -- "$eval_bin" traj --gt "$tmp/gt30.txt" --est "$tmp/est30.txt" --out "$tmp/new/dir/r.json"
[ -s "$tmp/new/dir/r.json" ] || { echo "FAIL: --out in a new directory not written"; fail=1; }
ls "$tmp" | grep -q '\.tmp\.' && { echo "FAIL: temporary file left behind"; fail=1; }
exit $fail
