#!/usr/bin/env bash
# Builds jpcr and runs the whole test suite (the README's test command; .ci/run calls it).
# Environment: JPCR_BUILD_DIR (default build), JPCR_CMAKE_ARGS (extra configure arguments).
set -euo pipefail
cd "$(dirname "$0")/.."
tools/setup.sh

build=${JPCR_BUILD_DIR:-build}
jobs=$(nproc)
# Without a GPU the CUDA code only has to compile: one architecture (that of tools/gpu-check.sh).
arch=()
if ! nvidia-smi -L > /dev/null 2>&1; then arch=(-DCMAKE_CUDA_ARCHITECTURES=90); fi
# Each test program is built in one of the two stages (JPCR_TEST_STAGE in CMakeLists.txt): this
# one builds those the sanitizer stage cannot run in time, and all of them when it is skipped.
stage=release
if [ "${JPCR_SKIP_SANITIZERS:-0}" = "1" ]; then stage=all; fi
# shellcheck disable=SC2086
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release "${arch[@]}" -DJPCR_TEST_STAGE=$stage \
  ${JPCR_CMAKE_ARGS:-}
cmake --build "$build" -j"$jobs"
ctest --test-dir "$build" --output-on-failure -j"$jobs"

# Robustness job: ASan+UBSan build of the CPU suite and bounded libFuzzer runs.
if [ "${JPCR_SKIP_SANITIZERS:-0}" != "1" ]; then
  tools/check_sanitizers.sh
fi
