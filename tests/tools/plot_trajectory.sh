#!/usr/bin/env bash
# tools/plot_trajectory.py draws a PNG from TUM trajectories and fails clearly on bad input.
set -uo pipefail
build=$1 src=$2 data=$3
/usr/bin/python3 -c 'import matplotlib' 2>/dev/null || { echo "SKIP: no python3-matplotlib"; exit 0; }
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
gt=$data/tum_fr1_xyz_20/groundtruth.txt
/usr/bin/python3 "$src/tools/plot_trajectory.py" --gt "$gt" --est "$gt:copy" --out "$tmp/p.png" || exit 1
head -c 8 "$tmp/p.png" | od -c | grep -q 'P   N   G' || { echo "FAIL: not a PNG"; exit 1; }
printf '1 0 0 0 0 0 0\n' > "$tmp/bad.txt"
out=$(/usr/bin/python3 "$src/tools/plot_trajectory.py" --gt "$gt" --est "$tmp/bad.txt" --out "$tmp/q.png" 2>&1)
rc=$?
[ $rc -ne 0 ] && grep -q "bad.txt:1: expected 8 finite numbers" <<<"$out" || { echo "FAIL: rc=$rc out=$out"; exit 1; }
[ ! -e "$tmp/q.png" ] || { echo "FAIL: partial PNG"; exit 1; }
echo "ok"
