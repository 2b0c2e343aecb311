#!/usr/bin/env bash
# Sustained frame rate of jpcr_dds_play --as-fast-as-possible -> jpcr_node --method icp-ftf (the
# front end alone) over Cyclone DDS on loopback, at 640x480 and 320x240 (synthetic sequences,
# 16UC1 like a ROS depth camera). For each size it runs the node three times:
#   keep last 2    the default input QoS (dds.image_history_depth 2): the node takes the newest
#                  frames and drops, counts and logs the others, as a live node should
#   keep last N    a queue as deep as the sequence: nothing is dropped, the node's own rate
#   keep all 2     dds.input_history: keep_all on both sides, depth 2: the player waits for the
#                  node, nothing is dropped, memory bounded by 2 images
# and prints one table row per run: frames published and the player's rate, frames the node
# processed and its rate (first arrival to last frame done), frames it reported dropped, and
# frames unaccounted for (published - processed - dropped; 0 unless DDS itself lost some).
#
#   tools/bench/bench_dds_rate.sh [BUILD_DIR] [FRAMES]     (default build, 300)
set -uo pipefail
src=$(cd "$(dirname "$0")/../.." && pwd)
build=${1:-$src/build}
frames=${2:-300}
node=$build/tools/jpcr_node
play=$build/tools/jpcr_dds_play
synth=$build/tools/jpcr_synth
for p in "$node" "$play" "$synth"; do
  [ -x "$p" ] || { echo "bench_dds_rate: $p not built" >&2; exit 1; }
done
tmp=$(mktemp -d)
node_pid=
cleanup() {
  [ -n "$node_pid" ] && kill -TERM "$node_pid" 2>/dev/null
  rm -rf "$tmp"
}
trap cleanup EXIT
export CYCLONEDDS_URI="file://$src/configs/cyclonedds_loopback.xml"
domain=$(( $$ % 200 + 11 ))

# One run: size, queue depth, input history (keep_last | keep_all). Prints a table row.
run() {
  local size=$1 depth=$2 history=$3 seq=$tmp/seq_$1
  local queue="${history/_/ } $depth"
  printf 'dds:\n  image_history_depth: %d\n  input_history: %s\n' "$depth" "$history" \
    > "$tmp/dds.yaml"
  local dds=(--params "$tmp/dds.yaml" --domain $domain)
  "$node" "${dds[@]}" --method icp-ftf --idle-timeout 3 > "$tmp/node.txt" 2> "$tmp/node.err" &
  node_pid=$!
  "$play" --dataset "$seq" --encoding 16UC1 --as-fast-as-possible --wait-subscribers 15 \
    "${dds[@]}" > "$tmp/play.txt" 2> "$tmp/play.err" || { cat "$tmp/play.err" >&2; exit 1; }
  wait "$node_pid" || { cat "$tmp/node.err" >&2; exit 1; }
  node_pid=
  # published 300 frames in 1.2 s (250 frames/s) on ...
  local published play_rate processed node_rate dropped
  published=$(sed -n 's/^published \([0-9]*\) frames.*/\1/p' "$tmp/play.txt")
  play_rate=$(sed -n 's/^published .* (\([0-9.]*\) frames\/s).*/\1/p' "$tmp/play.txt")
  processed=$(sed -n 's/^processed \([0-9]*\) frames.*/\1/p' "$tmp/node.txt")
  dropped=$(sed -n 's/.*dropped \([0-9]*\) frames.*/\1/p' "$tmp/node.txt")
  node_rate=$(sed -n 's/^jpcr_node: [0-9]* frames in .* (\([0-9.]*\)\/s)$/\1/p' "$tmp/node.err")
  # Why frames went unaccounted, if any did: the node's own lines about them.
  grep -h "lost in transport\|skipped an input" "$tmp/node.err" | sed "s/^/$size $queue: /" \
    >> "$tmp/notes"
  printf '| %-7s | %-13s | %9s | %10.0f | %9s | %8s | %7s | %12s |\n' "$size" \
    "$queue" "$published" "$play_rate" "$processed" "$node_rate" "$dropped" \
    $((published - processed - dropped))
}

echo "jpcr_dds_play --as-fast-as-possible -> jpcr_node --method icp-ftf, loopback, $frames frames"
echo "($(nproc) cores, $(uname -m), load average $(cut -d" " -f1-3 /proc/loadavg) at the start)"
echo
echo "| size    | input queue   | published | publish/s  | processed | node f/s | dropped | unaccounted |"
echo "|---------|---------------|-----------|------------|-----------|----------|---------|-------------|"
for size in 640x480 320x240; do
  "$synth" --scene room_spheres --frames "$frames" --size "$size" --seed 4 --out "$tmp/seq_$size" \
    > /dev/null 2>&1 || { echo "bench_dds_rate: jpcr_synth failed" >&2; exit 1; }
  run "$size" 2 keep_last
  run "$size" "$frames" keep_last
  run "$size" 2 keep_all
done
[ -s "$tmp/notes" ] && { echo; cat "$tmp/notes"; }
exit 0
