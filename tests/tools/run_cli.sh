#!/usr/bin/env bash
# jpcr_run end to end on a small synthetic sequence: every output written (trajectory, front
# end, keyframes, a curvature map per keyframe, report), the refined trajectory evaluates against
# ground truth, and bad input gives one clear message and the documented exit code.
set -uo pipefail
build=$1 src=$2
synth=$build/tools/jpcr_synth
run=$build/tools/jpcr_run
eval_bin=$build/tools/jpcr_eval
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
# shellcheck source=expect.sh
source "$src/tests/tools/expect.sh"

expect 0 "wrote 4 frames" -- "$synth" --scene room_spheres --frames 4 --size 160x120 --seed 4 \
  --out "$tmp/seq"
expect 0 "j-ftf " -- "$run" --dataset "$tmp/seq" --method j-ftf --out "$tmp/ftf"
for f in trajectory.txt front_end.txt keyframes.txt report.json; do
  [ -s "$tmp/ftf/$f" ] || { echo "FAIL: $f missing"; fail=1; }
done
for d in curvature curvature_sd; do
  n=$(ls "$tmp/ftf/$d" | wc -l)
  [ "$n" = 4 ] || { echo "FAIL: $n maps in $d/, want 4 (one per keyframe)"; fail=1; }
done
expect 0 "ATE" -- "$eval_bin" traj --gt "$tmp/seq/groundtruth.txt" --est "$tmp/ftf/trajectory.txt"
if /usr/bin/python3 -c 'import numpy' 2>/dev/null; then
  /usr/bin/python3 - "$tmp" <<'PY' || fail=1
import json, sys
r = json.load(open(sys.argv[1] + "/ftf/report.json"))
assert r["method"] == "j-ftf" and r["frames"] == 4 and r["keyframes"] == 4, r
pairs = [k["pair"] for k in r["keyframe_records"][1:]]
assert all(p is not None and p["verdict"] == "converged" for p in pairs), pairs
assert len({p["device"] for p in pairs}) == 1 and pairs[0]["device"] in ("cpu", "cuda"), pairs
# Each pair's predicted spread: one pose, one step, the same (J-ftf), positive.
for p in pairs:
    assert len(p["translation_sd_m"]) == 1 and p["step_translation_sd_m"] == p["translation_sd_m"], p
    assert len(p["rotation_sd_rad"]) == 1 and p["step_rotation_sd_rad"] == p["rotation_sd_rad"], p
    assert p["translation_sd_m"][0] > 0 and p["rotation_sd_rad"][0] > 0, p
assert r["errors"]["relative_translation_rms_m"] < r["front_end_errors"]["relative_translation_rms_m"]
# Whose quadrics each map is: J-ftf's for every keyframe that starts a pair, Quad IT's for the last.
sources = [k["curvature"] for k in r["keyframe_records"]]
assert sources == ["j-ftf"] * 3 + ["quad-it"], sources
PY
else
  echo "SKIP: the numpy checks (no python3-numpy); the test reports skipped"
  numpy_missing=1
fi
# A window that fails (a degeneracy threshold no scene meets) fails every keyframe it covers:
# report.json counts the three (it counted the window's last keyframe alone), the frames are
# untrusted with the cause named, per frame and in the summary, and the inputs are recorded.
printf 'joint:\n  degeneracy_threshold: 0.5\n' > "$tmp/strict.yaml"
expect 0 "3 of 4 frames are not trusted (window: 3 degenerate)" -- "$run" --dataset "$tmp/seq" \
  --method j-full --window 4 --params "$tmp/strict.yaml" --frames 0:4 --out "$tmp/strict"
/usr/bin/python3 - "$tmp" <<'PY' || fail=1
import json, sys
t = sys.argv[1]
r = json.load(open(t + "/strict/report.json"))
assert r["keyframes_with_failed_refinement"] == 3 and r["keyframes_on_front_end_motion"] == 3, r
assert r["frames_trusted"] == 1 and r["frames_untrusted"] == 3, r
assert r["untrusted_causes"] == {"window: degenerate": 3}, r["untrusted_causes"]
assert r["params"] == t + "/strict.yaml" and r["config"] is None and r["first_frame"] == 0, r
f = r["frame_records"]
assert [x["trusted"] for x in f] == [True, False, False, False], f
assert [x["window"] for x in f] == [None, "degenerate", "degenerate", "degenerate"], f
assert [x["dataset_index"] for x in f] == [0, 1, 2, 3], f
assert all(k["map"] + ".npy" in __import__("os").listdir(t + "/strict/curvature")
           for k in r["keyframe_records"]), r["keyframe_records"]
PY
# A sensor that starts blank: frame 0's depth all zero (a 16-bit PNG of zeros). The first frame
# with points is the gauge; frame 0 keeps its pose, untrusted, and frames 1-3 are refined and
# trusted (jpcr_run crashed on it: it read the last keyframe before there was one).
cp -r "$tmp/seq" "$tmp/blank"
/usr/bin/python3 - "$tmp/blank/depth/$(ls "$tmp/blank/depth" | head -1)" 160 120 <<'PY' || fail=1
import struct, sys, zlib
path, w, h = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
def chunk(kind, data):
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
raw = b"".join(b"\0" * (1 + 2 * w) for _ in range(h))
open(path, "wb").write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 16, 0, 0, 0, 0))
                       + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))
PY
for method in j-ftf pipeline; do
  expect 0 "$method " -- "$run" --dataset "$tmp/blank" --method $method --out "$tmp/blank_$method"
  got=$(grep -v '^#' "$tmp/blank_$method/verdicts.txt" | awk '{print $2 "/" $NF}' | tr '\n' ' ')
  [ "$got" = "too_few_points/no ok/yes ok/yes ok/yes " ] \
    || { echo "FAIL: $method on a blank start: verdicts $got"; fail=1; }
done
[ "$(grep -v '^#' "$tmp/blank_j-ftf/keyframes.txt" | wc -l)" = 3 ] \
  || { echo "FAIL: j-ftf on a blank start: keyframes"; cat "$tmp/blank_j-ftf/keyframes.txt"; fail=1; }

# Options that change nothing for the method are said (they were taken silently).
expect 0 "warning: --window has no effect: method icp-ftf refines no windows" -- "$run" \
  --dataset "$tmp/seq" --method icp-ftf --window 7 --out "$tmp/icp"
expect 0 "warning: --ply has no effect: method icp-ftf fits no quadrics" -- "$run" \
  --dataset "$tmp/seq" --method icp-ftf --ply --out "$tmp/icp"
expect 0 "warning: --no-sd has no effect: method icp-ftf fits no quadrics" -- "$run" \
  --dataset "$tmp/seq" --method icp-ftf --no-sd --out "$tmp/icp"
expect 0 "warning: --device has no effect: method icp-ftf runs on the CPU" -- "$run" \
  --dataset "$tmp/seq" --method icp-ftf --device cuda --out "$tmp/icp"
expect 0 "icp-ftf" -- "$run" --dataset "$tmp/seq" --method icp-ftf --out "$tmp/icp"
n=$(ls "$tmp/icp/curvature" | wc -l)
[ "$n" = 0 ] || { echo "FAIL: icp-ftf wrote $n curvature maps"; fail=1; }
# Images wider than the quadric pattern can be scaled to (s = 66 px at 14000 wide): refused for
# the methods that fit quadrics, before any frame; ICP-ftf fits none and runs.
expect 0 "wrote 2 frames" -- "$synth" --size 14000x40 --frames 2 --out "$tmp/wide"
expect 1 "quadric: pattern .* scaled to 14000 px wide" -- "$run" --dataset "$tmp/wide" \
  --method j-ftf --out "$tmp/wide_ftf"
expect 0 "wrote 2 poses" -- "$run" --dataset "$tmp/wide" --method icp-ftf --out "$tmp/wide_icp"

# Outputs are written whole or not at all (io/staged_output.hpp). A second run into the same
# OUT replaces every output of the first: icp-ftf writes no map, so j-ftf's four must be gone,
# while a file of the user's stays.
echo "mine" > "$tmp/ftf/notes.txt"
expect 0 "icp-ftf" -- "$run" --dataset "$tmp/seq" --method icp-ftf --out "$tmp/ftf"
n=$(ls "$tmp/ftf/curvature" "$tmp/ftf/curvature_sd" | grep -c npy)
[ "$n" = 0 ] || { echo "FAIL: $n stale curvature or sd maps of the earlier run in OUT"; fail=1; }
grep -q mine "$tmp/ftf/notes.txt" || { echo "FAIL: the user's file in OUT was touched"; fail=1; }
# A run that fails (a corrupt frame after good ones) changes nothing in OUT and leaves no
# staging directory; into a new OUT it creates nothing.
cp -r "$tmp/seq" "$tmp/seq_bad"
last=$(ls "$tmp/seq_bad/depth" | sort | tail -1)
head -c 100 "$tmp/seq/depth/$last" > "$tmp/seq_bad/depth/$last"
before=$(cd "$tmp/ftf" && find . -type f | sort | xargs md5sum)
expect 1 "$last" -- "$run" --dataset "$tmp/seq_bad" --method j-ftf --out "$tmp/ftf"
[ "$(cd "$tmp/ftf" && find . -type f | sort | xargs md5sum)" = "$before" ] ||
  { echo "FAIL: a failed run changed OUT"; fail=1; }
expect 1 "$last" -- "$run" --dataset "$tmp/seq_bad" --method j-ftf --out "$tmp/fresh"
[ ! -e "$tmp/fresh" ] || { echo "FAIL: a failed run created OUT"; fail=1; }
[ -z "$(ls -A "$tmp" | grep partial)" ] || { echo "FAIL: staging left: $(ls -A "$tmp")"; fail=1; }

# Ctrl-C (SIGINT) stops the run at the next frame: exit 130, "interrupted", OUT as it was and
# no staging left. A run killed outright (SIGKILL) leaves its staging directory, which the next
# run into the same OUT removes. The 30-frame sequence takes seconds; the signal is sent as
# soon as the staging directory appears, before the first frame is done.
# report.json's errors are jpcr_eval traj's on trajectory.txt: against the ground truth as
# recorded, over the frames run (--frames 3:17), with a gap in the motion capture (no ground
# truth within 20 ms of depth frame 10) that neither may bridge with a neighbour's pose.
cp -r "$src/tests/data/tum_fr1_xyz_20" "$tmp/tum"
t10=$(grep -v '^#' "$tmp/tum/depth.txt" | sed -n 11p | cut -d' ' -f1)
awk -v t="$t10" '/^#/ || ($1 - t) * ($1 - t) >= 0.0004' "$src/tests/data/tum_fr1_xyz_20/groundtruth.txt" \
  > "$tmp/tum/groundtruth.txt"
expect 0 "icp-ftf " -- "$run" --dataset "$tmp/tum" --config "$src/configs/tum_fr1.yaml" \
  --method icp-ftf --frames 3:17 --out "$tmp/tumrun"
"$eval_bin" traj --gt "$tmp/tum/groundtruth.txt" --est "$tmp/tumrun/trajectory.txt" --json \
  > "$tmp/tumeval.json" || { echo "FAIL: jpcr_eval on the TUM run"; fail=1; }
/usr/bin/python3 - "$tmp" <<'PY' || fail=1
import json, sys
t = sys.argv[1]
report = json.load(open(t + "/tumrun/report.json"))
# The run's frame 0 is the dataset's frame 3: both numbers are in the records.
assert report["first_frame"] == 3, report["first_frame"]
assert [f["dataset_index"] - f["index"] for f in report["frame_records"]] == [3] * 14
r = report["errors"]
e = json.load(open(t + "/tumeval.json"))
pairs = [(r["ate_rmse_m"], e["ate"]["translation_m"]["rmse"]),
         (r["rpe_frame_translation_rmse_m"], e["rpe_per_frame"]["translation_m"]["rmse"]),
         (r["rpe_frame_rotation_rmse_deg"], e["rpe_per_frame"]["rotation_deg"]["rmse"]),
         (r["relative_translation_rms_m"], e["relative"]["translation_rms_m"]),
         (r["relative_rotation_rms_rad"], e["relative"]["rotation_rms_rad"])]
assert all(abs(a - b) <= 1e-9 * abs(b) for a, b in pairs), pairs
# 14 frames, frame 10 (the 8th) without ground truth: 13 consecutive pairs less the two that
# touch it for the relative errors; RPE, as evaluate_rpe.py, also skips the pair ending at the
# last estimate: 10.
assert e["rpe_per_frame"]["translation_m"]["count"] == 10, e["rpe_per_frame"]
assert e["relative"]["pairs"] == 11, e["relative"]
print("ok: report.json's errors are jpcr_eval's against the recorded ground truth")
PY

expect 0 "wrote 30 frames" -- "$synth" --scene room_spheres --frames 30 --size 160x120 --seed 4 \
  --out "$tmp/long"
wait_for_staging() {  # $1: OUT; up to 20 s
  for _ in $(seq 200); do
    compgen -G "$(dirname "$1")/.$(basename "$1").partial-*" > /dev/null && return 0
    sleep 0.1
  done
  echo "FAIL: no staging directory for $1 appeared"; fail=1; return 1
}
before=$(cd "$tmp/ftf" && find . -type f | sort | xargs md5sum)
"$run" --dataset "$tmp/long" --method j-ftf --out "$tmp/ftf" > "$tmp/int.log" 2>&1 &
pid=$!
wait_for_staging "$tmp/ftf" && kill -INT $pid
wait $pid; rc=$?
{ [ $rc = 130 ] && grep -q "interrupted: stopped by SIGINT (Ctrl-C) at frame .* is left as it was" "$tmp/int.log" &&
  grep -q "^jpcr_run: stopping after the current step" "$tmp/int.log"; } ||
  { echo "FAIL: SIGINT: exit $rc, output: $(cat "$tmp/int.log")"; fail=1; }
# SIGTERM (a service manager's stop): the same, with 128 + 15, the shell's convention.
"$run" --dataset "$tmp/long" --method j-ftf --out "$tmp/ftf" > "$tmp/term.log" 2>&1 &
pid=$!
wait_for_staging "$tmp/ftf" && kill -TERM $pid
wait $pid; rc=$?
{ [ $rc = 143 ] && grep -q "interrupted: stopped by SIGTERM at frame" "$tmp/term.log"; } ||
  { echo "FAIL: SIGTERM: exit $rc, output: $(cat "$tmp/term.log")"; fail=1; }
[ "$(cd "$tmp/ftf" && find . -type f | sort | xargs md5sum)" = "$before" ] ||
  { echo "FAIL: an interrupted run changed OUT"; fail=1; }
[ -z "$(ls -A "$tmp" | grep partial)" ] || { echo "FAIL: staging left after SIGINT"; fail=1; }
"$run" --dataset "$tmp/long" --method j-ftf --out "$tmp/ftf" > /dev/null 2>&1 &
pid=$!
wait_for_staging "$tmp/ftf" && kill -KILL $pid
wait $pid 2> /dev/null
[ -n "$(ls -A "$tmp" | grep partial)" ] || { echo "FAIL: SIGKILL left no staging"; fail=1; }
expect 0 "wrote 4 poses" -- "$run" --dataset "$tmp/seq" --method icp-ftf --out "$tmp/ftf"
[ -z "$(ls -A "$tmp" | grep partial)" ] ||
  { echo "FAIL: the killed run's staging was not removed: $(ls -A "$tmp")"; fail=1; }

# Bad input.
expect 2 "--out needs a non-empty value" -- "$run" --dataset "$tmp/seq" --out ""
expect 2 "--method: unknown method 'bundle'" -- "$run" --dataset "$tmp/seq" --method bundle --out "$tmp/x"
expect 2 "--window must be in" -- "$run" --dataset "$tmp/seq" --window 1 --out "$tmp/x"
expect 1 "error: .*nowhere" -- "$run" --dataset "$tmp/nowhere" --out "$tmp/x"
printf 'pipeline:\n  window: 99\n' > "$tmp/bad.yaml"
expect 1 "window" -- "$run" --dataset "$tmp/seq" --params "$tmp/bad.yaml" --out "$tmp/x"
printf 'pipeline:\n  keep_history: false\n' > "$tmp/forget.yaml"
expect 1 "forget.yaml: pipeline.keep_history: false is for live runs" -- \
  "$run" --dataset "$tmp/seq" --params "$tmp/forget.yaml" --out "$tmp/x"
# OUT = the dataset would replace the generator's curvature/ ground truth there.
expect 1 "is --dataset .* itself" -- "$run" --dataset "$tmp/seq" --out "$tmp/seq"
[ -d "$tmp/seq/curvature" ] && [ ! -e "$tmp/seq/trajectory.txt" ] ||
  { echo "FAIL: jpcr_run wrote into its dataset"; fail=1; }
expect 0 "J-full" -- "$run" --help
# J-ftf out of memory (1280x960 needs about 1.3 GB; the rest of the run fits in 0.5 GB, measured
# on one thread): the pair is a failed refinement, the run ends and says why, and report.json
# holds the error. One thread everywhere (OpenMP, the tracker's pool: each thread reserves its
# stack and a malloc arena against ulimit -v) and the CPU, so that the window does not depend on
# the machine. Not under a sanitizer, which reserves terabytes of address space.
if grep -qE "__(asan|tsan|msan)_init" "$run"; then
  echo "SKIP: the out-of-memory case (a sanitizer build cannot run under ulimit -v)"
else
  expect 0 "wrote 2 frames" -- "$synth" --scene room_spheres --frames 2 --size 1280x960 \
    --out "$tmp/big"
  printf 'frontend:\n  threads: 1\n' > "$tmp/one_thread.yaml"
  expect 0 "the first error, j-ftf at keyframe 1: out of memory: j-ftf of 2 frames of 1280x960" \
    -- bash -c 'ulimit -v 900000 && OMP_NUM_THREADS=1 MALLOC_ARENA_MAX=1 exec "$@"' _ \
    "$run" --dataset "$tmp/big" --method j-ftf --device cpu --params "$tmp/one_thread.yaml" \
    --out "$tmp/oom"
  grep -q '"error": "out of memory: j-ftf of 2 frames of 1280x960' "$tmp/oom/report.json" ||
    { echo "FAIL: report.json does not say out of memory"; fail=1; }
  grep -q " ok error - no$" "$tmp/oom/verdicts.txt" ||
    { echo "FAIL: verdicts.txt"; cat "$tmp/oom/verdicts.txt"; fail=1; }
fi
# 77: ctest's SKIP_RETURN_CODE, so that a missing check shows as skipped, not passed.
[ "${fail:-0}" = 0 ] && [ "${numpy_missing:-0}" = 1 ] && exit 77
exit $fail
