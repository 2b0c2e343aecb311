#!/usr/bin/env bash
# Regenerates the paper's evaluation (issue 10) from nothing: synthetic scenes × range noise for
# the pose tables (I–III) and the curvature comparison (Fig. 7), Kinect-like noise (not in the
# paper), a rail drift sequence (Fig. 6), the real TUM frames with the OpenCV peer, curvature
# pictures (Fig. 1), timings, and a self-contained report (index.md + PNG figures).
#
#   tools/reproduce.sh [--quick] [--out DIR] [--tum DIR] [--camera CAM.yaml] [--build DIR] [--no-build]
#                      [--size WxH] [--frames N]
#                      [--window M] [--rail-frames N] [--rail-size WxH] [--real-frames N]
#                      [--real-jftf-frames N]
#
# Full run (default): 640x480 scenes, the report in report/ of the repository. --quick: small
# sizes and few frames (about 2 minutes on 2 cores), the report under --out, the real frames from the
# repository's tests/data (unless --tum), and exit status 1 unless every section is present and
# the pose orderings hold (CI runs it: tests/tools). --no-build: use the programs already built in
# --build. Every number in the report comes from this run; report/ is committed output of a full
# run. Relative paths are the caller's. An interrupted run resumes with the same --out; runs made
# there by another revision or with other options are refused (give a fresh --out).
set -euo pipefail
caller=$PWD
repo=$(cd "$(dirname "$0")/.." && pwd)
args="$*"

quick=0 no_build=0 out="" tum="" camera=configs/tum_fr1.yaml
build=${JPCR_BUILD_DIR:-$repo/build}
size=640x480 frames=4 window=4 rail_frames=200 rail_size=320x240 real_frames=300 real_jftf=10
kinect_frames=8 study_size=320x240 study_draws=8
# --quick sets small defaults first, so that options given with it still apply.
for a in "$@"; do
  if [[ $a == --quick ]]; then
    quick=1
    size=160x120 frames=3 window=3 rail_frames=24 rail_size=160x120 real_frames=8 real_jftf=3
    kinect_frames=3 study_size=80x60 study_draws=2
  fi
done
usage() { awk 'NR > 1 && !/^#/ { exit } NR > 1' "$0" | sed 's/^# \{0,1\}//'; }
# Paths given on the command line are the caller's: relative ones are taken from its directory.
from_caller() { [[ $1 == /* ]] && echo "$1" || echo "$caller/$1"; }
need() { [[ $# -ge 2 && -n $2 ]] || { echo "reproduce.sh: $1 needs a value" >&2; exit 2; }; }
while [[ $# -gt 0 ]]; do
  case $1 in
    --quick) shift ;;
    --out) need "$@"; out=$(from_caller "$2"); shift 2 ;;
    --tum) need "$@"; tum=$(from_caller "$2"); shift 2 ;;
    --camera) need "$@"; camera=$(from_caller "$2"); shift 2 ;;
    --build) need "$@"; build=$(from_caller "$2"); shift 2 ;;
    --no-build) no_build=1; shift ;;
    --size) need "$@"; size=$2; shift 2 ;;
    --frames) need "$@"; frames=$2; shift 2 ;;
    --window) need "$@"; window=$2; shift 2 ;;
    --rail-frames) need "$@"; rail_frames=$2; shift 2 ;;
    --rail-size) need "$@"; rail_size=$2; shift 2 ;;
    --real-frames) need "$@"; real_frames=$2; shift 2 ;;
    --real-jftf-frames) need "$@"; real_jftf=$2; shift 2 ;;
    -h|--help) usage; exit 0 ;;
    *) echo "reproduce.sh: unknown option '$1' (see --help)" >&2; exit 2 ;;
  esac
done
build=$(from_caller "$build")  # JPCR_BUILD_DIR too is the caller's
cd "$repo"
if [[ $quick == 1 ]]; then
  out=${out:-$repo/out/reproduce_quick}
  tum=${tum:-$repo/tests/data/tum_fr1_xyz_20}
fi
tum=${tum:-$repo/../shared/data/tum_fr1_xyz_first300}
out=${out:-$repo/report}
[[ $camera == /* ]] || camera=$repo/$camera
runs=$out/runs
mkdir -p "$runs"
# Runs already in --out are reused (an interrupted run resumes) only when this revision made
# them with these options; otherwise their numbers would be reported under the new ones.
revision=$(git rev-parse --short HEAD 2>/dev/null || echo unknown)
# Uncommitted changes to tracked files are part of the revision: a hash of them.
if ! git diff --quiet HEAD 2>/dev/null; then
  revision+="+$(git diff HEAD | sha1sum | cut -c1-8)"
fi
options="revision=$revision size=$size frames=$frames window=$window rail_frames=$rail_frames"
options+=" rail_size=$rail_size real_frames=$real_frames real_jftf=$real_jftf"
options+=" kinect_frames=$kinect_frames study_size=$study_size study_draws=$study_draws"
options+=" tum=$tum camera=$camera"
if [[ -s $runs/options ]] && [[ $(cat "$runs/options") != "$options" ]]; then
  echo "reproduce.sh: $runs holds runs made with other options or at another revision:" >&2
  echo "  then: $(cat "$runs/options")" >&2
  echo "  now:  $options" >&2
  echo "  give another --out, or delete $runs to start afresh" >&2
  exit 2
fi
echo "$options" > "$runs/options"
log=$out/reproduce.log
: > "$log"
say() { echo "reproduce: $*" | tee -a "$log" >&2; }
failed() { say "FAILED: $1 (see $2)"; failures=$((failures + 1)); }  # what, its log

bin=$build/tools
if [[ $no_build == 0 ]]; then
  say "building in $build (log: $out/build.log)"
  { cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release &&
    cmake --build "$build" -j"$(nproc)" --target jpcr_synth jpcr_run jpcr_curvature jpcr_eval \
      bench_icp_peers; } > "$out/build.log" 2>&1 || { say "build failed (see $out/build.log)"; exit 1; }
fi
for p in jpcr_synth jpcr_run jpcr_curvature jpcr_eval bench/bench_icp_peers; do
  [[ -x $bin/$p ]] || { say "$bin/$p is missing (build it, or leave out --no-build)"; exit 1; }
done
methods="icp-ftf q-full j-ftf j-full"
"$bin/jpcr_run" --help | grep -q icp-bundle && methods="icp-ftf icp-bundle q-full j-ftf j-full"
curvature_methods="it ls"  # and the peer, CGAL jet fitting, where jpcr_curvature has it
"$bin/jpcr_curvature" --help | grep -q "jet (the peer" && curvature_methods="it ls jet"
start=$(date +%s) failures=0

# The weight n₀ and the gate grow with the noise σ = k % of the range (README "Range noise"):
# gate = 3 σ for every method; n₀ = 3 σ for the pose methods (jpcr_run: the weight also discounts
# frame-to-frame misassociations) and 10 σ for the single-frame curvature fits (jpcr_curvature:
# only depth edges are outliers there, and the gate drops them). The front end (ICP-ftf, which
# starts every other pose method) smooths the depth with the bilateral filter, its depth σ 2.5 σ
# of the noise at 2 m (0.05 k m): without it, at 2 % and 3 % its normals are noise and it rejects
# every alignment (too_few_points), and at 1 % it is 2.6–3.4x less accurate.
noise_params() {  # k role(pose|curvature) → a params file
  local k=$1 role=$2
  local f=$runs/params_${role}_range${k}.yaml
  if [[ $k == 0 ]]; then : > "$f"; else
    local per=3; [[ $role == curvature ]] && per=10
    local n g b; n=$(/usr/bin/python3 -c "print(round($per * $k / 100, 6))")
    g=$(/usr/bin/python3 -c "print(round(3 * $k / 100, 6))")
    b=$(/usr/bin/python3 -c "print(round(0.05 * $k, 6))")
    printf 'quadric:\n  fit:\n    fair_n0_per_range: %s\n    gate_per_range: %s\n' "$n" "$g" > "$f"
    [[ $role == pose ]] &&
      printf 'frontend:\n  preprocess:\n    bilateral: true\n    bilateral_sigma_depth: %s\n' "$b" >> "$f"
  fi
  echo "$f"
}

# A run of one method, timed; skipped when its report exists (rerun with a fresh --out).
run_method() {  # dataset method params out [extra...]
  local data=$1 method=$2 params=$3 dir=$4; shift 4
  [[ -f $dir/report.json ]] && return 0
  local t0; t0=$(date +%s.%N)
  "$bin/jpcr_run" --dataset "$data" --method "$method" --window "$window" --params "$params" \
    --out "$dir" "$@" > "$dir.log" 2>&1 || {
    failed "jpcr_run $method on $data" "$dir.log"
    return 0
  }
  /usr/bin/python3 -c "import sys; print(float(sys.argv[2]) - float(sys.argv[1]))" "$t0" "$(date +%s.%N)" \
    > "$dir/wall_seconds"
  git rev-parse --short HEAD > "$dir/revision" 2>/dev/null || true
}

# 1. Synthetic scenes × noise: pose methods and curvature methods.
for scene in room_spheres cylinders_boxes torus_saddle; do
  for k in 0 1 2 3; do
    cell=$runs/$scene/range$k
    seq=$cell/sequence
    mkdir -p "$cell"
    noise=range:$k; [[ $k == 0 ]] && noise=none
    [[ -f $seq/groundtruth.txt ]] || "$bin/jpcr_synth" --scene "$scene" --trajectory walk \
      --frames "$frames" --noise "$noise" --size "$size" --seed 1 --out "$seq" --force \
      > "$cell/synth.log" 2>&1 || { failed "jpcr_synth $scene" "$cell/synth.log"; continue; }
    params=$(noise_params "$k" pose)
    for m in $methods; do
      say "$scene noise $k %: $m ($(( $(date +%s) - start )) s)"
      run_method "$seq" "$m" "$params" "$cell/$m"
    done
    # Not the paper's: J-ftf, J-full and ICP-bundle on the depth after the front end's bilateral
    # filter (pipeline.filtered_depth), the depth ICP-ftf tracks.
    if [[ $k != 0 ]]; then
      filtered=$runs/params_pose_range${k}_filtered.yaml
      { cat "$params"; printf 'pipeline:\n  filtered_depth: true\n'; } > "$filtered"
      for m in j-ftf j-full icp-bundle; do
        say "$scene noise $k %: $m on filtered depth ($(( $(date +%s) - start )) s)"
        run_method "$seq" "$m" "$filtered" "$cell/$m-filtered"
      done
    fi
    params=$(noise_params "$k" curvature)
    # The last frame is left out: the curvature table compares the frames J-ftf refines, each
    # the first of a pair (reproduce_report.py).
    for m in $curvature_methods; do
      [[ -d $cell/quad_$m/curvature ]] && continue
      "$bin/jpcr_curvature" --dataset "$seq" --method "$m" --params "$params" \
        --frames "0:$((frames - 1))" --out "$cell/quad_$m" > "$cell/quad_$m.log" 2>&1 ||
        failed "jpcr_curvature $m on $seq" "$cell/quad_$m.log"
    done
  done
done

# 1b. Kinect-like noise (jpcr_synth --noise kinect): ICP-ftf and J-ftf with the built-in weights
# and with configs/kinect_far.yaml, on consecutive frames of the same three scenes.
for scene in room_spheres cylinders_boxes torus_saddle; do
  cell=$runs/$scene/kinect
  seq=$cell/sequence
  mkdir -p "$cell"
  [[ -f $seq/groundtruth.txt ]] || "$bin/jpcr_synth" --scene "$scene" --trajectory walk \
    --frames "$kinect_frames" --noise kinect --size "$size" --seed 1 --out "$seq" --force \
    > "$cell/synth.log" 2>&1 || { failed "jpcr_synth $scene kinect" "$cell/synth.log"; continue; }
  : > "$cell/params.yaml"
  for m in icp-ftf j-ftf; do
    say "$scene kinect noise: $m ($(( $(date +%s) - start )) s)"
    run_method "$seq" "$m" "$cell/params.yaml" "$cell/$m"
  done
  say "$scene kinect noise: j-ftf, configs/kinect_far.yaml ($(( $(date +%s) - start )) s)"
  run_method "$seq" j-ftf configs/kinect_far.yaml "$cell/j-ftf_kinect_far"
done

# 1c. Not in the paper: J-ftf's, Q-full's and the peer ICP-ftf's bias and spread over noise draws
# on the first step of the room_spheres walk (jpcr_eval noise, docs/findings.md "Under heavy range
# noise J-ftf shortens the step"), with the step's motion and with both frames at one pose.
study_run() {  # out-name jpcr_eval-noise-options...
  local name=$1; shift
  [[ -s $name.json ]] && return 0
  say "noise study: $(basename "$name") ($(( $(date +%s) - start )) s)"
  if "$bin/jpcr_eval" noise "$@" --noise-matched --draws "$study_draws" --device cpu --json \
      > "$name.json.tmp" 2> "$name.log" && mv "$name.json.tmp" "$name.json"; then
    git rev-parse --short HEAD > "$name.revision" 2>/dev/null || true
  else
    failed "jpcr_eval noise $*" "$name.log"
  fi
}
study=$runs/noise_study
mkdir -p "$study"
for k in 1 2 3; do
  for method in j-ftf icp-ftf q-full; do
    [[ $method == q-full && $k != 3 ]] && continue
    for motion in 1 0; do
      study_run "$study/${method}_range${k}_motion${motion}" --method "$method" \
        --noise "range:$k" --motion "$motion" --size "$study_size"
    done
  done
done
# 1d. Not in the paper: J-ftf (on the raw and on the filtered depth) against ICP-ftf over the same
# noise draws, on the first step of each scene's walk at the pose tables' size: the expected
# errors behind one cell of those tables.
printf 'pipeline:\n  filtered_depth: true\n' > "$study/filtered_depth.yaml"
for k in 1 2 3; do
  for scene in room_spheres cylinders_boxes torus_saddle; do
    for method in icp-ftf j-ftf; do
      study_run "$study/${method}_${scene}_range${k}" --method "$method" --scene "$scene" \
        --noise "range:$k" --size "$size"
    done
    study_run "$study/j-ftf-filtered_${scene}_range${k}" --method j-ftf --scene "$scene" \
      --noise "range:$k" --size "$size" --params "$study/filtered_depth.yaml"
  done
done

# 2. Drift along a straight rail (10 mm per frame, Kinect-like noise).
rail=$runs/rail
mkdir -p "$rail"
if [[ -f $rail/sequence/groundtruth.txt ]] || "$bin/jpcr_synth" --scene rail_wall \
    --trajectory rail --frames "$rail_frames" --noise kinect --size "$rail_size" --seed 1 \
    --out "$rail/sequence" --force > "$rail/synth.log" 2>&1; then
  : > "$rail/params.yaml"
  for m in icp-ftf pipeline; do
    say "rail: $m ($(( $(date +%s) - start )) s)"
    run_method "$rail/sequence" "$m" "$rail/params.yaml" "$rail/$m"
  done
else
  failed "jpcr_synth rail" "$rail/synth.log"
fi

# 3. Real data: the TUM frames, jpcr and the OpenCV peer on the same frames.
real=$runs/real
mkdir -p "$real"
if [[ -f $tum/depth.txt ]]; then
  : > "$real/params.yaml"
  for m in icp-ftf pipeline; do
    say "real $tum: $m ($(( $(date +%s) - start )) s)"
    run_method "$tum" "$m" "$real/params.yaml" "$real/$m" --frames "0:$real_frames" \
      --config "$camera"
  done
  # J-ftf refines every consecutive pair at full resolution: seconds per pair on the CPU.
  say "real: j-ftf on the first $real_jftf frames"
  run_method "$tum" j-ftf "$real/params.yaml" "$real/j-ftf" --frames "0:$real_jftf" \
    --config "$camera"
  if [[ ! -s $real/peers.md ]]; then
    if "$build/tools/bench/bench_icp_peers" --dataset "$tum" --config "$camera" \
        --frames "$real_frames" --save "$real/peers" > "$real/peers.md.tmp" 2> "$real/peers.log"; then
      mv "$real/peers.md.tmp" "$real/peers.md"
    else
      failed "bench_icp_peers on $tum" "$real/peers.log"
    fi
  fi
else
  say "no TUM data at $tum: the real-data section is left out"
fi

# 4. The report.
say "report ($(( $(date +%s) - start )) s)"
report_status=0
/usr/bin/python3 tools/reproduce_report.py --runs "$runs" --out "$out" --quick "$quick" \
  --size "$size" --frames "$frames" --window "$window" --tum "$tum" \
  --revision "$revision" \
  --command "tools/reproduce.sh $args" --seconds "$(( $(date +%s) - start ))" --bin "$bin" || report_status=$?
say "done in $(( $(date +%s) - start )) s: $out/index.md"
if [[ $failures -gt 0 ]]; then
  say "$failures runs failed: their cells are missing from the report"
  exit 1
fi
[[ $report_status == 0 ]] || { say "the report's checks failed (above)"; exit 1; }
