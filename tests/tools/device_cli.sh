#!/usr/bin/env bash
# --device of jpcr_run and jpcr_curvature (issue 7): a bad value is a usage error (exit 2); cpu
# runs and says so; cuda without a usable GPU is an error naming the cause (exit 1), never a
# silent fall back; with a GPU it runs there. auto always runs.
set -uo pipefail
build=$1 src=$2
synth=$build/tools/jpcr_synth
run=$build/tools/jpcr_run
curv=$build/tools/jpcr_curvature
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
# shellcheck source=expect.sh
source "$src/tests/tools/expect.sh"

expect 0 "wrote 3 frames" -- "$synth" --scene room_spheres --frames 3 --size 160x120 --seed 2 \
  --out "$tmp/seq"
expect 2 "device: 'gpu0' is not one of auto, cpu, cuda" -- \
  "$run" --dataset "$tmp/seq" --device gpu0 --out "$tmp/bad"
[ -e "$tmp/bad/trajectory.txt" ] && { echo "FAIL: a usage error wrote outputs"; fail=1; }
expect 0 "device cpu -> cpu" -- "$run" --dataset "$tmp/seq" --method pipeline --window 2 \
  --device cpu --out "$tmp/cpu"
expect 0 "j-full runs on the cpu" -- "$run" --dataset "$tmp/seq" --method pipeline --window 2 \
  --device auto --out "$tmp/auto"
if "$run" --dataset "$tmp/seq" --method j-ftf --device cuda --out "$tmp/cuda" \
  > "$tmp/cuda.log" 2>&1; then
  grep -q "device cuda -> cuda" "$tmp/cuda.log" || { echo "FAIL: cuda ran but did not say where"; fail=1; }
  echo "ok: a GPU is usable here, j-ftf ran on it"
else
  rc=$?
  if [ "$rc" != 1 ] || ! grep -q "no CUDA device is usable" "$tmp/cuda.log"; then
    echo "FAIL: --device cuda without a GPU exited $rc: $(cat "$tmp/cuda.log")"; fail=1
  else
    echo "ok: --device cuda without a GPU -> 1: $(grep -m1 'no CUDA' "$tmp/cuda.log")"
  fi
fi
expect 2 "--device" -- "$curv" --dataset "$tmp/seq" --device 1 --out "$tmp/c_bad"
expect 0 "device cpu -> cpu" -- "$curv" --dataset "$tmp/seq" --device cpu --out "$tmp/c_cpu"
exit $fail
