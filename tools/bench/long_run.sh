#!/usr/bin/env bash
# The long run of issue 11: 5000 synthetic frames at 160x120 through the whole pipeline, with RSS
# sampled and ms per frame at start and end (tools/bench/long_run.cpp). Builds jpcr_long_run when
# needed. Exit status 1 when RSS grew by 5 % or more after the warm-up, or the time per frame grew.
#   tools/bench/long_run.sh [BUILD_DIR] [jpcr_long_run options, e.g. --frames 500]
set -euo pipefail
cd "$(dirname "$0")/../.."
build=${1:-build}
shift || true
cmake --build "$build" -j2 --target jpcr_long_run > /dev/null
"$build/tools/bench/jpcr_long_run" --frames 5000 "$@"
