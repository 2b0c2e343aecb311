#!/usr/bin/env bash
# jpcr_odometry end to end: --help, a small run on the 20 real fr1/xyz frames (trajectory, JSON
# summary with per-frame verdicts and keyframes, an ATE jpcr_eval finds small), and bad input
# (one clear message naming the file, exit 1 or 2, nothing written).
set -uo pipefail
build=$1 src=$2 data=$3
odo=$build/tools/jpcr_odometry
eval_bin=$build/tools/jpcr_eval
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
# shellcheck source=expect.sh
source "$src/tests/tools/expect.sh"
cam=$src/configs/tum_fr1.yaml
fr1=$data/tum_fr1_xyz_20

expect 0 "usage: jpcr_odometry" -- "$odo" --help
expect 0 "frame_to_keyframe" -- "$odo" --help

# A small run, both modes.
expect 0 "wrote 20 poses" -- "$odo" --dataset "$fr1" --config "$cam" --out "$tmp/f2f/traj.txt"
expect 0 "wrote 12 poses" -- "$odo" --dataset "$fr1" --config "$cam" --mode frame_to_keyframe \
  --frames 12 --threads 1 --out "$tmp/kf.txt" --summary "$tmp/kf_summary.json"
[ "$(grep -vc '^#' "$tmp/f2f/traj.txt")" = 20 ] || { echo "FAIL: trajectory lines"; fail=1; }
"$eval_bin" traj --gt "$fr1/groundtruth.txt" --est "$tmp/f2f/traj.txt" --json > "$tmp/eval.json" \
  || { echo "FAIL: jpcr_eval"; fail=1; }
if /usr/bin/python3 -c 'import json' 2>/dev/null; then
  /usr/bin/python3 - "$tmp" <<'PY' || fail=1
import json, sys
t = sys.argv[1]
s = json.load(open(t + "/f2f/traj.txt.json"))
assert s["mode"] == "frame_to_frame" and s["frames"] == 20, s["mode"]
frames = s["per_frame"]
assert len(frames) == 20 and frames[0]["verdict"] == "first"
assert all(f["verdict"] == "ok" for f in frames[1:]), [f["verdict"] for f in frames]
assert s["verdicts"]["ok"] == 19 and s["kept_last_motion"] == 0
assert s["keyframes"][0] == 0 and all(frames[k]["is_keyframe"] for k in s["keyframes"])
assert all(f["reference"] == f["index"] - 1 for f in frames)
k = json.load(open(t + "/kf_summary.json"))
assert k["mode"] == "frame_to_keyframe" and k["threads"] == 1 and len(k["per_frame"]) == 12
kf = set(k["keyframes"])
for f in k["per_frame"][1:]:
    assert f["reference"] in kf and f["reference"] < f["index"], f
# 20 frames of fr1/xyz (0.24 m): ICP-ftf's ATE is about 2 mm; 1 cm would mean it is broken.
e = json.load(open(t + "/eval.json"))
ate = e["ate"]["translation_m"]["rmse"]
assert ate < 0.01, ate
print("ok: summary has 20 verdicts and the keyframes; ATE %.4f m" % ate)
PY
fi

# Bad input.
mkdir -p "$tmp/broken/depth"
cp "$fr1/depth.txt" "$fr1/groundtruth.txt" "$tmp/broken/"
cp "$fr1"/depth/*.png "$tmp/broken/depth/"
bad_png=$(ls "$tmp/broken/depth" | sed -n 3p)
echo "not a png" > "$tmp/broken/depth/$bad_png"
printf 'fx: 525\nfy: 525\ncx: 159.5\ncy: 119.5\nwidth: 320\nheight: 240\ndepth_scale: 5000\n' > "$tmp/small.yaml"
printf 'frontend:\n  icp:\n    max_distance: -1\n' > "$tmp/bad_params.yaml"
printf 'frontend:\n  tracker:\n    keyframe_distance: 1\n' > "$tmp/typo_params.yaml"
expect 1 "$bad_png" -- "$odo" --dataset "$tmp/broken" --config "$cam" --out "$tmp/x/traj.txt"
# The outputs never replace the dataset's own files (on a copy: the real frames stay safe).
cp "$tmp/broken/groundtruth.txt" "$tmp/gt_before.txt"
expect 1 "groundtruth.txt: is a file of --dataset" -- \
  "$odo" --dataset "$tmp/broken" --config "$cam" --out "$tmp/broken/groundtruth.txt"
expect 1 "depth.txt: is a file of --dataset" -- \
  "$odo" --dataset "$tmp/broken" --config "$cam" --out "$tmp/x.txt" --summary "$tmp/broken/depth.txt"
cp "$cam" "$tmp/cam.yaml"
expect 1 "cam.yaml: is --config" -- \
  "$odo" --dataset "$tmp/broken" --config "$tmp/cam.yaml" --out "$tmp/cam.yaml"
cmp -s "$tmp/broken/groundtruth.txt" "$tmp/gt_before.txt" ||
  { echo "FAIL: the dataset's groundtruth.txt was overwritten"; fail=1; }
expect 1 "nosuch: dataset does not exist" -- "$odo" --dataset "$tmp/nosuch" --config "$cam" --out "$tmp/x.txt"
# A run that fails creates no directory for its outputs.
expect 1 "nosuch: dataset does not exist" -- "$odo" --dataset "$tmp/nosuch" --config "$cam" --out "$tmp/newdir/x.txt"
[ ! -e "$tmp/newdir" ] || { echo "FAIL: a failed run created the output's directory"; fail=1; }
expect 1 "missing.yaml" -- "$odo" --dataset "$fr1" --config "$tmp/missing.yaml" --out "$tmp/x.txt"
expect 1 "640x480" -- "$odo" --dataset "$fr1" --config "$tmp/small.yaml" --out "$tmp/x.txt"
expect 1 "bad_params.yaml:3: key 'frontend.icp.max_distance': must be positive" -- \
  "$odo" --dataset "$fr1" --config "$cam" --params "$tmp/bad_params.yaml" --out "$tmp/x.txt"
expect 1 "unknown key 'frontend.tracker.keyframe_distance'" -- \
  "$odo" --dataset "$fr1" --config "$cam" --params "$tmp/typo_params.yaml" --out "$tmp/x.txt"
expect 1 "no camera given" -- "$odo" --dataset "$fr1" --out "$tmp/x.txt"
# An output under a file can never be written: refused before the run (no dataset is read).
printf 'x' > "$tmp/afile"
expect 1 "afile/x.txt: .*afile is not a directory" -- "$odo" --dataset "$tmp/nosuch" --out "$tmp/afile/x.txt"
expect 2 "out is required" -- "$odo" --dataset "$fr1"
expect 2 "mode: unknown tracking mode 'sideways'" -- "$odo" --dataset "$fr1" --mode sideways --out "$tmp/x.txt"
expect 2 "frames must be >= 0" -- "$odo" --dataset "$fr1" --frames -1 --out "$tmp/x.txt"
expect 2 "summary and --out name the same file" -- \
  "$odo" --dataset "$fr1" --config "$cam" --out "$tmp/x.txt" --summary "$tmp/./x.txt"
# Relative names of a file not yet there ("x.txt" stayed relative, "./x.txt" became absolute).
(cd "$tmp" && expect 2 "summary and --out name the same file" -- \
  "$odo" --dataset "$fr1" --config "$cam" --out rel.txt --summary ./rel.txt; exit $fail) || fail=1
mkdir -p "$tmp/adir"
expect 1 "adir: names a directory" -- "$odo" --dataset "$fr1" --config "$cam" --out "$tmp/x.txt" \
  --summary "$tmp/adir"
# A directory name ("DIR/") is refused before the run, not after it.
expect 1 "newdir/: names a directory, not a file" -- "$odo" --dataset "$fr1" --config "$cam" \
  --out "$tmp/newdir/"
[ -e "$tmp/newdir" ] && { echo "FAIL: newdir/ made for a refused --out"; fail=1; }
# Another run's results are never an output file (jpcr_run's trajectory.txt beside its
# report.json).
mkdir -p "$tmp/run1" && echo '{}' > "$tmp/run1/report.json" && echo keep > "$tmp/run1/trajectory.txt"
touch "$tmp/run1/verdicts.txt"
expect 1 "run1/trajectory.txt: is a file of the dataset or results in" -- \
  "$odo" --dataset "$fr1" --config "$cam" --frames 2 --out "$tmp/run1/trajectory.txt"
[ "$(cat "$tmp/run1/trajectory.txt")" = keep ] || { echo "FAIL: run1/trajectory.txt replaced"; fail=1; }
expect 2 "threads must be in 0..256" -- "$odo" --dataset "$fr1" --threads 300 --out "$tmp/x.txt"
[ -e "$tmp/x.txt" ] || [ -e "$tmp/x/traj.txt" ] && { echo "FAIL: output written after an error"; fail=1; }
# A summary that cannot be written where --out can: the run fails and leaves no empty --out
# directory behind.
expect 1 "/proc/jpcr_nowhere" -- "$odo" --dataset "$fr1" --config "$cam" --frames 2 \
  --out "$tmp/od3/t.txt" --summary /proc/jpcr_nowhere/s.json
[ -e "$tmp/od3" ] && { echo "FAIL: an empty od3/ was left behind"; fail=1; }
ls "$tmp" "$tmp/f2f" | grep -q '\.tmp\.' && { echo "FAIL: temporary file left behind"; fail=1; }
# What a device, a pipe or a link to one at --out: refused before the run, left as it was (a
# rename replaced them: as root, --out /dev/null deleted the device node).
mkfifo "$tmp/pipe" && ln -s "$tmp/pipe" "$tmp/to_pipe" && ln -s "$tmp/none" "$tmp/dangling"
expect 1 "pipe: exists and is no regular file (a device, a pipe or a socket)" -- \
  "$odo" --dataset "$fr1" --config "$cam" --frames 2 --out "$tmp/pipe"
expect 1 "to_pipe: a symbolic link to no regular file" -- \
  "$odo" --dataset "$fr1" --config "$cam" --frames 2 --out "$tmp/x.txt" --summary "$tmp/to_pipe"
expect 1 "dangling: a symbolic link to nothing" -- \
  "$odo" --dataset "$fr1" --config "$cam" --frames 2 --out "$tmp/dangling"
[ -p "$tmp/pipe" ] && [ -L "$tmp/to_pipe" ] || { echo "FAIL: the pipe or its link was replaced"; fail=1; }
[ -e "$tmp/x.txt" ] && { echo "FAIL: --out written beside a refused --summary"; fail=1; }
# A link to a regular file writes that file, and stays a link.
echo old > "$tmp/real.txt" && ln -s "$tmp/real.txt" "$tmp/link.txt"
expect 0 "wrote 2 poses" -- "$odo" --dataset "$fr1" --config "$cam" --frames 2 --out "$tmp/link.txt"
[ -L "$tmp/link.txt" ] && [ "$(grep -vc '^#' "$tmp/real.txt")" = 2 ] \
  || { echo "FAIL: the link was replaced or its file not written"; fail=1; }
# A run killed outright left its copies (PID gone): the next run removes them, and puts the
# earlier trajectory back where the kill left none.
gone=$(cat /proc/sys/kernel/pid_max)  # PIDs are below it: no process has it
echo new > "$tmp/k.txt.partial-$gone" && echo new > "$tmp/k.txt.json.partial-$gone"
echo earlier > "$tmp/k.txt.previous-$gone"
expect 1 "no_such_dataset" -- "$odo" --dataset "$tmp/no_such_dataset" --out "$tmp/k.txt"
[ "$(cat "$tmp/k.txt" 2>/dev/null)" = earlier ] || { echo "FAIL: the earlier k.txt not put back"; fail=1; }
ls "$tmp" | grep -q 'k\.txt.*-'"$gone" && { echo "FAIL: a killed run's copies left"; fail=1; }
exit $fail
