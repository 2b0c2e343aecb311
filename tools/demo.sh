#!/usr/bin/env bash
# The main job on the embedded default: installs what is missing, builds, and evaluates the
# bundled real TUM fr1/xyz slice. Later steps grow this into the full synthetic pipeline run.
set -euo pipefail
cd "$(dirname "$0")/.."
tools/setup.sh

build=${JPCR_BUILD_DIR:-build}
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release > /dev/null
cmake --build "$build" -j"$(nproc)" --target jpcr_eval

out=${JPCR_DEMO_OUT:-out/demo}
mkdir -p "$out"
data=tests/data/tum_fr1_xyz_20
echo "== jpcr demo: trajectory metrics on $data (ground truth against itself) =="
"$build/tools/jpcr_eval" traj --gt "$data/groundtruth.txt" --est "$data/groundtruth.txt" \
  --out "$out/eval.json"
echo "report: $out/eval.json"
