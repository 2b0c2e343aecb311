#!/usr/bin/env bash
# jpcr_node over real Cyclone DDS on loopback, as separate processes: jpcr_dds_play publishes a
# 6-frame 160x120 synthetic sequence (32FC1, lossless) as fast as it can, after three malformed
# depth images from jpcr_test_bad_depth; jpcr_node --method j-ftf rejects those with one log line
# each, processes the 6 good frames and publishes odom, curvature, its sd and path; the final path
# received by jpcr_dds_echo equals jpcr_run's offline trajectory to 1e-9 m. jpcr_run --dds
# publishes the same path, and the sd maps it writes to curvature_sd/. With dds.input_history: keep_all on both sides the player waits for
# the node and nothing is dropped. --idle-timeout and SIGTERM stop the node cleanly; bad command lines
# exit 2 and bad parameters 1. Every wait is bounded.
set -uo pipefail
build=$1 src=$2
bad=$build/tests/tools/jpcr_test_bad_depth
# shellcheck source=node_helpers.sh
source "$src/tests/tools/node_helpers.sh"
# Deep enough histories that no frame or result is dropped while the node computes.
printf 'dds:\n  history_depth: 32\n  image_history_depth: 16\n' > "$tmp/dds.yaml"
dds=(--params "$tmp/dds.yaml" --domain $domain)

expect 0 "wrote 6 frames" -- "$synth" --scene room_spheres --frames 6 --size 160x120 --seed 4 \
  --out "$tmp/seq"

# The sd maps an echo ($1) received equal the ones a run wrote to $2 (the same share with an sd,
# median and maximum, matched by stamp), at least $3 of them.
same_sd() {
  /usr/bin/python3 - "$@" <<'PY'
import array, ast, math, os, sys
def npy(path):  # float32 H x W, little-endian, version 1
    b = open(path, "rb").read()
    n = int.from_bytes(b[8:10], "little")
    head = ast.literal_eval(b[10:10 + n].decode())
    assert head["descr"] == "<f4" and len(head["shape"]) == 2, head
    a = array.array("f"); a.frombytes(b[10 + n:])
    return a
def summary(a):
    v = sorted(x for x in a if not math.isnan(x))
    line = " with_sd=%.1f%%" % (100.0 * len(v) / len(a))
    return line + (" median=%.4g max=%.4g 1/m" % (v[len(v) // 2], v[-1]) if v else "")
want = {round(float(f[:-4]), 6): summary(npy(os.path.join(sys.argv[2], f)))
        for f in os.listdir(sys.argv[2])}
got = {}
for l in open(sys.argv[1]):
    if l.startswith("curvature_sd "):
        stamp = round(float(l.split("stamp=")[1].split()[0]), 6)
        if stamp in got:
            sys.exit("stamp %s received twice" % stamp)
        got[stamp] = l[l.index(" with_sd="):].rstrip("\n")
bad = {k: (v, want.get(k)) for k, v in got.items() if want.get(k) != v}
if bad or len(got) < int(sys.argv[3]):
    sys.exit("%d received, %d wanted at least; differing (echo, file): %s" % (len(got), int(sys.argv[3]), bad))
print("ok: %d published sd maps equal %s" % (len(got), sys.argv[2]))
PY
}

# jpcr_run --method j-ftf --dds on the sequence into $1 with --params $2, while jpcr_dds_echo
# records topic $3 into file $4 (with option $5, or none when it is "") and topic $6 into $7
# (transient local: what was written before discovery completed arrives too).
run_dds_echoing() {
  local out=$1 opts=(--params "$2" --domain $domain) first second
  # shellcheck disable=SC2086  # $5: one option or none
  "$echo_bin" "$3" "${opts[@]}" $5 --timeout 120 > "$4" 2>&1 &
  first=$!; pids+=($first)
  "$echo_bin" "$6" "${opts[@]}" --transient-local --timeout 120 > "$7" 2>&1 &
  second=$!; pids+=($second)
  expect 0 "j-ftf " -- "$run" --dataset "$tmp/seq" --method j-ftf --out "$out" --dds "${opts[@]}" \
    --wait-readers 2 --wait-timeout 60
  sleep 1; kill -INT $first $second; wait_bounded $first 10; wait_bounded $second 10
}

# jpcr_run offline, publishing the same topics (--dds); its path equals its trajectory.txt, and
# the sd maps it publishes are the ones it writes, all 6 of them: jpcr_run waits for the two
# echoes' readers (--wait-readers 2) before its first sample, and the sd echo, transient local,
# gets the maps kept for it even if it matched jpcr_run's writer after the first was written.
run_dds_echoing "$tmp/off" "$tmp/dds.yaml" rt/jpcr/path "$tmp/run_path.txt" --tum \
  rt/jpcr/curvature_sd "$tmp/run_sd.txt"
same_path "$tmp/run_path.txt" "$tmp/off/trajectory.txt" || { echo "FAIL: jpcr_run --dds path"; cat "$tmp/run_path.txt"; fail=1; }
same_sd "$tmp/run_sd.txt" "$tmp/off/curvature_sd" 6 || { echo "FAIL: jpcr_run --dds sd maps"; cat "$tmp/run_sd.txt"; fail=1; }
# dds.curvature_sd: false publishes the maps without their sd (which jpcr_run still writes).
printf 'dds:\n  history_depth: 32\n  image_history_depth: 16\n  curvature_sd: false\n' > "$tmp/no_sd.yaml"
run_dds_echoing "$tmp/off_no_sd" "$tmp/no_sd.yaml" rt/jpcr/curvature "$tmp/no_sd_curv.txt" "" \
  rt/jpcr/curvature_sd "$tmp/no_sd_sd.txt"
n=$(ls "$tmp/off_no_sd/curvature_sd" | wc -l)
maps=$(grep -c "^image .* 32FC2 " "$tmp/no_sd_curv.txt")
if [ "$n" != 6 ] || [ "$maps" = 0 ] || grep -q "^curvature_sd " "$tmp/no_sd_sd.txt"; then
  echo "FAIL: curvature_sd: false: $n sd maps written (want 6), $maps curvature maps received (want some), sd published:"
  cat "$tmp/no_sd_sd.txt"; fail=1
fi

# The round trip: echoes first, then the node, the malformed images, the good frames.
"$echo_bin" rt/jpcr/path "${dds[@]}" --tum --timeout 240 > "$tmp/path.txt" 2>&1 &
path_echo=$!; pids+=($path_echo)
"$echo_bin" rt/jpcr/odom "${dds[@]}" --count 6 --timeout 240 > "$tmp/odom.txt" 2>&1 &
odom_echo=$!; pids+=($odom_echo)
"$echo_bin" rt/jpcr/curvature "${dds[@]}" --count 6 --timeout 240 > "$tmp/curv.txt" 2>&1 &
curv_echo=$!; pids+=($curv_echo)
"$echo_bin" rt/jpcr/curvature_color "${dds[@]}" --count 6 --timeout 240 > "$tmp/color.txt" 2>&1 &
color_echo=$!; pids+=($color_echo)
"$echo_bin" rt/jpcr/keyframe_pose "${dds[@]}" --count 6 --timeout 240 > "$tmp/kf.txt" 2>&1 &
kf_echo=$!; pids+=($kf_echo)
"$echo_bin" rt/jpcr/curvature_sd "${dds[@]}" --count 6 --timeout 240 > "$tmp/sd.txt" 2>&1 &
sd_echo=$!; pids+=($sd_echo)
sleep 1
"$node" "${dds[@]}" --method j-ftf --max-frames 6 --idle-timeout 60 > "$tmp/node.txt" 2> "$tmp/node.err" &
node_pid=$!; pids+=($node_pid)
expect 0 "published 3 malformed" -- "$bad" $domain rt/camera/depth/image_raw 3
expect 0 "published 6 frames" -- "$play" --dataset "$tmp/seq" --encoding 32FC1 \
  --as-fast-as-possible --wait-subscribers 15 "${dds[@]}"
wait_bounded $node_pid 200; rc=$?
if [ $rc != 0 ] || ! grep -q "processed 6 frames, 6 keyframes, 6 curvature maps (0 samples not published); rejected 3 samples, dropped 0 frames, skipped 0 frames; stopped by --max-frames" "$tmp/node.txt"; then
  echo "FAIL: jpcr_node exited $rc"; cat "$tmp/node.txt" "$tmp/node.err"; fail=1
else
  echo "ok: jpcr_node: $(cat "$tmp/node.txt")"
fi
n=$(grep -c "rejected sample" "$tmp/node.err")
[ "$n" = 3 ] || { echo "FAIL: $n rejection lines, want 3"; cat "$tmp/node.err"; fail=1; }
grep -q "jpcr_node: frame 6  keyframes 6" "$tmp/node.err" || { echo "FAIL: progress line"; cat "$tmp/node.err"; fail=1; }
for e in $odom_echo $curv_echo $color_echo $kf_echo $sd_echo; do
  wait_bounded $e 30 || { echo "FAIL: an echo exited $?"; fail=1; }
done
kill -INT $path_echo; wait_bounded $path_echo 10
n=$(grep -c "^odom stamp=.* frame=map child=camera_depth_optical_frame" "$tmp/odom.txt")
[ "$n" = 6 ] || { echo "FAIL: $n of 6 odom"; cat "$tmp/odom.txt"; fail=1; }
n=$(grep -c "cov_diag=\[0 0 0 0 0 0\]" "$tmp/odom.txt")
[ "$n" = 1 ] || { echo "FAIL: $n odom with zero covariance, want 1 (the first)"; cat "$tmp/odom.txt"; fail=1; }
n=$(grep -c "^pose stamp=.* frame=map position=" "$tmp/kf.txt")
[ "$n" = 6 ] || { echo "FAIL: $n of 6 keyframe poses"; cat "$tmp/kf.txt"; fail=1; }
n=$(grep -c "^image .* 160x120 32FC2 .* valid=" "$tmp/curv.txt")
[ "$n" = 6 ] || { echo "FAIL: $n of 6 curvature maps"; cat "$tmp/curv.txt"; fail=1; }
n=$(grep -c "^image .* 160x120 rgb8 .* ok$" "$tmp/color.txt")
[ "$n" = 6 ] || { echo "FAIL: $n of 6 curvature colour maps"; cat "$tmp/color.txt"; fail=1; }
n=$(grep -c "^curvature_sd .* 160x120 32FC1 with_sd=[0-9.]*% median=" "$tmp/sd.txt")
[ "$n" = 6 ] || { echo "FAIL: $n of 6 curvature sd maps"; cat "$tmp/sd.txt"; fail=1; }
# The node computes each sd itself (PipelinePublisher): the same maps as jpcr_run's, whose
# trajectory the node's path equals.
same_sd "$tmp/sd.txt" "$tmp/off/curvature_sd" 6 || { echo "FAIL: jpcr_node's sd maps"; fail=1; }
same_path "$tmp/path.txt" "$tmp/off/trajectory.txt" || { echo "FAIL: node path vs offline"; cat "$tmp/path.txt"; fail=1; }

# dds.input_history: keep_all on both sides, at the default input depth of 2 (the first round
# trip needs 16): the player waits for the J-ftf node, slower than it, and every frame is
# processed, none dropped, with the same path as offline.
printf 'dds:\n  history_depth: 32\n  input_history: keep_all\n' > "$tmp/keep_all.yaml"
keep_all=(--params "$tmp/keep_all.yaml" --domain $domain)
"$echo_bin" rt/jpcr/path "${keep_all[@]}" --tum --timeout 240 > "$tmp/keep_all_path.txt" 2>&1 &
keep_all_echo=$!; pids+=($keep_all_echo)
sleep 1
"$node" "${keep_all[@]}" --method j-ftf --max-frames 6 --idle-timeout 60 > "$tmp/keep_all.txt" 2>&1 &
keep_all_pid=$!; pids+=($keep_all_pid)
expect 0 "published 6 frames" -- "$play" --dataset "$tmp/seq" --encoding 32FC1 \
  --as-fast-as-possible --wait-subscribers 15 "${keep_all[@]}"
expect_node $keep_all_pid 200 "$tmp/keep_all.txt" "processed 6 frames, 6 keyframes.*dropped 0 frames" \
  "keep_all input: the player waits for the node"
kill -INT $keep_all_echo; wait_bounded $keep_all_echo 10
same_path "$tmp/keep_all_path.txt" "$tmp/off/trajectory.txt" ||
  { echo "FAIL: keep_all: node path vs offline"; cat "$tmp/keep_all_path.txt"; fail=1; }

# --idle-timeout after the first frame, and SIGTERM before any, both stop with exit 0. The same
# two frames played again are out of time order: skipped, one line each.
"$node" "${dds[@]}" --method icp-ftf --idle-timeout 6 > "$tmp/idle.txt" 2>&1 &
idle_pid=$!; pids+=($idle_pid)
for _ in 1 2; do
  expect 0 "published 2 frames" -- "$play" --dataset "$tmp/seq" --encoding 32FC1 --frames 0:2 \
    --as-fast-as-possible --wait-subscribers 15 "${dds[@]}"
done
expect_node $idle_pid 60 "$tmp/idle.txt" "processed 2 frames.*skipped 2 frames.*stopped by --idle-timeout" \
  "idle timeout, repeated frames skipped"
n=$(grep -c "skipped an input: frame stamped .* is not after the previous frame" "$tmp/idle.txt")
[ "$n" = 2 ] || { echo "FAIL: $n out-of-order lines, want 2"; cat "$tmp/idle.txt"; fail=1; }
# A step back of more than a second is a new time line (a restarted recording) once 3 frames in
# a row continue it: taken, said once. A single stale frame is skipped (it was taken, and the
# path went back in time), as is a repeated one, and a frame of the line left (a second
# publisher ahead in time: the path went back and forth). Stamps 0, 2, 4, 6, 8 s; played: 8,
# then 2 (stale), 8 (repeated), then 0, 2, 4 (the new line, taken at 4), then 8 (the line left).
# The camera here names its own frame: odom's child frame is the depth's header.frame_id.
printf 'synthetic:\n  trajectory:\n    rate: 0.5\n' > "$tmp/slow.yaml"
expect 0 "wrote 5 frames" -- "$synth" --scene room_spheres --frames 5 --size 160x120 --seed 4 \
  --params "$tmp/slow.yaml" --out "$tmp/slow"
cp "$tmp/dds.yaml" "$tmp/robot1.yaml"
printf '  camera_frame_id: robot1/depth_optical\n' >> "$tmp/robot1.yaml"
"$echo_bin" rt/jpcr/odom "${dds[@]}" --count 2 --timeout 120 > "$tmp/reset_odom.txt" 2>&1 &
reset_echo=$!; pids+=($reset_echo)
"$node" "${dds[@]}" --method icp-ftf --idle-timeout 6 > "$tmp/reset.txt" 2>&1 &
reset_pid=$!; pids+=($reset_pid)
for frames in 4:5/1 1:2/1 4:5/1 0:3/3 4:5/1; do
  expect 0 "published ${frames#*/} frames" -- "$play" --dataset "$tmp/slow" --encoding 32FC1 \
    --frames "${frames%/*}" --as-fast-as-possible --wait-subscribers 15 --params "$tmp/robot1.yaml" \
    --domain $domain
done
expect_node $reset_pid 60 "$tmp/reset.txt" "processed 2 frames.*skipped 5 frames" \
  "a new time line is taken, a stale frame and the line left are not"
grep -q "the stamps jumped by -4 s .*for 3 frames in a row.*taken as a new time line" "$tmp/reset.txt" ||
  { echo "FAIL: no line about the new time line"; cat "$tmp/reset.txt"; fail=1; }
n=$(grep -c "taken as a new time line" "$tmp/reset.txt")
[ "$n" = 1 ] || { echo "FAIL: $n new time lines, want 1"; cat "$tmp/reset.txt"; fail=1; }
wait_bounded $reset_echo 30
n=$(grep -c "^odom .* child=robot1/depth_optical" "$tmp/reset_odom.txt")
[ "$n" = 2 ] || { echo "FAIL: $n of 2 odom in the camera's frame"; cat "$tmp/reset_odom.txt"; fail=1; }
# keep_history: false, an unattended run: J-full windows of 3 (every frame a keyframe) forget
# each final frame, and every keyframe's map is still published. Each final pose is published
# once, in the first path after it became final: together the paths hold every frame's final
# pose, equal to jpcr_run's (the node published only the frames still held: 1 of 6).
printf 'dds:\n  history_depth: 32\n  image_history_depth: 16\npipeline:\n  keep_history: false\n  window: 3\n' \
  > "$tmp/forget.yaml"
expect 0 "j-full " -- "$run" --dataset "$tmp/seq" --method j-full --window 3 --out "$tmp/off_full"
"$echo_bin" rt/jpcr/path "${dds[@]}" --tum --timeout 240 > "$tmp/forget_path.txt" 2>&1 &
forget_echo=$!; pids+=($forget_echo)
"$node" --params "$tmp/forget.yaml" --domain $domain --method j-full --max-frames 6 \
  --idle-timeout 60 > "$tmp/forget.txt" 2>&1 &
forget_pid=$!; pids+=($forget_pid)
expect 0 "published 6 frames" -- "$play" --dataset "$tmp/seq" --encoding 32FC1 \
  --as-fast-as-possible --wait-subscribers 15 "${dds[@]}"
expect_node $forget_pid 200 "$tmp/forget.txt" "processed 6 frames, 6 keyframes, 6 curvature maps" \
  "keep_history false"
kill -INT $forget_echo; wait_bounded $forget_echo 10
same_path "$tmp/forget_path.txt" "$tmp/off_full/trajectory.txt" union ||
  { echo "FAIL: keep_history false: the paths vs jpcr_run"; cat "$tmp/forget_path.txt"; fail=1; }
"$node" "${dds[@]}" > "$tmp/term.txt" 2>&1 &
term_pid=$!; pids+=($term_pid)
sleep 1.5; kill -TERM $term_pid
expect_node $term_pid 20 "$tmp/term.txt" "processed 0 frames.*stopped by signal" "SIGTERM"

# Bad command lines and parameters.
expect 0 "usage: jpcr_node" -- "$node" --help
expect 2 "--method: unknown method 'bundle'" -- "$node" --method bundle
expect 2 "--window must be in" -- "$node" --window 1
expect 2 "--max-frames must be >= 0" -- "$node" --max-frames -1
expect 2 "--max-frames is the front end's" -- "$node" --role backend --max-frames 5
expect 2 "--idle-timeout must be 0..86400 s" -- "$node" --idle-timeout -1
expect 2 "--idle-timeout must be 0..86400 s" -- "$node" --idle-timeout 1e999
expect 2 "--flush-timeout must be 0..86400 s" -- "$node" --flush-timeout inf
expect 2 "--backend-wait must be 0..86400 s" -- "$node" --backend-wait 1e300
expect 2 "domain must be in 0..232" -- "$node" --domain 300
printf 'pipeline:\n  window: 99\n' > "$tmp/bad.yaml"
expect 1 "error: .*window" -- "$node" --params "$tmp/bad.yaml"
expect 1 "error: .*nosuch" -- "$node" --params "$tmp/nosuch.yaml"
# jpcr_run's wait for readers: bounded, then it publishes anyway; its options need --dds.
expect 0 "0 of 1 DDS readers matched; publishing anyway" -- "$run" --dataset "$tmp/seq" \
  --method icp-ftf --frames 0:2 --out "$tmp/no_readers" --dds "${dds[@]}" --wait-readers 1 \
  --wait-timeout 0.3
expect 2 "--wait-readers needs --dds" -- "$run" --dataset "$tmp/seq" --out "$tmp/x" \
  --wait-readers 1
expect 2 "--wait-readers must be 0..1000" -- "$run" --dataset "$tmp/seq" --out "$tmp/x" --dds \
  --wait-readers -1
expect 2 "--wait-timeout must be 0..86400 s" -- "$run" --dataset "$tmp/seq" --out "$tmp/x" \
  --dds --wait-timeout nan
exit $fail
