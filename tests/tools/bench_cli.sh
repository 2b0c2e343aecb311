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
# jpcr_long_run's command-line mistakes are usage errors too, named by their option.
long_run=$build/tools/bench/jpcr_long_run
if [ -x "$long_run" ]; then
  expect 2 "--width and --height must be in 1..16384 px" -- "$long_run" --frames 20 --width 0
  expect 2 "--noise: noise 'range:200'" -- "$long_run" --frames 20 --noise range:200
  expect 2 "--seed must be a non-negative integer" -- "$long_run" --frames 20 --seed -1
fi
exit $fail
