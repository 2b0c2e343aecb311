#!/usr/bin/env bash
# jpcr_curvature and jpcr_eval curvature end to end: maps, PNGs, PLYs and summary written for
# Quad IT and Quad LS; the ground truth against itself is exactly 0 with full coverage; numpy
# reads the maps; an all-zero depth frame gives a warning and an all-NaN map, not a crash; bad
# input gives one clear message and the documented exit code.
set -uo pipefail
build=$1 src=$2
synth=$build/tools/jpcr_synth
curv=$build/tools/jpcr_curvature
eval_bin=$build/tools/jpcr_eval
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
# shellcheck source=expect.sh
source "$src/tests/tools/expect.sh"

expect 0 "wrote 3 frames" -- "$synth" --scene room_spheres --frames 3 --noise range:0.5 \
  --size 160x120 --seed 2 --out "$tmp/seq"
expect 0 "wrote 3 curvature maps" -- "$curv" --dataset "$tmp/seq" --method it --out "$tmp/it" --ply
expect 0 "wrote 2 curvature maps" -- "$curv" --dataset "$tmp/seq" --method ls --frames 1:3 --out "$tmp/ls"
# Only Quad IT has a CUDA kernel: --device with Quad LS says so (it ran on the CPU silently).
expect 0 "warning: --device has no effect: method ls runs on the CPU" -- \
  "$curv" --dataset "$tmp/seq" --method ls --frames 0 --device cpu --out "$tmp/ls_device"
for d in curvature curvature_sd curvature_png ply; do
  n=$(ls "$tmp/it/$d" | wc -l)
  [ "$n" = 3 ] || { echo "FAIL: it/$d has $n files, want 3"; fail=1; }
done
# The sd describes Quad IT's weighted fit: Quad LS writes none, and --no-sd none for Quad IT.
[ ! -e "$tmp/ls/curvature_sd" ] || { echo "FAIL: ls wrote curvature_sd/"; fail=1; }
expect 0 "wrote 1 curvature maps" -- "$curv" --dataset "$tmp/seq" --frames 0 --no-sd --out "$tmp/it_no_sd"
[ ! -e "$tmp/it_no_sd/curvature_sd" ] || { echo "FAIL: --no-sd wrote curvature_sd/"; fail=1; }
# The built-in 14 mm gate is below 0.5 % range noise at the room's 2-5 m: most sd are withheld,
# and the run says why. With the gate at 3 sigma (README "Range noise") most pixels have one.
expect 0 "warning: no curvature sd at .* gate is likely below the depth noise" -- \
  "$curv" --dataset "$tmp/seq" --frames 0 --out "$tmp/it_built_in"
printf 'quadric:\n  fit:\n    fair_n0_per_range: 0.05\n    gate_per_range: 0.015\n' > "$tmp/matched.yaml"
out=$("$curv" --dataset "$tmp/seq" --params "$tmp/matched.yaml" --out "$tmp/it_matched" 2>&1) ||
  { echo "FAIL: the run with the matched gate exited $?: $out"; fail=1; }
if grep -q "no curvature sd" <<<"$out"; then echo "FAIL: warned with the matched gate: $out"; fail=1; fi
[ -s "$tmp/it/summary.json" ] || { echo "FAIL: no summary.json"; fail=1; }
head -c 600 "$tmp/it/ply/0.000000.ply" | grep -q "property float k1" || { echo "FAIL: PLY header"; fail=1; }

# The ground truth against itself: 0 error, full coverage. Estimates: finite error, 2 frames for LS.
expect 0 "rms k1 0.0000 1/m  rms k2 0.0000" -- "$eval_bin" curvature --gt "$tmp/seq" --est "$tmp/seq"
expect 0 "coverage 100.00 %" -- "$eval_bin" curvature --gt "$tmp/seq" --est "$tmp/seq"
expect 0 "frames: 2 compared" -- "$eval_bin" curvature --gt "$tmp/seq" --est "$tmp/ls"
"$eval_bin" curvature --gt "$tmp/seq" --est "$tmp/it" --json --out "$tmp/it.json" > /dev/null ||
  { echo "FAIL: eval json"; fail=1; }
# Interior pixels only (--support pattern: the fit's ±5 px span at 160 wide): fewer pixels, and
# the error there below the error over every pixel (the edges are where patch fits go wrong).
"$eval_bin" curvature --gt "$tmp/seq" --est "$tmp/it" --json --support pattern \
  --out "$tmp/it_interior.json" > /dev/null || { echo "FAIL: eval --support"; fail=1; }
expect 2 "--support: expected a radius" -- "$eval_bin" curvature --gt "$tmp/seq" --est "$tmp/it" --support -3
# A radius whose window would overflow int (2R + 1 for R = 2^30) is refused, not a crash.
expect 2 "--support: expected a radius in pixels (0..16384)" -- "$eval_bin" curvature --gt "$tmp/seq" --est "$tmp/it" --support 1073741824
if /usr/bin/python3 -c 'import numpy' 2>/dev/null; then
  /usr/bin/python3 - "$tmp" <<'PY' || fail=1
import glob, json, os, sys, numpy as np
t = sys.argv[1]
r = json.load(open(t + "/it.json"))
assert r["frames"] == 3 and r["estimated_frames"] == 3 and r["gt_frames"] == 3, r
assert 0.9 < r["coverage"] <= 1.0, r
assert 0 < r["rms"] < 50, r
assert 0 < r["sd_compared_pixels"] <= r["compared_pixels"] and 0 <= r["within_2sd"] <= 1, r
i = json.load(open(t + "/it_interior.json"))
assert i["support_radius_px"] == 5 and 0 < i["gt_valid_pixels"] < r["gt_valid_pixels"], (i, r)
assert i["rms"] < r["rms"], (i, r)
sd = np.load(t + "/it_matched/curvature_sd/0.000000.npy")
assert sd.shape == (120, 160) and sd.dtype == np.float32, (sd.shape, sd.dtype)
km = np.load(t + "/it_matched/curvature/0.000000.npy")
assert not np.any(np.isfinite(sd) & ~np.isfinite(km[..., 0]))  # an sd only where a curvature
assert np.isfinite(sd).sum() > 0.5 * np.isfinite(km[..., 0]).sum() and np.nanmin(sd) >= 0
k = np.load(sorted(glob.glob(t + "/it/curvature/*.npy"))[0])
assert k.shape == (120, 160, 2) and k.dtype == np.float32, (k.shape, k.dtype)
valid = np.isfinite(k[..., 0])
assert valid.mean() > 0.9 and np.all(k[valid][:, 0] >= k[valid][:, 1])
s = json.load(open(t + "/it/summary.json"))
assert s["method"] == "quad-it" and len(s["frames"]) == 3 and s["cpu_fallback_frames"] == 0, s
assert all(f["method"] == "quad-it" for f in s["frames"]), s  # what made each map
for f in s["frames"]:  # the maps' names and the timestamps as numbers
    assert os.path.exists(t + "/it/curvature/" + f["stamp"] + ".npy"), f["stamp"]
    assert abs(f["timestamp"] - float(f["stamp"])) < 1e-6, (f["timestamp"], f["stamp"])
# The same maps with k1 and k2 swapped, as a peer with another convention might write them.
import shutil
os.makedirs(t + "/swapped/curvature")
for f in glob.glob(t + "/it/curvature/*.npy"):
    np.save(t + "/swapped/curvature/" + os.path.basename(f), np.load(f)[..., ::-1].copy())
PY
  expect 0 "warning: .* pixels of .*swapped have k1 < k2" -- "$eval_bin" curvature --gt "$tmp/seq" --est "$tmp/swapped"
else
  echo "SKIP: the numpy checks (no python3-numpy); the test reports skipped"
  numpy_missing=1
fi

# A frame with no depth at all (nothing in view): a warning and an all-NaN map, exit 0.
cat > "$tmp/empty.yaml" <<'YAML'
view: {eye: [0, 0, 0], target: [0, 1, 0]}
surfaces:
  - {type: sphere, center: [0, -100, 0], radius: 0.1}
YAML
expect 0 "wrote 1 frames" -- "$synth" --scene "$tmp/empty.yaml" --frames 1 --size 160x120 --out "$tmp/empty"
expect 0 "warning: frame 0 .* no valid curvature" -- "$curv" --dataset "$tmp/empty" --out "$tmp/empty_it"

# Bad input.
expect 1 "error: .*missing_dir" -- "$curv" --dataset "$tmp/missing_dir" --out "$tmp/x"
expect 2 "--method must be 'it'" -- "$curv" --dataset "$tmp/seq" --method cubic --out "$tmp/x"
expect 2 "selects no frame" -- "$curv" --dataset "$tmp/seq" --frames 5:9 --out "$tmp/x"
expect 1 "no curvature/ directory" -- "$eval_bin" curvature --gt "$tmp/seq" --est "$tmp/missing_dir"
printf 'quadric:\n  fit:\n    iterations: many\n' > "$tmp/bad.yaml"
expect 1 "iterations" -- "$curv" --dataset "$tmp/seq" --params "$tmp/bad.yaml" --out "$tmp/x"
expect 2 "--out needs a non-empty value" -- "$curv" --dataset "$tmp/seq" --out ""
expect 2 "color-scale must be a positive finite" -- "$curv" --dataset "$tmp/seq" --color-scale inf --out "$tmp/x"
# A command line's numbers are plain decimal tokens (strtod read "0x10" as 16, " 3" as 3).
expect 2 "--color-scale expects a number, got '0x10'" -- "$curv" --dataset "$tmp/seq" \
  --color-scale 0x10 --out "$tmp/x"
# OUT = the dataset would replace its curvature/ ground truth: refused, the truth kept (the
# trailing slash and ".." name the same directory).
cp "$tmp/seq/curvature/0.000000.npy" "$tmp/truth.npy"
expect 1 "is --dataset .* itself" -- "$curv" --dataset "$tmp/seq" --out "$tmp/seq/"
expect 1 "is --dataset .* itself" -- "$curv" --dataset "$tmp/seq" --out "$tmp/it/../seq"
cmp -s "$tmp/truth.npy" "$tmp/seq/curvature/0.000000.npy" || { echo "FAIL: ground truth changed"; fail=1; }
# OUT = another dataset (here a copy): its ground truth is kept too.
cp -r "$tmp/seq" "$tmp/seq_copy"
expect 1 "holds a dataset (depth.txt)" -- "$curv" --dataset "$tmp/seq" --out "$tmp/seq_copy"
cmp -s "$tmp/truth.npy" "$tmp/seq_copy/curvature/0.000000.npy" ||
  { echo "FAIL: the copy's ground truth changed"; fail=1; }
# OUT in one of the dataset's folders (its ground truth, its depth): refused, nothing added
# there; a new folder beside them is fine.
expect 1 "lies in --dataset .*'s curvature/" -- "$curv" --dataset "$tmp/seq" --out "$tmp/seq/curvature"
expect 1 "lies in --dataset .*'s depth/" -- "$build/tools/jpcr_run" --dataset "$tmp/seq" --method icp-ftf \
  --out "$tmp/seq/depth/run"
[ "$(ls "$tmp/seq/curvature" | wc -l)" = 3 ] && [ ! -e "$tmp/seq/depth/run" ] ||
  { echo "FAIL: outputs landed in the dataset's folders"; fail=1; }
expect 0 "wrote 3 curvature maps" -- "$curv" --dataset "$tmp/seq" --out "$tmp/seq/mine"
# OUT = another program's results: jpcr_run would replace jpcr_curvature's maps and leave its
# summary.json behind, and the other way round.
expect 1 "holds jpcr_curvature's results (summary.json)" -- "$build/tools/jpcr_run" \
  --dataset "$tmp/seq" --method icp-ftf --out "$tmp/it"
[ "$(ls "$tmp/it/curvature" | wc -l)" = 3 ] || { echo "FAIL: it/curvature changed"; fail=1; }
printf '{}\n' > "$tmp/ls/report.json"
expect 1 "holds jpcr_run's results (report.json)" -- "$curv" --dataset "$tmp/seq" --out "$tmp/ls"
# A truncated map: named once, with the problem.
mkdir -p "$tmp/trunc/curvature"
head -c 100 "$tmp/it/curvature/0.000000.npy" > "$tmp/trunc/curvature/0.000000.npy"
expect 1 "error: $tmp/trunc/curvature/0.000000.npy: truncated" -- \
  "$eval_bin" curvature --gt "$tmp/seq" --est "$tmp/trunc"
# A map with ±Inf where NaN belongs: scored as missing, and said so (plain python3, no numpy).
mkdir -p "$tmp/inf/curvature"
python3 - "$tmp/it/curvature/0.000000.npy" "$tmp/inf/curvature/0.000000.npy" <<'PY'
import struct, sys
d = bytearray(open(sys.argv[1], "rb").read())
start = 10 + struct.unpack("<H", d[8:10])[0]  # .npy version 1: the data after the header
d[start:start + 8 * 100] = struct.pack("<f", float("inf")) * 200  # 100 pixels of float32 pairs
open(sys.argv[2], "wb").write(d)
PY
expect 0 "warning: 100 pixels of .*inf are +-Inf" -- "$eval_bin" curvature --gt "$tmp/seq" --est "$tmp/inf"
# A map of another size than its ground truth: both files named (plain python3, no numpy).
# float32_npy FILE SHAPE DATA: a float32 .npy of SHAPE ("(4, 5)") holding the bytes of the Python
# expression DATA, written by plain python3 (no numpy).
float32_npy() {
  python3 - "$@" <<'PY'
import sys
header = "{'descr': '<f4', 'fortran_order': False, 'shape': %s, }" % sys.argv[2]
header += " " * (63 - (10 + len(header)) % 64) + "\n"
data = b"\x93NUMPY\x01\x00" + len(header).to_bytes(2, "little") + header.encode()
open(sys.argv[1], "wb").write(data + eval(sys.argv[3]))
PY
}
mkdir -p "$tmp/small/curvature"
float32_npy "$tmp/small/curvature/0.000000.npy" "(4, 5, 2)" "bytes(160)"
expect 1 "small/curvature/0.000000.npy: the map is 5x4 but its ground truth .*seq/curvature/0.000000.npy is" -- \
  "$eval_bin" curvature --gt "$tmp/seq" --est "$tmp/small"
# An sd map of another size than its curvature map: the sd map is named, not the curvature map.
mkdir -p "$tmp/sd_small/curvature" "$tmp/sd_small/curvature_sd"
cp "$tmp/it/curvature/0.000000.npy" "$tmp/sd_small/curvature/"
float32_npy "$tmp/sd_small/curvature_sd/0.000000.npy" "(4, 5)" "bytes(80)"
expect 1 "error: $tmp/sd_small/curvature_sd/0.000000.npy: the sd map is 5x4 but its curvature map is 160x120" -- \
  "$eval_bin" curvature --gt "$tmp/seq" --est "$tmp/sd_small"
# sd values that are no spread (here -Inf, from a 120x160 map of 0xff800000) are left out and said.
float32_npy "$tmp/sd_small/curvature_sd/0.000000.npy" "(120, 160)" 'b"\x00\x00\x80\xff" * (120 * 160)'
expect 0 "warning: 19200 sd pixels of .*sd_small/curvature_sd are +-Inf or negative" -- \
  "$eval_bin" curvature --gt "$tmp/seq" --est "$tmp/sd_small"
# A map whose stamp has no ground truth is not compared, and said so.
cp "$tmp/inf/curvature/0.000000.npy" "$tmp/inf/curvature/99.000000.npy"
expect 0 "warning: 1 of 2 maps of .*inf have no ground truth of their stamp" -- "$eval_bin" curvature --gt "$tmp/seq" --est "$tmp/inf"
# jpcr_eval's report never replaces what it reads, nor the results it scores.
expect 1 "summary.json: is a file of --est" -- "$eval_bin" curvature --gt "$tmp/seq" --est "$tmp/it" \
  --out "$tmp/it/summary.json"
expect 1 "is a file of --gt" -- "$eval_bin" curvature --gt "$tmp/seq" --est "$tmp/it" \
  --out "$tmp/seq/groundtruth.txt"
# A pattern that cannot be scaled to the images fails before the run, naming the file.
printf 'quadric:\n  pattern:\n    reference_width: 1\n' > "$tmp/tiny_ref.yaml"
expect 1 "tiny_ref.yaml: quadric: pattern (radius 6, stride 3 at reference_width 1) scaled to 160 px wide" -- \
  "$curv" --dataset "$tmp/seq" --params "$tmp/tiny_ref.yaml" --out "$tmp/x"
# So does a min_samples that the pattern has at 640 px but not scaled to these 160 px.
printf 'quadric:\n  fit:\n    min_samples: 129\n' > "$tmp/many.yaml"
expect 1 "many.yaml: quadric: min_samples: 129 exceeds the" -- \
  "$curv" --dataset "$tmp/seq" --params "$tmp/many.yaml" --out "$tmp/x"
# Written whole or not at all: a run with a corrupt last frame leaves no map of the good frames
# and no staging directory; a second run into an earlier OUT leaves none of the earlier maps.
cp -r "$tmp/seq" "$tmp/seq_bad"
last=$(ls "$tmp/seq_bad/depth" | sort | tail -1)
head -c 100 "$tmp/seq/depth/$last" > "$tmp/seq_bad/depth/$last"
expect 1 "$last" -- "$curv" --dataset "$tmp/seq_bad" --out "$tmp/partial"
[ ! -e "$tmp/partial" ] || { echo "FAIL: a failed run wrote $(ls -R "$tmp/partial")"; fail=1; }
[ -z "$(ls -A "$tmp" | grep partial-)" ] || { echo "FAIL: staging left behind"; fail=1; }
expect 0 "wrote 1 curvature maps" -- "$curv" --dataset "$tmp/seq" --frames 2:3 --out "$tmp/it"
n=$(ls "$tmp/it/curvature" | wc -l)
[ "$n" = 1 ] || { echo "FAIL: $n maps in OUT after a 1-frame run into the 3-frame run's OUT"; fail=1; }
# A dataset inside one of the entries a run replaces (OUT/curvature) is refused before the run,
# and stays whole; a failed run removes the parent directories it made for OUT.
mkdir -p "$tmp/exp" && cp -r "$tmp/seq" "$tmp/exp/curvature"
expect 1 "exp/curvature: --dataset lies in .*exp/curvature, which this run replaces" -- \
  "$curv" --dataset "$tmp/exp/curvature" --out "$tmp/exp"
[ -e "$tmp/exp/curvature/depth.txt" ] || { echo "FAIL: the dataset in OUT/curvature is gone"; fail=1; }
expect 1 "$last" -- "$curv" --dataset "$tmp/seq_bad" --out "$tmp/nest1/nest2/out"
[ ! -e "$tmp/nest1" ] || { echo "FAIL: a failed run left $tmp/nest1"; fail=1; }
# No pixel to compare (a support wider than any smooth patch) is an error, not an RMS of NaN.
expect 1 "no pixel is valid in both" -- "$eval_bin" curvature --gt "$tmp/seq" --est "$tmp/it" --support 100
expect 0 "Quad LS" -- "$curv" --help
# The peer, CGAL jet fitting, where the build has it: a map as complete as Quad LS's.
if "$curv" --help | grep -q "jet (the peer"; then
  expect 0 "cgal-jet" -- "$curv" --dataset "$tmp/seq" --method jet --frames 0:1 --out "$tmp/jet"
  expect 0 "coverage 100.00 %" -- "$eval_bin" curvature --gt "$tmp/seq" --est "$tmp/jet"
else
  expect 2 "no CGAL" -- "$curv" --dataset "$tmp/seq" --method jet --out "$tmp/x"
fi
# 77: ctest's SKIP_RETURN_CODE, so that a missing check shows as skipped, not passed.
[ "${fail:-0}" = 0 ] && [ "${numpy_missing:-0}" = 1 ] && exit 77
exit $fail
