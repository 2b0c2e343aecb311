#!/usr/bin/env bash
# Runs every libFuzzer target of a JPCR_FUZZ=ON build for a bounded time, starting from the seeds
# in tests/fuzz/corpus/<target>/, and prints the executions per target and in total.
#   tools/fuzz.sh BUILD_DIR [SECONDS_PER_TARGET]   (default 30)
# Exit status: non-zero when a target crashed (the reproducer is left in BUILD_DIR/fuzz-artifacts)
# or when BUILD_DIR has no fuzz target (a wrong directory, or a build without JPCR_FUZZ=ON).
set -euo pipefail
build=${1:?usage: tools/fuzz.sh BUILD_DIR [SECONDS]}
build=$(cd "$build" 2>/dev/null && pwd) || { echo "fuzz: $1 is not a directory" >&2; exit 2; }
cd "$(dirname "$0")/.."
seconds=${2:-30}
artifacts=$build/fuzz-artifacts
mkdir -p "$artifacts"
total=0
status=0
targets=0
for bin in "$build"/tests/fuzz/fuzz_*; do
  [ -x "$bin" ] || continue
  targets=$((targets + 1))
  name=$(basename "$bin")
  work=$(mktemp -d)
  log=$work/log
  if ! "$bin" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len=65536 \
      -print_final_stats=1 -artifact_prefix="$artifacts/$name-" "$work" "tests/fuzz/corpus/$name" \
      > "$log" 2>&1; then
    echo "fuzz: $name FAILED"; tail -40 "$log"; status=1
  fi
  runs=$(grep -E '^stat::number_of_executed_units' "$log" | awk '{print $2}' | tail -1 || true)
  runs=${runs:-0}
  total=$((total + runs))
  printf 'fuzz: %-18s %10d executions in %ss, corpus %s inputs\n' "$name" "$runs" "$seconds" "$(ls "$work" | wc -l)"
  rm -rf "$work"
done
echo "fuzz: $total executions in total"
if [ $targets = 0 ]; then
  echo "fuzz: no fuzz target in $build/tests/fuzz (configure with -DJPCR_FUZZ=ON)" >&2
  exit 1
fi
exit $status
