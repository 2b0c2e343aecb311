#!/usr/bin/env bash
# jpcr_eval noise: small J-ftf, Q-full and ICP-ftf studies run and report consistent numbers
# (JSON), and bad options exit 2 (usage) or 1 (input) with a message that names the problem.
set -uo pipefail
build=$1 src=$2
eval_bin=$build/tools/jpcr_eval
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
# shellcheck source=expect.sh
source "$src/tests/tools/expect.sh"

small=(--size 80x60 --noise range:1 --noise-matched --device cpu)
for method in j-ftf q-full icp-ftf; do
  if ! "$eval_bin" noise "${small[@]}" --method "$method" --draws 3 --json > "$tmp/$method.json" \
      2> "$tmp/$method.log"; then
    echo "FAIL: jpcr_eval noise --method $method exited non-zero: $(cat "$tmp/$method.log")"; fail=1
    continue
  fi
  # The summary agrees with the per-draw errors it came from.
  /usr/bin/env python3 - "$tmp/$method.json" <<'PY' || fail=1
import json, math, sys
d = json.load(open(sys.argv[1]))
e = d["errors"]
assert d["draws"] == 3 and len(e) == 3 and all(len(x) == 6 for x in e), d
mean = [sum(x[i] for x in e) / 3 for i in range(6)]
assert all(abs(a - b) <= 1e-12 + 1e-9 * abs(b) for a, b in zip(mean, d["mean_error"])), (mean, d["mean_error"])
rms_t = math.sqrt(sum(sum(v * v for v in x[:3]) for x in e) / 3)
assert abs(rms_t - d["rms_translation_m"]) <= 1e-9 * rms_t, (rms_t, d["rms_translation_m"])
# The RMS error splits into bias and spread: rms^2 = |mean|^2 + (n-1)/n spread^2.
for part, rms, bias, spread in (("t", d["rms_translation_m"], d["bias_translation_m"], d["spread_translation_m"]),
                                ("r", d["rms_rotation_rad"], d["bias_rotation_rad"], d["spread_rotation_rad"])):
    want = math.sqrt(bias * bias + 2 / 3 * spread * spread)
    assert abs(rms - want) <= 1e-9 * rms, (part, rms, want)
assert d["predicted_translation_sd_m"] > 0 and d["step_translation_m"] > 0, d
assert abs(math.sqrt(sum(v * v for v in d["step"][:3])) - d["step_translation_m"]) <= 1e-9 * d["step_translation_m"], d
assert d["verdict"].startswith("too few usable draws"), d["verdict"]
assert d["usable_draws"] == 3 and len(d["draw_verdicts"]) == 3, d
# The quadric normals' error (J-ftf, Q-full): an angle; ICP-ftf fits no quadrics.
if d.get("normal_error_rad") is not None:
    assert 0 <= d["normal_error_rad"] <= math.pi and 0 <= d["normal_error_initial_rad"] <= math.pi, d
print("ok: summary of %s consistent, rms t %.3g m" % (d.get("draws"), d["rms_translation_m"]))
PY
  [[ $method == icp-ftf ]] || grep -q '"normal_error_rad"' "$tmp/$method.json" || {
    echo "FAIL: $method reports no normal_error_rad"; fail=1; }
  [[ $method != icp-ftf ]] || ! grep -q '"normal_error_rad"' "$tmp/$method.json" || {
    echo "FAIL: icp-ftf reports a quadric normal error"; fail=1; }
  # The refiners say where they run (ICP-ftf always runs on the CPU).
  [[ $method == icp-ftf ]] || grep -q "device cpu -> cpu" "$tmp/$method.log" || {
    echo "FAIL: no device line in the log: $(cat "$tmp/$method.log")"; fail=1; }
done
# pipeline.filtered_depth: J-ftf refines the bilateral-filtered depth, so the same draws give
# other errors.
printf 'pipeline:\n  filtered_depth: true\n' > "$tmp/filtered.yaml"
if "$eval_bin" noise "${small[@]}" --draws 3 --json --params "$tmp/filtered.yaml" \
    > "$tmp/filtered.json" 2> /dev/null; then
  /usr/bin/env python3 - "$tmp/j-ftf.json" "$tmp/filtered.json" <<'PY' || fail=1
import json, sys
raw, filtered = (json.load(open(p))["errors"] for p in sys.argv[1:3])
assert len(raw) == len(filtered) == 3
assert any(abs(a - b) > 1e-9 for x, y in zip(raw, filtered) for a, b in zip(x, y)), "filtered_depth had no effect"
print("ok: pipeline.filtered_depth changes J-ftf's errors on the same draws")
# Filtering the depth determines the quadrics better: at 80x60 and 1 % their normals are
# 12.1 deg from the true ones on the raw depth and 9.4 deg on the filtered depth (3 draws).
raw_n, filtered_n = (json.load(open(p))["normal_error_rad"] for p in sys.argv[1:3])
assert filtered_n < raw_n, (filtered_n, raw_n)
print("ok: normals %.1f deg off on the raw depth, %.1f on the filtered" % (raw_n * 57.2958, filtered_n * 57.2958))
PY
  # Without noise the quadrics find the true normals (0.5 deg measured at 80x60; the pattern
  # straddles depth edges there), while 1 % range noise leaves them 12 deg off.
  if "$eval_bin" noise --size 80x60 --noise none --device cpu --draws 2 --json \
      > "$tmp/exact.json" 2> /dev/null; then
    /usr/bin/env python3 - "$tmp/exact.json" "$tmp/j-ftf.json" <<'PY' || fail=1
import json, math, sys
exact, noisy = (json.load(open(p))["normal_error_rad"] for p in sys.argv[1:3])
assert exact < math.radians(2) and noisy > 5 * exact, (exact, noisy)
print("ok: normals %.2f deg off without noise, %.1f deg at 1 %%" % (math.degrees(exact), math.degrees(noisy)))
PY
  else
    echo "FAIL: jpcr_eval noise --noise none exited non-zero"; fail=1
  fi
else
  echo "FAIL: jpcr_eval noise with pipeline.filtered_depth exited non-zero"; fail=1
fi
# Text output: the table and the bias / spread lines.
expect 0 "spread      t" -- "$eval_bin" noise "${small[@]}" --draws 2 --motion 0 --start-offset 1,0.1

printf 'joint:\n  bogus_key: 1\n' > "$tmp/bad.yaml"
expect 2 "draws must be 2-1000" -- "$eval_bin" noise "${small[@]}" --draws 1
expect 2 "seed must be >= 0" -- "$eval_bin" noise "${small[@]}" --seed -3
expect 2 "start-offset expects MM,DEG" -- "$eval_bin" noise "${small[@]}" --start-offset 5
expect 2 "method expects j-ftf, q-full or icp-ftf" -- "$eval_bin" noise "${small[@]}" --method j-full
expect 2 "size expects WIDTHxHEIGHT" -- "$eval_bin" noise --size 80by60
expect 2 "noise-matched needs --noise range:K" -- "$eval_bin" noise --noise kinect --noise-matched
expect 2 "noise-matched needs --noise range:K with K > 0" -- "$eval_bin" noise --noise range:0 \
  --noise-matched
expect 2 "motion must be a finite scale" -- "$eval_bin" noise "${small[@]}" --motion nan
expect 2 "range:K needs a percentage 0 ≤ K ≤ 100" -- "$eval_bin" noise --noise range:-1
expect 1 "bad.yaml" -- "$eval_bin" noise "${small[@]}" --params "$tmp/bad.yaml"
# A min_samples the pattern scaled to these images cannot hold: refused before the study, with
# the file that sets it.
printf 'quadric:\n  fit:\n    min_samples: 110\n' > "$tmp/many.yaml"
expect 1 "many.yaml: quadric: min_samples: 110 exceeds the" -- "$eval_bin" noise --size 160x120 \
  --draws 2 --params "$tmp/many.yaml"
# Draws whose refinement failed keep their start pose; counting them would report the start's
# error (zero from the true pose) as the method's. With no usable draw there is no study.
expect 1 "usable result in 0 of 2 draws" -- "$eval_bin" noise --size 64x48 --noise range:100 --draws 2 --device cpu
expect 2 "0 ≤ K ≤ 100" -- "$eval_bin" noise --size 64x48 --noise range:1e300 --draws 2 --device cpu
expect 1 "no_such_scene" -- "$eval_bin" noise --size 80x60 --scene no_such_scene
expect 0 "usage: jpcr_eval noise" -- "$eval_bin" noise --help
exit $fail
