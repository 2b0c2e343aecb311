#!/usr/bin/env bash
# The GPU check in one command (issue 7), for the GPU machine (Ubuntu 24.04, CMake 4.x, gcc 13,
# nvcc 13; Eigen, GTest, Google Benchmark, yaml-cpp and CUDA only):
#   configure the core profile with CUDA for sm_90, build the GPU targets, run the GPU tests
#   (ctest label gpu: Quad IT and J-ftf parity, plus device selection), time the benchmark
#   tables (bench_cuda_quadric, bench_cuda_joint), run compute-sanitizer memcheck, initcheck and racecheck
#   on both GPU test binaries, then print the tables again and a summary last; the exit status is
#   0 only when every step passed.
# Time: the whole check stays inside JPCR_GPU_CHECK_BUDGET seconds (default 570, a 10-minute
# lease): every step runs under `timeout` with its own limit (build 420 s, others
# JPCR_STEP_LIMIT, default 240 s) cut to what is left of the budget; a step with no time left
# fails as "out of time". The steps are ordered by what a run must show: tests, then tables,
# then the sanitizers.
#
#   tools/gpu-check.sh [--all]       --all builds and runs every core target and test too
# Environment: JPCR_GPU_BUILD_DIR (default build-gpu), JPCR_CUDA_ARCH (default 90),
# JPCR_CMAKE_ARGS (extra configure arguments), JPCR_GPU_NCU (1: profile the 640x480 kernels
# with ncu after the tables; default 0), JPCR_GPU_SANITIZERS (0: skip compute-sanitizer;
# default 1), OUT (if set, every log goes there as one archive, gpu-check-logs.tgz, beside
# the summary, gpu-check-summary.txt).
set -uo pipefail
cd "$(dirname "$0")/.." || exit 1

build=${JPCR_GPU_BUILD_DIR:-build-gpu}
arch=${JPCR_CUDA_ARCH:-90}
budget=${JPCR_GPU_CHECK_BUDGET:-570}
limit=${JPCR_STEP_LIMIT:-240}
jobs=$(nproc)
all=0
case "${1:-}" in
  "") ;;
  --all) all=1 ;;
  -h|--help) sed -n '2,/^set /p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
  *) echo "gpu-check: unknown option '$1' (--all, --help)" >&2; exit 2 ;;
esac
logs=$build/gpu-check-logs
rm -rf "$logs"
mkdir -p "$logs"

declare -a summary=()
failed=0
step() {  # step NAME LIMIT COMMAND...: runs it under timeout, logs it, records PASS/FAIL
  local name=$1 seconds=$2
  shift 2
  local left=$((budget - SECONDS))
  if [ "$left" -lt 10 ]; then
    summary+=("FAIL  $name (out of time: the ${budget} s budget is spent)")
    failed=1
    return 1
  fi
  [ "$seconds" -gt "$left" ] && seconds=$left
  echo "==== $name (limit ${seconds} s): $*"
  local start=$SECONDS
  if timeout "$seconds" "$@" 2>&1 | tee "$logs/$name.log"; then
    summary+=("PASS  $name ($((SECONDS - start)) s)")
  else
    summary+=("FAIL  $name ($((SECONDS - start)) s of ${seconds}, log $logs/$name.log)")
    failed=1
    return 1
  fi
}
finish() {
  for table in benchmark benchmark-jftf; do
    [ -f "$logs/$table.log" ] && { echo; cat "$logs/$table.log"; }
  done
  echo
  {
    echo "==== gpu-check summary ($(date -u +%FT%TZ), ${SECONDS} s)"
    printf '%s\n' "${summary[@]}"
    if [ "$failed" = 0 ]; then echo "gpu-check: OK"; else echo "gpu-check: FAILED"; fi
  } | tee "$logs/summary.txt"
  if [ -n "${OUT:-}" ]; then  # one archive: the device tool brings back at most 8 files
    tar czf "$OUT/gpu-check-logs.tgz" -C "$logs" . && cp "$logs/summary.txt" "$OUT/gpu-check-summary.txt"
  fi
  exit "$failed"
}

command -v nvidia-smi > /dev/null && nvidia-smi -L
nvcc=${CUDACXX:-/usr/local/cuda/bin/nvcc}
[ -x "$nvcc" ] || nvcc=$(command -v nvcc || true)
if [ -z "$nvcc" ]; then
  echo "gpu-check: no nvcc (set CUDACXX)" >&2
  exit 1
fi

# CMAKE_POLICY_VERSION_MINIMUM: CMake 4 refuses package files written for CMake < 3.5; jpcr
# itself asks for 3.22, and CMake 3.x ignores the setting.
# shellcheck disable=SC2086
step configure 120 cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release -DJPCR_CORE_ONLY=ON \
  -DJPCR_WITH_DDS=OFF -DJPCR_WITH_CUDA=ON -DCMAKE_CUDA_COMPILER="$nvcc" \
  -DCMAKE_CUDA_ARCHITECTURES="$arch" -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  ${JPCR_CMAKE_ARGS:-} || finish

targets=(--target test_cuda_quadric_fit test_cuda_joint_ftf test_device_selection
  bench_cuda_quadric bench_cuda_joint)
[ "$all" = 1 ] && targets=()
step build 420 cmake --build "$build" -j"$jobs" "${targets[@]}" || finish

# JPCR_CUDA_SYNC=1 (also set by ctest for the gpu label): every launch is synchronised and checked.
export JPCR_CUDA_SYNC=1
step gpu-tests "$limit" ctest --test-dir "$build" -L gpu --output-on-failure --no-tests=error -j2
# A skipped GPU test on the GPU machine is a failure: the GPU was not found.
if grep -q "Skipped" "$logs/gpu-tests.log"; then
  summary+=("FAIL  gpu-tests skipped (no GPU visible?)")
  failed=1
fi
step device-selection "$limit" "$build/tests/cuda/test_device_selection"
if [ "$all" = 1 ]; then
  step all-tests "$limit" ctest --test-dir "$build" --output-on-failure -j"$jobs"
fi

# The tables run with synchronous checks off: they time the asynchronous pipeline.
JPCR_CUDA_SYNC=0 step benchmark "$limit" "$build/tools/bench/bench_cuda_quadric" --runs 30
JPCR_CUDA_SYNC=0 step benchmark-jftf "$limit" "$build/tools/bench/bench_cuda_joint" --runs 30

# Where the time goes inside the 640x480 kernels (the first launches of each: double).
# --clock-control none: the card's clocks are left as they are.
ncu=/usr/local/cuda/bin/ncu
[ -x "$ncu" ] || ncu=$(command -v ncu || ls /opt/nvidia/nsight-compute/*/ncu 2> /dev/null | tail -1)
if [ "${JPCR_GPU_NCU:-0}" = 1 ] && [ -n "$ncu" ]; then
  sections=(--section SpeedOfLight --section Occupancy --section LaunchStats
    --section MemoryWorkloadAnalysis --section ComputeWorkloadAnalysis)
  JPCR_CUDA_SYNC=0 step ncu-jftf "$limit" "$ncu" --clock-control none "${sections[@]}" \
    --kernel-name regex:'linearize_pair|step_pair' --launch-count 2 \
    "$build/tools/bench/bench_cuda_joint" --width 640 --runs 20 --warmup 1 --no-cpu
  JPCR_CUDA_SYNC=0 step ncu-quad-it "$limit" "$ncu" --clock-control none "${sections[@]}" \
    --kernel-name regex:'quad_it|plane_normals' --launch-count 3 \
    "$build/tools/bench/bench_cuda_quadric" --width 640 --runs 20 --warmup 1 --no-cpu
elif [ "${JPCR_GPU_NCU:-0}" = 1 ]; then
  summary+=("SKIP  ncu (not found)")
fi

sanitizer=/usr/local/cuda/bin/compute-sanitizer
[ -x "$sanitizer" ] || sanitizer=$(command -v compute-sanitizer || true)
if [ "${JPCR_GPU_SANITIZERS:-1}" = 0 ]; then
  summary+=("SKIP  compute-sanitizer (JPCR_GPU_SANITIZERS=0)")
elif [ -n "$sanitizer" ]; then
  for tool in memcheck initcheck racecheck; do
    step "sanitizer-$tool" "$limit" "$sanitizer" --tool "$tool" --error-exitcode 1 \
      "$build/tests/cuda/test_cuda_quadric_fit"
    # J-ftf: one iteration against the CPU and three short refinements (the kernels, every
    # buffer); the full refinement parity test adds only more of the same launches.
    step "sanitizer-$tool-jftf" "$limit" "$sanitizer" --tool "$tool" --error-exitcode 1 \
      "$build/tests/cuda/test_cuda_joint_ftf" \
      --gtest_filter='*OneIterationEqualsTheCpuReference:*ReusesDeviceBuffersAcrossPairs'
  done
else
  summary+=("SKIP  compute-sanitizer (not found)")
fi
finish
