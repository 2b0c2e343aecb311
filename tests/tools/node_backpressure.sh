#!/usr/bin/env bash
# The split deployment when the back end falls behind: its reader holds dds.keyframe_queue
# unread keyframes (here 1), so memory stays bounded, and the front end waits for it instead of
# queueing keyframes without end. A 10-frame 320x240 sequence where every frame is a keyframe:
# the front end tracks a frame in tens of ms, the back end's J-ftf takes about ten times longer,
# so the front end gets ahead, says that it waits, and every keyframe still arrives: the final
# path equals jpcr_run's to 1e-9 (without the queue limit the back end's reader would take them
# all and the front end would never wait). Then SIGINT to a front end that waits (the back end
# stopped with SIGSTOP): the keyframe it gives up reaches the back end as a tracked frame in the
# end of stream, so the back end still ends cleanly with every frame.
set -uo pipefail
build=$1 src=$2
# shellcheck source=node_helpers.sh
source "$src/tests/tools/node_helpers.sh"
# A keyframe every 1 cm: every frame of the walk is one.
split_params 0.01
dds=(--params "$tmp/params.yaml" --domain $domain)
frames=10
expect 0 "wrote $frames frames" -- "$synth" --scene room_spheres --frames $frames --size 320x240 \
  --seed 4 --out "$tmp/seq"
expect 0 "wrote $frames poses" -- "$run" --dataset "$tmp/seq" --params "$tmp/params.yaml" \
  --method j-ftf --out "$tmp/off"

# Starts a back end and a front end (j-ftf), waits for discovery, stops the back end if $2 is
# "stop" and plays the sequence; returns once the front end says it waits for the back end (or
# fails after 120 s).
start_behind() {
  "$node" --role backend "${dds[@]}" --method j-ftf --idle-timeout 120 > "$tmp/back$1.txt" \
    2> "$tmp/back$1.err" &
  back_pid=$!; pids+=($back_pid)
  "$node" --role frontend "${dds[@]}" --method j-ftf --max-frames $frames --idle-timeout 60 \
    > "$tmp/front$1.txt" 2> "$tmp/front$1.err" &
  front_pid=$!; pids+=($front_pid)
  sleep 3
  [ "$2" = stop ] && kill -STOP $back_pid
  expect 0 "published $frames frames" -- "$play" --dataset "$tmp/seq" --encoding 32FC1 \
    --as-fast-as-possible --wait-subscribers 15 "${dds[@]}"
  for _ in $(seq 1200); do grep -q "waiting for it" "$tmp/front$1.err" && return; sleep 0.1; done
  echo "FAIL: the front end never waited for the back end"; cat "$tmp/front$1.err"; fail=1
}

"$echo_bin" rt/jpcr/path "${dds[@]}" --tum --timeout 300 > "$tmp/path.txt" 2>&1 &
path_echo=$!; pids+=($path_echo)
start_behind 1 run
grep -h "waiting for it" "$tmp/front1.err" | head -1
expect_node $front_pid 120 "$tmp/front1.txt" \
  "processed $frames frames, sent $frames keyframes and the end of stream; rejected 0 samples, dropped 0 frames" \
  "front end, paced by the back end"
expect_node $back_pid 240 "$tmp/back1.txt" \
  "refined $frames keyframes of $frames frames.*stopped by end of stream" "back end"
kill -INT $path_echo; wait_bounded $path_echo 10
same_path "$tmp/path.txt" "$tmp/off/trajectory.txt" ||
  { echo "FAIL: paced split path vs single process"; cat "$tmp/path.txt"; fail=1; }

# SIGINT while the front end waits: it gives the keyframe up and ends the stream with it.
start_behind 2 stop
kill -INT $front_pid
sleep 1
kill -CONT $back_pid
expect_node $front_pid 60 "$tmp/front2.txt" "sent .* keyframes and the end of stream.*stopped by signal" \
  "front end, stopped while waiting"
sent=$(sed -n 's/.*sent \([0-9]*\) keyframes.*/\1/p' "$tmp/front2.txt")
processed=$(sed -n 's/^processed \([0-9]*\) frames.*/\1/p' "$tmp/front2.txt")
if [ -n "$sent" ] && [ -n "$processed" ] && [ "$sent" -lt "$processed" ]; then
  echo "ok: $processed frames, $sent keyframes sent: the one given up went as a tracked frame"
else
  echo "FAIL: want fewer keyframes sent than frames processed"; cat "$tmp/front2.txt"; fail=1
fi
expect_node $back_pid 240 "$tmp/back2.txt" \
  "refined $sent keyframes of $processed frames.*stopped by end of stream" "back end after it"
exit ${fail:-0}
