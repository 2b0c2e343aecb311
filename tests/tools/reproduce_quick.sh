#!/usr/bin/env bash
# tools/reproduce.sh --quick (issue 10) on the programs of this build: every section of the report
# is produced, and the pose orderings it checks hold (reproduce_report.py exits 1 otherwise).
set -uo pipefail
build=$1 src=$2
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
fail=0
"$src/tools/reproduce.sh" --quick --no-build --build "$build" --out "$tmp/report" \
  > "$tmp/out.txt" 2>&1 || { echo "FAIL: reproduce.sh --quick exited $?"; fail=1; }
grep "reproduce_report\|FAILED\|failed" "$tmp/out.txt"
for section in "Pose accuracy" "Curvature accuracy" "Curvature sd against the error" "Kinect-like noise" "Bias and spread over noise" \
  "Drift along a straight rail" "Real data" "OpenCV peer" "Curvature maps" "Timings" "paper's claims"; do
  grep -q "$section" "$tmp/report/index.md" 2>/dev/null || { echo "FAIL: no '$section'"; fail=1; }
done
for f in curvature_vs_noise.png rail_drift.png synthetic_curvature.png real_curvature.png; do
  [ -s "$tmp/report/figures/$f" ] || { echo "FAIL: figure $f missing"; fail=1; }
done
[ $fail = 0 ] && echo "PASS: the --quick report is complete and its checks hold"
exit $fail
