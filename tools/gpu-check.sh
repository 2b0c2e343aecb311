#!/usr/bin/env bash
# The GPU check in one command (issue 7), for the GPU machine (Ubuntu 24.04, CMake 4.x, gcc 13,
# nvcc 13; Eigen, GTest, Google Benchmark, yaml-cpp and CUDA only):
#   configure the core profile with CUDA for sm_90, build the GPU targets, run the GPU tests
#   (ctest label gpu: Quad IT and J-ftf parity, plus device selection), compute-sanitizer
#   memcheck and initcheck on both GPU test binaries, then print the benchmark tables (Quad IT,
#   J-ftf). A summary comes last; the exit status is 0 only when every step passed. Every step
#   has a time limit (JPCR_STEP_LIMIT, default 240 s; the build 420 s) so the whole check fits
#   a 10-minute lease on 16 cores.
#
#   tools/gpu-check.sh [--all]       --all builds and runs every core target and test too
# Environment: JPCR_GPU_BUILD_DIR (default build-gpu), JPCR_CUDA_ARCH (default 90),
# JPCR_CMAKE_ARGS (extra configure arguments), OUT (if set, logs are copied there).
set -uo pipefail
cd "$(dirname "$0")/.." || exit 1

build=${JPCR_GPU_BUILD_DIR:-build-gpu}
arch=${JPCR_CUDA_ARCH:-90}
jobs=$(nproc)
all=0
[ "${1:-}" = "--all" ] && all=1
logs=${OUT:-$build/gpu-check-logs}
mkdir -p "$logs"

declare -a summary=()
failed=0
step() {  # step NAME COMMAND...: runs it, logs it, records PASS/FAIL
  local name=$1
  shift
  echo "==== $name: $*"
  local start=$SECONDS
  if "$@" 2>&1 | tee "$logs/$name.log"; then
    summary+=("PASS  $name ($((SECONDS - start)) s)")
  else
    summary+=("FAIL  $name ($((SECONDS - start)) s, log $logs/$name.log)")
    failed=1
    return 1
  fi
}
finish() {
  echo
  echo "==== gpu-check summary ($(date -u +%FT%TZ))"
  printf '%s\n' "${summary[@]}"
  if [ "$failed" = 0 ]; then echo "gpu-check: OK"; else echo "gpu-check: FAILED"; fi
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
step configure cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release -DJPCR_CORE_ONLY=ON \
  -DJPCR_WITH_DDS=OFF -DJPCR_WITH_CUDA=ON -DCMAKE_CUDA_COMPILER="$nvcc" \
  -DCMAKE_CUDA_ARCHITECTURES="$arch" -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  ${JPCR_CMAKE_ARGS:-} || finish

targets=(--target test_cuda_quadric_fit test_cuda_joint_ftf test_device_selection
  bench_cuda_quadric bench_cuda_joint)
[ "$all" = 1 ] && targets=()
limit=${JPCR_STEP_LIMIT:-240}
step build timeout 420 cmake --build "$build" -j"$jobs" "${targets[@]}" || finish

# JPCR_CUDA_SYNC=1 (also set by ctest for the gpu label): every launch is synchronised and checked.
export JPCR_CUDA_SYNC=1
step gpu-tests timeout "$limit" ctest --test-dir "$build" -L gpu --output-on-failure \
  --no-tests=error -j2
# A skipped GPU test on the GPU machine is a failure: the GPU was not found.
if grep -q "Skipped" "$logs/gpu-tests.log"; then
  summary+=("FAIL  gpu-tests skipped (no GPU visible?)")
  failed=1
fi
step device-selection timeout "$limit" "$build/tests/cuda/test_device_selection"
if [ "$all" = 1 ]; then
  step all-tests ctest --test-dir "$build" --output-on-failure -j"$jobs"
fi

sanitizer=/usr/local/cuda/bin/compute-sanitizer
[ -x "$sanitizer" ] || sanitizer=$(command -v compute-sanitizer || true)
if [ -n "$sanitizer" ]; then
  for tool in memcheck initcheck; do
    step "sanitizer-$tool" timeout "$limit" "$sanitizer" --tool "$tool" --error-exitcode 1 \
      "$build/tests/cuda/test_cuda_quadric_fit"
    # J-ftf: one iteration against the CPU and three short refinements (the kernels, every
    # buffer); the full refinement parity test adds only more of the same launches.
    step "sanitizer-$tool-jftf" timeout "$limit" "$sanitizer" --tool "$tool" --error-exitcode 1 \
      "$build/tests/cuda/test_cuda_joint_ftf" \
      --gtest_filter='*OneIterationEqualsTheCpuReference:*ReusesDeviceBuffersAcrossPairs'
  done
else
  summary+=("SKIP  compute-sanitizer (not found)")
fi

step benchmark timeout "$limit" "$build/tools/bench/bench_cuda_quadric" --runs 30
step benchmark-jftf timeout "$limit" "$build/tools/bench/bench_cuda_joint" --runs 30
finish
