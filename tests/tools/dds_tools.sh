#!/usr/bin/env bash
# jpcr_dds_play and jpcr_dds_echo over real Cyclone DDS on loopback, as separate processes: the
# TUM test frames played as 16UC1 arrive at jpcr_dds_echo with their camera_info; SIGINT stops
# the player cleanly; bad command lines and inputs give one clear message and the documented code.
set -uo pipefail
build=$1 src=$2 data=$3
play=$build/tools/jpcr_dds_play
echo_bin=$build/tools/jpcr_dds_echo
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
# shellcheck source=expect.sh
source "$src/tests/tools/expect.sh"
export CYCLONEDDS_URI="file://$src/configs/cyclonedds_loopback.xml"
domain=$(( $$ % 200 + 1 ))
tum=$data/tum_fr1_xyz_20
cam=$src/configs/tum_fr1.yaml

# Depth and camera_info of frames 3..7 reach two echo processes started first.
"$echo_bin" rt/camera/depth/image_raw --domain $domain --count 5 --timeout 30 > "$tmp/depth.txt" 2>&1 &
echo_depth=$!
"$echo_bin" rt/camera/depth/camera_info --domain $domain --count 5 --timeout 30 > "$tmp/info.txt" 2>&1 &
echo_info=$!
expect 0 "published 5 frames" -- "$play" --dataset "$tum" --config "$cam" --frames 3:8 \
  --as-fast-as-possible --domain $domain --wait-subscribers 15
wait $echo_depth || { echo "FAIL: echo of depth exited $?"; cat "$tmp/depth.txt"; fail=1; }
wait $echo_info || { echo "FAIL: echo of camera_info exited $?"; cat "$tmp/info.txt"; fail=1; }
n=$(grep -c "^image stamp=1305031102\.[0-9]* frame=camera_depth_optical_frame 640x480 16UC1 step=1280 bytes=614400 valid=" "$tmp/depth.txt")
[ "$n" = 5 ] || { echo "FAIL: $n of 5 depth lines"; cat "$tmp/depth.txt"; fail=1; }
# The stamp as the dataset writes it (the nearest nanosecond to its double was 1305031102.262885...).
grep -q "stamp=1305031102.262886000 " "$tmp/depth.txt" || { echo "FAIL: frame 3 stamp"; cat "$tmp/depth.txt"; fail=1; }
n=$(grep -c "^camera_info .* 640x480 fx=517.300 fy=516.500 cx=318.600 cy=255.300 model=plumb_bob$" "$tmp/info.txt")
[ "$n" = 5 ] || { echo "FAIL: $n of 5 camera_info lines"; cat "$tmp/info.txt"; fail=1; }
echo "ok: 5 depth images and 5 camera_infos received from jpcr_dds_play"

# A best-effort publisher (a ROS sensor-data camera) sends the reliable echo nothing: it says so,
# with the way out (it printed only "received 0 of 1"). The player's volatile topic sends a
# --transient-local echo nothing either, for its durability.
printf 'dds:\n  input_reliability: best_effort\n' > "$tmp/best_effort.yaml"
"$echo_bin" rt/camera/depth/image_raw --domain $domain --count 1 --timeout 8 > "$tmp/mismatch.txt" 2>&1 &
echo_mismatch=$!
"$echo_bin" rt/camera/depth/image_raw --domain $domain --count 1 --timeout 8 --best-effort \
  --transient-local > "$tmp/durability.txt" 2>&1 &
echo_durability=$!
# (about 5 s of frames: the echo meets the publisher while it plays; it matches no subscriber)
"$play" --params "$tmp/best_effort.yaml" --dataset "$tum" --config "$cam" --frames 0:8 --rate 0.05 \
  --domain $domain --wait-subscribers 0 > "$tmp/best_effort_play.txt" 2>&1
wait $echo_mismatch; rc=$?
if [ "$rc" = 1 ] && grep -q "offer a QoS this reader cannot match (reliability: a best-effort publisher needs --best-effort)" "$tmp/mismatch.txt"; then
  echo "ok: a QoS mismatch is named: $(grep QoS "$tmp/mismatch.txt")"
else
  echo "FAIL: QoS mismatch: exit $rc"; cat "$tmp/mismatch.txt" "$tmp/best_effort_play.txt"; fail=1
fi
wait $echo_durability; rc=$?
if [ "$rc" = 1 ] && grep -q "offer a QoS this reader cannot match (durability: a volatile publisher keeps nothing for --transient-local)" "$tmp/durability.txt"; then
  echo "ok: a durability mismatch is named: $(grep QoS "$tmp/durability.txt")"
else
  echo "FAIL: durability mismatch: exit $rc"; cat "$tmp/durability.txt" "$tmp/best_effort_play.txt"; fail=1
fi

# At the recorded rate, SIGINT stops the player between frames with exit 0.
"$play" --dataset "$tum" --config "$cam" --rate 0.05 --domain $domain --wait-subscribers 0 \
  > "$tmp/slow.txt" 2>&1 &
slow=$!
# Its first line comes after the handler is installed (before it, a background job ignores
# SIGINT); wait for it, bounded, on a busy machine.
for ((i = 0; i < 300; ++i)); do grep -q "^jpcr_dds_play: " "$tmp/slow.txt" && break; sleep 0.1; done
sleep 0.5; kill -INT $slow; wait $slow; rc=$?
if [ "$rc" != 0 ] || ! grep -q "stopped by signal" "$tmp/slow.txt"; then
  echo "FAIL: SIGINT: exit $rc"; cat "$tmp/slow.txt"; fail=1
else
  echo "ok: SIGINT stops jpcr_dds_play: $(tail -1 "$tmp/slow.txt")"
fi

# SIGINT also ends the wait for subscribers (none here): it ran the whole --wait-subscribers.
"$play" --dataset "$tum" --config "$cam" --domain $domain --wait-subscribers 60 \
  > "$tmp/waiting.txt" 2>&1 &
waiting=$!
for ((i = 0; i < 300; ++i)); do grep -q "^jpcr_dds_play: " "$tmp/waiting.txt" && break; sleep 0.1; done
sleep 0.5; start=$SECONDS; kill -INT $waiting; wait $waiting; rc=$?
if [ "$rc" != 0 ] || [ $((SECONDS - start)) -gt 10 ] || grep -q "publishing anyway" "$tmp/waiting.txt"; then
  echo "FAIL: SIGINT while waiting for subscribers: exit $rc after $((SECONDS - start)) s"
  cat "$tmp/waiting.txt"; fail=1
else
  echo "ok: SIGINT ends the wait for subscribers: $(tail -1 "$tmp/waiting.txt")"
fi

# Nothing published: the wait is bounded and fewer samples than --count is an error.
expect 1 "received 0 of 1 samples on rt/jpcr/odom within 0.5 s" -- \
  "$echo_bin" rt/jpcr/odom --domain $domain --count 1 --timeout 0.5
expect 0 "" -- "$echo_bin" rt/jpcr/path --domain $domain --timeout 0.2

# Bad command lines and inputs.
expect 0 "usage: jpcr_dds_play" -- "$play" --help
expect 0 "usage: jpcr_dds_echo TOPIC" -- "$echo_bin" --help
expect 2 "dataset is required" -- "$play"
expect 2 "missing argument TOPIC" -- "$echo_bin"
expect 2 "encoding: unknown depth encoding 'bgr8'" -- "$play" --dataset "$tum" --encoding bgr8
expect 2 "frames '5:2' selects no frame" -- "$play" --dataset "$tum" --config "$cam" --frames 5:2
expect 2 "frames expects FIRST:LAST" -- "$play" --dataset "$tum" --config "$cam" --frames x7
# A bare N is frame N alone, as in jpcr_run and jpcr_curvature.
expect 0 "frames 7..7" -- "$play" --dataset "$tum" --config "$cam" --frames 7 --as-fast-as-possible \
  --wait-subscribers 0
expect 2 "rate must be in 0.001..1e6" -- "$play" --dataset "$tum" --rate 0
expect 2 "rate must be in 0.001..1e6" -- "$play" --dataset "$tum" --rate 1e-12
expect 2 "wait-subscribers must be 0..86400" -- "$play" --dataset "$tum" --wait-subscribers 1e10
expect 2 "timeout must be 0..86400 s (0: no limit)" -- "$echo_bin" rt/x --count 1 --timeout 1e999
expect 0 "warning: --rate has no effect with --as-fast-as-possible" -- "$play" --dataset "$tum" \
  --config "$cam" --frames 0 --as-fast-as-possible --rate 2 --wait-subscribers 0 --domain $domain
# A timestamp far past the first frame's is refused, not a wait of years (or, past 292 years, an
# overflow into no wait at all): the frames before it are published.
mkdir -p "$tmp/far" && ln -s "$tum/depth" "$tmp/far/depth"
awk '!/^#/ { n++; if (n == 2) $1 = "1e300"; print; if (n == 2) exit }' "$tum/depth.txt" > "$tmp/far/depth.txt"
expect 1 "far: frame 1 is stamped 1e+300 s after frame 0: playing it at a rate of 1 would wait" -- \
  "$play" --dataset "$tmp/far" --config "$cam" --wait-subscribers 0 --domain $domain
expect 2 "domain must be in 0..232" -- "$echo_bin" rt/x --domain 300
expect 2 "TOPIC: '/jpcr/odom' is a ROS name; its DDS topic is 'rt/jpcr/odom'" -- "$echo_bin" /jpcr/odom
expect 2 "TOPIC: 'rt/jpcr/od-om' holds a character other than" -- "$echo_bin" rt/jpcr/od-om
expect 2 "TOPIC needs a non-empty value" -- "$echo_bin" ""
expect 2 "type must be odom, pose, path, image, camera_info, keyframe or curvature_sd, got 'twist'" -- \
  "$echo_bin" rt/x --type twist
expect 1 "error: .*nosuch" -- "$play" --dataset "$tmp/nosuch"
printf 'dds:\n  domain_id: 3\n  topic_prefx: x\n' > "$tmp/bad.yaml"
expect 1 "bad.yaml:3: unknown key .dds.topic_prefx." -- "$echo_bin" rt/x --params "$tmp/bad.yaml"
exit $fail
