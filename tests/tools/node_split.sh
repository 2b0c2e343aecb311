#!/usr/bin/env bash
# The split deployment over real Cyclone DDS on loopback, as three processes: jpcr_dds_play
# publishes an 8-frame 160x120 synthetic sequence (32FC1, lossless); jpcr_node --role frontend
# tracks it and sends keyframes (depth + pose + the poses of the frames in between) to
# jpcr_node --role backend, which refines them (--method pipeline, window 2: J-ftf per keyframe
# pair and J-full per window, with non-keyframes re-anchored) and publishes the path. The final
# path equals jpcr_run's single-process trajectory of the same data to 1e-9 m (and 1e-9 in the
# quaternion): both processes run the same PipelineFrontEnd / PipelineBackEnd code on the same
# floats; the only difference is the poses' trip through a geometry_msgs quaternion (~1e-16).
# The front end's end of stream stops the back end; SIGINT stops both cleanly. Every wait is
# bounded.
set -uo pipefail
build=$1 src=$2
# shellcheck source=node_helpers.sh
source "$src/tests/tools/node_helpers.sh"
# A keyframe every 2 cm so that 8 frames of the walk make keyframes and frames between them. The
# back-end queue of one keyframe may make the front end wait (how often depends on timing): no
# keyframe may be lost either way.
split_params 0.02
dds=(--params "$tmp/params.yaml" --domain $domain)
method=(--method pipeline --window 2)
frames=8

expect 0 "wrote $frames frames" -- "$synth" --scene room_spheres --frames $frames --size 160x120 \
  --seed 4 --out "$tmp/seq"
# The single process, offline.
expect 0 "wrote $frames poses" -- "$run" --dataset "$tmp/seq" --params "$tmp/params.yaml" \
  "${method[@]}" --out "$tmp/off"
n=$(grep -c '"icp_verdict": "ok"' "$tmp/off/report.json")
[ "$n" = $frames ] || { echo "FAIL: the front end aligned $n of $frames frames"; fail=1; }
keyframes=$(grep -vc "^#" "$tmp/off/keyframes.txt")
# Both kinds of frame must be present for the test to mean something: the pose of a keyframe
# comes from the back end's refinement, that of a non-keyframe from its re-anchoring.
if [ "$keyframes" -lt 2 ] || [ "$keyframes" -ge $frames ]; then
  echo "FAIL: the single process made $keyframes keyframes of $frames frames; want some of each"
  fail=1
fi

"$echo_bin" rt/jpcr/path "${dds[@]}" --tum --timeout 240 > "$tmp/path.txt" 2>&1 &
path_echo=$!; pids+=($path_echo)
"$echo_bin" rt/jpcr/keyframe "${dds[@]}" --count $((keyframes + 1)) --timeout 240 \
  > "$tmp/kf.txt" 2>&1 &
kf_echo=$!; pids+=($kf_echo)
"$echo_bin" rt/jpcr/odom "${dds[@]}" --count $frames --timeout 240 > "$tmp/odom.txt" 2>&1 &
odom_echo=$!; pids+=($odom_echo)
"$node" --role backend "${dds[@]}" "${method[@]}" --idle-timeout 120 > "$tmp/back.txt" \
  2> "$tmp/back.err" &
back_pid=$!; pids+=($back_pid)
"$node" --role frontend "${dds[@]}" "${method[@]}" --max-frames $frames --idle-timeout 60 \
  > "$tmp/front.txt" 2> "$tmp/front.err" &
front_pid=$!; pids+=($front_pid)
sleep 1
expect 0 "published $frames frames" -- "$play" --dataset "$tmp/seq" --encoding 32FC1 \
  --as-fast-as-possible --wait-subscribers 15 "${dds[@]}"
wait_bounded $front_pid 60; rc=$?
want="processed $frames frames, sent $keyframes keyframes and the end of stream; rejected 0 samples, dropped 0 frames, skipped 0 frames; stopped by --max-frames"
if [ $rc != 0 ] || ! grep -qF "$want" "$tmp/front.txt"; then
  echo "FAIL: front end exited $rc"; cat "$tmp/front.txt" "$tmp/front.err"; fail=1
else
  echo "ok: front end: $(cat "$tmp/front.txt")"
fi
wait_bounded $back_pid 200; rc=$?
want="refined $keyframes keyframes of $frames frames, $keyframes curvature maps (0 samples not published); rejected 0 samples, skipped 0 messages; stopped by end of stream"
if [ $rc != 0 ] || ! grep -qF "$want" "$tmp/back.txt"; then
  echo "FAIL: back end exited $rc"; cat "$tmp/back.txt" "$tmp/back.err"; fail=1
else
  echo "ok: back end: $(cat "$tmp/back.txt")"
fi
for e in $kf_echo $odom_echo; do
  wait_bounded $e 30 || { echo "FAIL: an echo exited $?"; fail=1; }
done
kill -INT $path_echo; wait_bounded $path_echo 10
n=$(grep -c "^keyframe .* depth 160x120 32FC1" "$tmp/kf.txt")
[ "$n" = "$keyframes" ] || { echo "FAIL: $n of $keyframes keyframes"; cat "$tmp/kf.txt"; fail=1; }
grep -q "frame_index=$frames tracked=.* end_of_stream" "$tmp/kf.txt" ||
  { echo "FAIL: no end of stream"; cat "$tmp/kf.txt"; fail=1; }
n=$(grep -c "^odom stamp=" "$tmp/odom.txt")
[ "$n" = $frames ] || { echo "FAIL: $n of $frames odom"; cat "$tmp/odom.txt"; fail=1; }
same_path "$tmp/path.txt" "$tmp/off/trajectory.txt" ||
  { echo "FAIL: split path vs single process"; cat "$tmp/path.txt"; fail=1; }

# SIGINT to the front end before any frame: it sends the end of stream, which stops the back
# end; SIGTERM stops a back end that waits.
"$node" --role backend "${dds[@]}" > "$tmp/back2.txt" 2>&1 &
back_pid=$!; pids+=($back_pid)
"$node" --role frontend "${dds[@]}" > "$tmp/front2.txt" 2>&1 &
front_pid=$!; pids+=($front_pid)
sleep 1.5; kill -INT $front_pid; wait_bounded $front_pid 20; rc=$?
grep -q "processed 0 frames.*stopped by signal" "$tmp/front2.txt" && [ $rc = 0 ] ||
  { echo "FAIL: front end SIGINT: exit $rc"; cat "$tmp/front2.txt"; fail=1; }
wait_bounded $back_pid 20; rc=$?
grep -q "refined 0 keyframes of 0 frames.*stopped by end of stream" "$tmp/back2.txt" && [ $rc = 0 ] ||
  { echo "FAIL: back end after the front end's SIGINT: exit $rc"; cat "$tmp/back2.txt"; fail=1; }
"$node" --role backend "${dds[@]}" > "$tmp/back3.txt" 2>&1 &
back_pid=$!; pids+=($back_pid)
sleep 1.5; kill -TERM $back_pid; wait_bounded $back_pid 20; rc=$?
grep -q "stopped by signal" "$tmp/back3.txt" && [ $rc = 0 ] ||
  { echo "FAIL: back end SIGTERM: exit $rc"; cat "$tmp/back3.txt"; fail=1; }

# Ctrl-C under a launcher arrives twice (from the terminal and from the launcher): two SIGINTs
# 0.3 s apart still stop the front end cleanly, here while its shutdown waits up to
# --flush-timeout (3 s) for a stopped back end (the second SIGINT used to kill it).
"$node" --role backend "${dds[@]}" > "$tmp/back6.txt" 2>&1 &
back_pid=$!; pids+=($back_pid)
"$node" --role frontend "${dds[@]}" --flush-timeout 3 > "$tmp/front6.txt" 2>&1 &
front_pid=$!; pids+=($front_pid)
sleep 1.5; kill -STOP $back_pid
kill -INT $front_pid; sleep 0.3; kill -INT $front_pid
wait_bounded $front_pid 30; rc=$?
kill -CONT $back_pid; kill -TERM $back_pid; wait_bounded $back_pid 20
grep -q "processed 0 frames.*stopped by signal" "$tmp/front6.txt" && [ $rc = 0 ] ||
  { echo "FAIL: front end after two quick SIGINTs: exit $rc"; cat "$tmp/front6.txt"; fail=1; }

# A back end started after the front end sent its first keyframes cannot chain the later ones:
# it names the lost keyframes, publishes what it has and exits 1 (it used to skip every later
# message, the end of stream included, and never stop).
"$node" --role frontend "${dds[@]}" "${method[@]}" --backend-wait 0 --max-frames $frames \
  --idle-timeout 60 > "$tmp/front4.txt" 2>&1 &
front_pid=$!; pids+=($front_pid)
sleep 1
expect 0 "published 4 frames" -- "$play" --dataset "$tmp/seq" --encoding 32FC1 --frames 0:4 \
  --as-fast-as-possible --wait-subscribers 15 "${dds[@]}"
for _ in $(seq 600); do grep -q "jpcr_node: frame 4 " "$tmp/front4.txt" && break; sleep 0.1; done
"$node" --role backend "${dds[@]}" "${method[@]}" --idle-timeout 60 > "$tmp/back4.txt" 2>&1 &
back_pid=$!; pids+=($back_pid)
sleep 1.5
expect 0 "published 4 frames" -- "$play" --dataset "$tmp/seq" --encoding 32FC1 --frames 4:8 \
  --as-fast-as-possible --wait-subscribers 15 "${dds[@]}"
wait_bounded $front_pid 60
wait_bounded $back_pid 60; rc=$?
if [ $rc = 1 ] && grep -q "error: keyframe message for frames .* keyframes were lost" "$tmp/back4.txt" &&
    grep -q "stopped by a lost keyframe" "$tmp/back4.txt"; then
  echo "ok: a back end that missed keyframes stops: $(grep error "$tmp/back4.txt")"
else
  echo "FAIL: late back end: exit $rc"; cat "$tmp/front4.txt" "$tmp/back4.txt"; fail=1
fi

# Another reader of the keyframe topic (an echo, a recorder) is no back end: it neither counts as
# one for --backend-wait nor keeps the front end waiting at the end (it used to, until the echo
# exited).
"$echo_bin" rt/jpcr/keyframe "${dds[@]}" --timeout 240 > "$tmp/kf5.txt" 2>&1 &
kf_echo=$!; pids+=($kf_echo)
"$node" --role frontend "${dds[@]}" "${method[@]}" --backend-wait 1 --max-frames 4 \
  --idle-timeout 60 > "$tmp/front5.txt" 2> "$tmp/front5.err" &
front_pid=$!; pids+=($front_pid)
sleep 1
expect 0 "published 4 frames" -- "$play" --dataset "$tmp/seq" --encoding 32FC1 --frames 0:4 \
  --as-fast-as-possible --wait-subscribers 15 "${dds[@]}"
wait_bounded $front_pid 30; rc=$?
if [ $rc = 0 ] && grep -q "no back end on rt/jpcr/keyframe" "$tmp/front5.err" &&
    ! grep -q "waiting for the back end to finish" "$tmp/front5.err"; then
  echo "ok: an echo on the keyframe topic is no back end: $(cat "$tmp/front5.txt")"
else
  echo "FAIL: front end with an echo on its keyframes: exit $rc"
  cat "$tmp/front5.txt" "$tmp/front5.err"; fail=1
fi
kill -INT $kf_echo; wait_bounded $kf_echo 10

# A side killed mid-stream (kill -9: no end of stream, no goodbye; Cyclone unmatches it when its
# lease runs out, 10 s): the back end finishes what it has and exits 1 naming the cause; the
# front end stops sending keyframes and exits 1 (both used to wait for ever or report success).
# Each is killed once the back end has refined the first keyframe, before the front end's
# --idle-timeout (15 s after its last frame) would end the stream. (After its end of stream the
# front end cannot tell a back end that crashed from one that finished: both go.)
dds2=(--params "$tmp/params.yaml" --domain $((domain + 1)))
for victim in back front; do
  "$node" --role backend "${dds2[@]}" "${method[@]}" > "$tmp/gone_back.txt" 2>&1 &
  back_pid=$!; pids+=($back_pid)
  sleep 1
  "$node" --role frontend "${dds2[@]}" "${method[@]}" --idle-timeout 15 > "$tmp/gone_front.txt" 2>&1 &
  front_pid=$!; pids+=($front_pid)
  sleep 1
  expect 0 "published 4 frames" -- "$play" --dataset "$tmp/seq" --encoding 32FC1 --frames 0:4 \
    --as-fast-as-possible --wait-subscribers 15 "${dds2[@]}"
  for _ in $(seq 300); do grep -q "keyframe 1 " "$tmp/gone_back.txt" && break; sleep 0.1; done
  if [ $victim = back ]; then
    kill -KILL $back_pid; wait_bounded $front_pid 60; rc=$?
    out=$tmp/gone_front.txt want="went away; of the .* keyframes sent, those after it stopped are lost"
  else
    kill -KILL $front_pid; wait_bounded $back_pid 60; rc=$?
    out=$tmp/gone_back.txt want="error: the front end went away after .* frames without its end of stream"
  fi
  if [ $rc = 1 ] && grep -q "$want" "$out"; then
    echo "ok: the $victim end killed: $(grep -m1 "$want" "$out")"
  else
    echo "FAIL: the $victim end killed: the other exited $rc"; cat "$tmp/gone_back.txt" "$tmp/gone_front.txt"; fail=1
  fi
  kill -KILL $back_pid $front_pid 2>/dev/null; wait $back_pid $front_pid 2>/dev/null
done

expect 2 "--role must be all, frontend or backend, got 'middle'" -- "$node" --role middle
expect 2 "--backend-wait must be 0..86400 s" -- "$node" --role frontend --backend-wait -1
# A held-back (keep_all) input would block the acknowledgements the front end's keyframes wait for.
printf 'dds:\n  input_history: keep_all\n' > "$tmp/keep_all.yaml"
expect 1 "keep_all cannot pace a split front end" -- "$node" --role frontend \
  --params "$tmp/keep_all.yaml" --domain $domain
exit ${fail:-0}
