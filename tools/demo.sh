#!/usr/bin/env bash
# The main job on the embedded default: installs what is missing, builds, generates a small
# ray-traced sequence with exact ground truth (30 frames of room_spheres at 640x480 with 1 %
# range noise), estimates curvature with Quad IT and Quad LS and scores both against the exact
# ground truth. Later steps grow this into the full pipeline run.
set -euo pipefail
cd "$(dirname "$0")/.."
tools/setup.sh

build=${JPCR_BUILD_DIR:-build}
# As tools/test.sh: without a GPU the CUDA code only has to compile, for one architecture.
arch=()
if ! nvidia-smi -L > /dev/null 2>&1; then arch=(-DCMAKE_CUDA_ARCHITECTURES=90); fi
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release "${arch[@]}" > /dev/null
cmake --build "$build" -j"$(nproc)" --target jpcr_synth jpcr_eval jpcr_curvature jpcr_run

out=${JPCR_DEMO_OUT:-out/demo}
mkdir -p "$out"
data=$out/room_spheres
echo "== jpcr demo: a synthetic sequence with exact pose and curvature ground truth =="
"$build/tools/jpcr_synth" --scene room_spheres --trajectory walk --frames 30 --noise range:1 \
  --size 640x480 --seed 1 --out "$data" --force
echo "== trajectory metrics of $data (ground truth against itself) =="
"$build/tools/jpcr_eval" traj --gt "$data/groundtruth.txt" --est "$data/groundtruth.txt" \
  --out "$out/eval.json"
echo "== curvature of the first 3 frames: Quad IT and Quad LS against the exact ground truth =="
printf 'quadric:\n  fit:\n    fair_n0_per_range: 0.1\n    gate_per_range: 0.03\n' > "$out/range1.yaml"
"$build/tools/jpcr_curvature" --dataset "$data" --method it --frames 0:3 --params "$out/range1.yaml" \
  --out "$out/quad_it"
"$build/tools/jpcr_curvature" --dataset "$data" --method ls --frames 0:3 --out "$out/quad_ls"
for m in quad_it quad_ls; do
  echo "-- $m"
  "$build/tools/jpcr_eval" curvature --gt "$data" --est "$out/$m"
done
# The pose methods on a smaller copy of the scene (the CPU back end takes seconds per frame pair).
small=$out/room_spheres_small
echo "== pose refinement: ICP-ftf, J-ftf, J-full and the pipeline on 12 frames at 320x240, 0.5 % noise =="
"$build/tools/jpcr_synth" --scene room_spheres --trajectory walk --frames 12 --noise range:0.5 \
  --size 320x240 --seed 1 --out "$small" --force > /dev/null
printf 'quadric:\n  fit:\n    fair_n0_per_range: 0.015\n    gate_per_range: 0.015\n' > "$out/range05.yaml"
# The 12 frames move 3.1 cm, less than the default keyframe spacing (10 cm), so the pipeline
# run takes a keyframe every 8 mm here: it then refines keyframe pairs and a window.
cp "$out/range05.yaml" "$out/pipeline05.yaml"
printf 'frontend:\n  tracker:\n    keyframe_translation: 0.008\n' >> "$out/pipeline05.yaml"
for method in j-ftf j-full pipeline; do
  params=$out/range05.yaml
  [[ $method == pipeline ]] && params=$out/pipeline05.yaml
  "$build/tools/jpcr_run" --dataset "$small" --method "$method" --params "$params" \
    --out "$out/run_$method" | tail -n +2 > "$out/run_$method.table"
done
echo "errors against ground truth (relative = the paper's Tables I-III):"
head -3 "$out/run_j-ftf.table"
for method in j-full pipeline; do sed -n 3p "$out/run_$method.table"; done
echo "pipeline keyframes: $(grep -vc '^#' "$out/run_pipeline/keyframes.txt") of 12 frames (one every 8 mm)"
echo "pipeline outputs: $out/run_pipeline (trajectory.txt, keyframes.txt, curvature/, report.json)"
echo "curvature maps: $out/quad_it/curvature_png (colour key in the corner), .npy in curvature/"
echo "sequence: $data (TUM layout; run other tools with --config $data/camera.yaml)"
echo "report: $out/eval.json"
