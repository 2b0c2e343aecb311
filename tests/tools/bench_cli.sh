#!/usr/bin/env bash
# The Google Benchmark tools' command line (benchmark_main.hpp): --help says what each times and
# exits 0, an unknown argument is a usage error (exit 2), and the library's own options pass
# through (--benchmark_list_tests lists without timing anything).
set -uo pipefail
build=$1
source "$(dirname "$0")/expect.sh"
found=0
for tool in bench_curvature bench_joint bench_synthetic bench_icp_bundle; do
  bin=$build/tools/bench/$tool
  [ -x "$bin" ] || continue  # bench_icp_bundle needs Ceres (not in JPCR_CORE_ONLY builds)
  found=1
  expect 0 "usage: $tool \[Google Benchmark options\]" -- "$bin" --help
  expect 0 "Times " -- "$bin" -h
  expect 2 "$tool: unknown argument '--bogus'" -- "$bin" --bogus
  expect 2 "Try '$tool --help'" -- "$bin" --benchmark_filter=BM_ stray
  expect 0 "^BM_" -- "$bin" --benchmark_list_tests=true
done
[ "$found" = 1 ] || { echo "no benchmark tool built in $build/tools/bench"; exit 1; }
exit $fail
