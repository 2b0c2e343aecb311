#!/usr/bin/python3
"""Writes the reproduction report (report/index.md + figures) from the runs of tools/reproduce.sh.

Every number of ours is read from the runs' report.json / jpcr_eval output; the paper's numbers
(Spek & Drummond, Tables I-III) are the constants below, labelled as the paper's wherever they
appear. Exit status 1 when the report cannot be written or, with --quick, when an ordering the
project guarantees fails (J-ftf below ICP-ftf in translation on the noise-free cells, J-full below
ICP-bundle in every cell, ICP-ftf keeping every alignment).
"""
import argparse
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

SCENES = ["room_spheres", "cylinders_boxes", "torus_saddle"]
NOISES = [0, 1, 2, 3]
# jpcr_eval noise runs of reproduce.sh (section 1c): <method>_range<k>_motion<scale>.
STUDY_RUNS = [f"{method}_range{k}_motion{m}" for method in ("j-ftf", "icp-ftf")
              for k in (1, 2, 3) for m in (1, 0)] + \
    ["q-full_range3_motion1", "q-full_range3_motion0"]
# Section 1d: <method>_<scene>_range<k>, the first step of each scene at the tables' size.
CELL_RUNS = [f"{method}_{scene}_range{k}" for k in (1, 2, 3) for scene in SCENES
             for method in ("icp-ftf", "j-ftf", "j-ftf-filtered")]
POSE_METHODS = ["icp-ftf", "icp-bundle", "q-full", "j-ftf", "j-full"]
# Not the paper's: the joint refiners on the bilateral-filtered depth (pipeline.filtered_depth).
FILTERED_METHODS = ["j-ftf-filtered", "j-full-filtered", "icp-bundle-filtered"]
CURVATURE_METHODS = ["quad_ls", "quad_it", "j-ftf", "j-full"]
CURVATURE_COLUMNS = CURVATURE_METHODS + ["quad_jet"]  # and the peer: CGAL Monge jet fitting
LABEL = {"icp-ftf": "ICP-ftf", "icp-bundle": "ICP-bundle", "q-full": "Q-full", "j-ftf": "J-ftf",
         "j-full": "J-full", "quad_ls": "Quad LS", "quad_it": "Quad IT", "pipeline": "pipeline",
         "quad_jet": "CGAL jet (peer)", "j-ftf-filtered": "J-ftf, filtered depth",
         "j-full-filtered": "J-full, filtered depth",
         "icp-bundle-filtered": "ICP-bundle, filtered depth"}

# The paper's Tables I-III (synthetic Datasets 1-3): RMS translation (m) and rotation (rad) per
# noise level 0..3 % and method (ICP-ftf, ICP-bundle, Q-full, J-ftf, J-full). Our scenes are not
# the paper's scenes (which are not published); they are paired by order only.
PAPER = {
    "Dataset 1": {
        "t": [[4.19e-3, 6.93e-4, 2.79e-4, 2.87e-4, 2.88e-4], [9.22e-3, 1.83e-3, 8.15e-4, 1.02e-3, 6.90e-4],
              [1.52e-2, 3.00e-3, 1.68e-3, 1.92e-3, 1.53e-3], [2.01e-2, 4.45e-3, 2.53e-3, 2.91e-3, 2.37e-3]],
        "r": [[3.36e-3, 5.77e-4, 2.38e-4, 2.31e-4, 2.79e-4], [7.35e-3, 1.69e-3, 3.69e-4, 5.05e-4, 4.98e-4],
              [1.31e-2, 2.69e-3, 6.84e-4, 8.70e-4, 5.54e-4], [1.72e-2, 3.40e-3, 1.21e-3, 1.22e-3, 8.75e-4]]},
    "Dataset 2": {
        "t": [[3.56e-3, 5.42e-5, 3.55e-5, 3.69e-5, 3.58e-5], [4.83e-3, 6.22e-4, 4.74e-4, 4.70e-4, 4.56e-4],
              [8.29e-3, 1.41e-3, 1.07e-3, 9.97e-4, 9.86e-4], [1.17e-2, 2.60e-3, 2.07e-3, 2.07e-3, 1.97e-3]],
        "r": [[2.00e-4, 2.71e-5, 1.14e-5, 1.19e-5, 8.49e-5], [2.46e-3, 1.01e-4, 6.33e-5, 5.92e-5, 9.75e-5],
              [5.70e-3, 5.34e-4, 3.54e-4, 2.01e-4, 2.10e-4], [7.79e-3, 2.32e-3, 1.99e-4, 2.26e-4, 1.89e-4]]},
    "Dataset 3": {
        "t": [[1.94e-3, 1.27e-4, 1.91e-4, 1.23e-4, 1.22e-4], [4.61e-3, 9.78e-4, 9.49e-4, 9.45e-4, 9.39e-4],
              [8.50e-3, 1.95e-3, 1.96e-3, 1.82e-3, 1.83e-3], [1.58e-2, 3.04e-3, 2.69e-3, 2.71e-3, 2.72e-3]],
        "r": [[1.93e-3, 7.09e-5, 1.74e-4, 7.64e-5, 7.40e-5], [4.74e-3, 2.28e-4, 2.73e-4, 2.55e-4, 2.55e-4],
              [8.25e-3, 3.82e-4, 4.99e-4, 4.10e-4, 3.69e-4], [1.30e-2, 7.06e-4, 5.52e-4, 5.99e-4, 5.30e-4]]},
}


def load_json(path):
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def filtered_revisions(a, methods):
    """'; <column> at revision `X`' for filtered-depth runs made at another revision than the
    report's run (a column added to an earlier run), else ''. The runs' revision files hold the
    commit alone; --revision may add '+<diff hash>' for a tree with changes."""
    revs = set()
    for s in SCENES:
        for k in NOISES:
            for m in methods:
                f = os.path.join(a.runs, s, f"range{k}", m, "revision")
                if os.path.exists(f):
                    revs.add((m, open(f).read().strip()))
    commit = a.revision.split("+")[0]
    other = sorted({(m, r) for m, r in revs if r != commit})
    if not other:
        return ""
    return "; " + ", ".join(f"{LABEL[m]} at revision `{r}`" for m, r in other)


def noise_rules(runs):
    """The weight n₀ and the gate per metre of range that reproduce.sh gave each role at 1 %."""
    rules = []
    roles = (("pose", "pose methods (jpcr_run)"), ("curvature", "Quad IT (jpcr_curvature)"))
    for role, who in roles:
        try:
            text = open(os.path.join(runs, f"params_{role}_range1.yaml")).read()
        except OSError:
            continue
        found = dict(re.findall(
            r"(fair_n0_per_range|gate_per_range|bilateral_sigma_depth):\s*([0-9.eE+-]+)", text))
        if "fair_n0_per_range" in found and "gate_per_range" in found:
            rule = (f"{who} n₀ = {found['fair_n0_per_range']} and gate = "
                    f"{found['gate_per_range']} m per m")
            if "bilateral_sigma_depth" in found:
                rule += (f", the front end's (ICP-ftf's) bilateral depth filter at σ = "
                         f"{found['bilateral_sigma_depth']} m")
            rules.append(rule)
    return rules


def fmt(x, spec=".2e"):
    return "–" if x is None or (isinstance(x, float) and not np.isfinite(x)) else format(x, spec)


def pose_errors(run_dir):
    r = load_json(os.path.join(run_dir, "report.json"))
    if not r or not r.get("errors"):
        return None
    e = r["errors"]
    wall = None
    try:
        wall = float(open(os.path.join(run_dir, "wall_seconds")).read())
    except (OSError, ValueError):
        pass
    return {"t": e.get("relative_translation_rms_m"), "r": e.get("relative_rotation_rms_rad"),
            "ate": e.get("ate_rmse_m"), "wall": wall, "frames": r.get("frames"),
            "failed": r.get("keyframes_with_failed_refinement", 0)}


def predicted_step_sd(run_dir):
    """The refiners' own prediction of the relative-pose error the table measures: the RMS over
    every refined step (J-ftf: each pair; J-full/Q-full: each window's successive frames) of the
    step's standard deviation in report.json (step_translation_sd_m, step_rotation_sd_rad, from
    the pose covariance). None for runs without it (icp-bundle, older runs)."""
    r = load_json(os.path.join(run_dir, "report.json"))
    if not r:
        return None
    t, rot = [], []
    for k in r.get("keyframe_records", []):
        for key in ("pair", "window"):
            ref = k.get(key)
            if ref and ref.get("step_translation_sd_m"):
                t += ref["step_translation_sd_m"]
                rot += ref["step_rotation_sd_rad"]
    if not t:
        return None
    return {"t": float(np.sqrt(np.mean(np.square(t)))),
            "r": float(np.sqrt(np.mean(np.square(rot)))), "steps": len(t)}


def front_end_failures(run_dir):
    """Frames after the first whose front-end verdict (verdicts.txt) is not ok."""
    try:
        rows = [l.split() for l in open(os.path.join(run_dir, "verdicts.txt"))
                if l.strip() and not l.startswith("#")]
    except OSError:
        return 0
    return sum(1 for r in rows[1:] if len(r) > 1 and r[1] != "ok")


def stamps(d):
    c = os.path.join(d, "curvature")
    return {f[:-4] for f in os.listdir(c) if f.endswith(".npy")} if os.path.isdir(c) else set()


def sequence_stamps(seq):
    """The stamps of a TUM sequence's depth frames, as its file names spell them."""
    path = os.path.join(seq, "depth.txt")
    if not os.path.isfile(path):
        return set()
    with open(path) as f:
        return {os.path.basename(line.split()[1])[:-4] for line in f
                if line.strip() and not line.startswith("#")}


def own_curvature_stamps(run_dir, method):
    """The stamps (as floats) of the keyframes whose curvature map is the method's own quadrics,
    from report.json's keyframe_records[].curvature. Runs written before that field: J-full
    refines the first keyframe of each window (keyframe 0 and each window's last keyframe but
    the final one), J-ftf every keyframe but the last."""
    r = load_json(os.path.join(run_dir, "report.json"))
    if not r:
        return set()
    k = r.get("keyframe_records", [])
    if k and "curvature" in k[0]:
        return {round(x["stamp"], 6) for x in k if x["curvature"] == method}
    if method == "j-ftf":
        return {round(x["stamp"], 6) for x in k[:-1]}
    ends = [i for i, x in enumerate(k) if x.get("window")]
    return {round(k[i]["stamp"], 6) for i in [0] + ends if i + 1 < len(k)}


def curvature_errors(cell, bin_dir, only=None, support="0", tag="all"):
    """RMS curvature error of each method on the frames every method estimated (the sequence's
    last frame left out: J-ftf refines a frame only as the first of a pair), or on those of them
    in `only` (stamps as floats); over pixels `support` from a crease (jpcr_eval --support)."""
    seq = os.path.join(cell, "sequence")
    dirs = {m: os.path.join(cell, m) for m in CURVATURE_COLUMNS}
    common = None
    for m, d in dirs.items():
        s = stamps(d)
        if not s:
            continue
        common = s if common is None else common & s
    last = max(sequence_stamps(seq), key=float, default=None)
    if common and last is not None and len(common) > 1:
        common.discard(last)
    if common and only is not None:
        common = {c for c in common if round(float(c), 6) in only}
    if not common:
        return {}
    common = sorted(common, key=float)
    out = {}
    for m, d in dirs.items():
        if not stamps(d):
            continue
        sel = os.path.join(cell, "curvature_eval", tag, m)
        shutil.rmtree(sel, ignore_errors=True)
        os.makedirs(os.path.join(sel, "curvature"))
        for s in common:
            os.symlink(os.path.abspath(os.path.join(d, "curvature", s + ".npy")),
                       os.path.join(sel, "curvature", s + ".npy"))
            # The map's sd (jpcr_run, jpcr_curvature with Quad IT): jpcr_eval then scores it too.
            sd = os.path.join(d, "curvature_sd", s + ".npy")
            if os.path.exists(sd):
                os.makedirs(os.path.join(sel, "curvature_sd"), exist_ok=True)
                os.symlink(os.path.abspath(sd), os.path.join(sel, "curvature_sd", s + ".npy"))
        res = subprocess.run([os.path.join(bin_dir, "jpcr_eval"), "curvature", "--gt", seq,
                              "--est", sel, "--support", support, "--json"],
                             capture_output=True, text=True)
        if res.returncode == 0:
            out[m] = json.loads(res.stdout)
    return out


def curvature_sd_section(w, a, curv):
    """How well each map's per-pixel sd (README, "Curvature spread") describes its error, on
    the frames of the curvature table (`curv`: all pixels) and on their interior pixels."""
    methods = ["quad_it", "j-ftf", "j-full"]
    rows = []
    for s in SCENES:
        for k in NOISES:
            cell = os.path.join(a.runs, s, f"range{k}")
            interior = curvature_errors(cell, a.bin, None, "pattern", "all_interior")
            for m in methods:
                e_all, e_int = curv[s, k].get(m, {}), interior.get(m, {})
                if e_all.get("sd_maps"):
                    rows.append((s, k, m, e_all, e_int))
    if not rows:
        return
    w("### Curvature sd against the error (not in the paper)\n")
    w("Each map's per-pixel sd (`curvature_sd/`, README \"Curvature spread\": the spread of "
      "each fit from its own samples) against its error, on the frames of the first table: RMS "
      "error / RMS sd over the pixels with an sd (1: the sd describes the error; above 1: a "
      "bias it does not see), the share of errors within 2 sd (about 98 % for Gaussian errors at "
      "the sd) and the share of the compared pixels that have an sd. Interior pixels as in the "
      "tables above.\n")
    w("| scene | noise | map | all pixels: error / sd | within 2 sd | with an sd | "
      "interior: error / sd | within 2 sd |")
    w("|---|---|---|---|---|---|---|---|")

    def ratio(e):
        return e["rms_where_sd"] / e["sd_rms"] if e.get("sd_rms") else None

    for s, k, m, e_all, e_int in rows:
        share = e_all["sd_compared_pixels"] / e_all["compared_pixels"] \
            if e_all.get("compared_pixels") else None
        w(f"| {s} | {k} % | {LABEL[m]} | {fmt(ratio(e_all), '.2f')} | "
          f"{fmt(e_all.get('within_2sd'), '.1%')} | {fmt(share, '.0%')} | "
          f"{fmt(ratio(e_int), '.2f')} | {fmt(e_int.get('within_2sd'), '.1%')} |")
    w("")


def trajectory_errors(bin_dir, gt, run_dir):
    """jpcr_eval traj's JSON for a run's trajectory.txt against the TUM ground truth, or {}."""
    est = os.path.join(run_dir, "trajectory.txt")
    if not (os.path.exists(gt) and os.path.exists(est)):
        return {}
    res = subprocess.run([os.path.join(bin_dir, "jpcr_eval"), "traj", "--gt", gt, "--est", est,
                          "--json"], capture_output=True, text=True)
    return json.loads(res.stdout) if res.returncode == 0 else {}


def paired_comparison(bin_dir, gt, est, baseline):
    """jpcr_eval traj --baseline's comparison of est with baseline (JSON "baseline"), or {}."""
    if not all(os.path.exists(f) for f in (gt, est, baseline)):
        return {}
    res = subprocess.run([os.path.join(bin_dir, "jpcr_eval"), "traj", "--gt", gt, "--est", est,
                          "--baseline", baseline, "--json"], capture_output=True, text=True)
    return json.loads(res.stdout).get("baseline", {}) if res.returncode == 0 else {}


def rmse(errors, *keys):
    """errors[k1][k2]...["rmse"], or None where a key (e.g. RPE per second on < 1 s) is missing."""
    for k in keys + ("rmse",):
        errors = errors.get(k) if isinstance(errors, dict) else None
    return errors


def zero_rms(cell, frames, support):
    """RMS of the ground-truth κ over the interior pixels of `frames`: the error of κ = 0."""
    d = os.path.join(cell, "sequence", "curvature")
    total, count = 0.0, 0
    for name in os.listdir(d) if os.path.isdir(d) else []:
        if not name.endswith(".npy") or round(float(name[:-4]), 6) not in frames:
            continue
        k = np.load(os.path.join(d, name))
        ok = np.isfinite(k).all(axis=-1)
        n = 2 * support + 1
        inner = sliding_window_view(np.pad(ok, support), (n, n)).all(axis=(-1, -2))
        total += float((k[inner] ** 2).sum())
        count += 2 * int(inner.sum())
    return np.sqrt(total / count) if count else None


def read_tum(path):
    rows = []
    with open(path) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            rows.append([float(x) for x in line.split()[:8]])
    return np.array(rows)


def quat_to_R(q):
    x, y, z, w = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def relative_agreement(path_a, path_b):
    """RMS (m, deg) of the difference between two trajectories' frame-to-frame motions, over the
    consecutive frames of b whose stamps a also has: how far apart two estimators are, with no
    ground truth in it."""
    def poses(path):
        out = {}
        for row in read_tum(path):
            T = np.eye(4)
            T[:3, :3], T[:3, 3] = quat_to_R(row[4:8]), row[1:4]
            out[round(row[0], 6)] = T
        return out
    a, b = poses(path_a), poses(path_b)
    stamps = sorted(b)
    dt, dr = [], []
    for s0, s1 in zip(stamps, stamps[1:]):
        if s0 not in a or s1 not in a:
            continue
        D = np.linalg.inv(np.linalg.inv(a[s0]) @ a[s1]) @ (np.linalg.inv(b[s0]) @ b[s1])
        dt.append(np.linalg.norm(D[:3, 3]))
        dr.append(np.degrees(np.arccos(np.clip((np.trace(D[:3, :3]) - 1) / 2, -1, 1))))
    if not dt:
        return None
    return float(np.sqrt(np.mean(np.square(dt)))), float(np.sqrt(np.mean(np.square(dr)))), len(dt)


def drift_curve(gt_path, est_path):
    """Distance travelled and accumulated translation error per frame, both trajectories expressed
    relative to their first pose (no alignment: drift, as the paper's Fig. 6)."""
    gt, est = read_tum(gt_path), read_tum(est_path)
    g = {round(r[0], 4): r for r in gt}
    pairs = [(g[round(r[0], 4)], r) for r in est if round(r[0], 4) in g]
    if len(pairs) < 2:
        return None

    def T(r):
        M = np.eye(4)
        M[:3, :3] = quat_to_R(r[4:8])
        M[:3, 3] = r[1:4]
        return M

    G0, E0 = np.linalg.inv(T(pairs[0][0])), np.linalg.inv(T(pairs[0][1]))
    dist, err, last = [0.0], [0.0], pairs[0][0][1:4]
    for gr, er in pairs[1:]:
        dist.append(dist[-1] + np.linalg.norm(gr[1:4] - last))
        last = gr[1:4]
        Gi, Ei = G0 @ T(gr), E0 @ T(er)
        err.append(np.linalg.norm(Gi[:3, 3] - Ei[:3, 3]))
    return np.array(dist), np.array(err)


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    for a in ["runs", "out", "size", "tum", "revision", "command", "bin"]:
        ap.add_argument("--" + a, required=True)
    ap.add_argument("--quick", type=int, default=0)
    ap.add_argument("--frames", type=int, required=True)
    ap.add_argument("--window", type=int, required=True)
    ap.add_argument("--seconds", type=int, default=0)
    ap.add_argument("--recomputed-at", default="",
                    help="revision of this script when it re-reads the outputs of an earlier run")
    a = ap.parse_args()
    if not os.path.isdir(a.runs) or not any(
            os.path.isdir(os.path.join(a.runs, s)) for s in SCENES):
        sys.exit(f"reproduce_report: error: {a.runs} holds no runs of tools/reproduce.sh "
                 f"(no directory of {', '.join(SCENES)})")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig_dir = os.path.join(a.out, "figures")
    os.makedirs(fig_dir, exist_ok=True)
    md = []
    w = md.append
    w("# jpcr: reproduction of Spek & Drummond, *Joint Pose and Principal Curvature Refinement "
      "Using Quadrics*\n")
    w(f"Generated by `{a.command}` at git revision `{a.revision}` in {a.seconds} s on this "
      f"machine ({os.cpu_count()} cores). Synthetic scenes at {a.size}, {a.frames} frames per "
      f"sequence (walk trajectory), J-full/Q-full/ICP-bundle windows of {a.window} frames. "
      "Numbers in columns marked (paper) are copied from the paper's Tables I–III (its rows σ, "
      "1σ, 2σ, 3σ read as 0–3 % range noise, evaluation.md's protocol: the first row is taken "
      "to be noise-free); every other number "
      "comes from this run (no hand edits). Every sequence is seed 1, and the synthetic noise "
      "is keyed by seed, frame and pixel: the k % noise is k times one standard-normal draw, the "
      "same in every scene (the three scenes also share the walk). The cells of a table are "
      "therefore one draw, scaled: paired comparisons, not independent samples. The sections "
      "over noise draws below draw afresh.\n")
    rules = noise_rules(a.runs)
    if rules:
        w("Range-noise parameters at σ = 1 % of the range (they scale with k), as `--params`: "
          + "; ".join(rules) + " (README, \"Range noise\").\n")
    if a.recomputed_at:
        w(f"The tables and figures were recomputed from that run's outputs by "
          f"`tools/reproduce_report.py` at revision `{a.recomputed_at}`; no method was re-run "
          "except in the sections that name the revision of their own runs.\n")
    if a.quick:
        w("> **--quick run**: tiny images and few frames, to check that the pipeline of the report "
          "works; its numbers are not the evaluation.\n")

    # Pose tables.
    pose = {}
    for s in SCENES:
        for k in NOISES:
            for m in POSE_METHODS + FILTERED_METHODS:
                pose[s, k, m] = pose_errors(os.path.join(a.runs, s, f"range{k}", m))
    present = [m for m in POSE_METHODS if any(pose[s, k, m] for s in SCENES for k in NOISES)]
    filtered = [m for m in FILTERED_METHODS if any(pose[s, k, m] for s in SCENES for k in NOISES)]
    complete = sum(all(pose[s, k, m] for m in present) for s in SCENES for k in NOISES)
    if complete < len(SCENES) * len(NOISES):
        w(f"> **Incomplete run**: {complete} of {len(SCENES) * len(NOISES)} scene × noise cells "
          "have every pose method; the others show '–' where a run is missing.\n")
    failed_front = []
    for s in SCENES:
        for k in NOISES:
            n = front_end_failures(os.path.join(a.runs, s, f"range{k}", "icp-ftf"))
            if n:
                failed_front.append(f"{s} {k} % ({n} frames)")
    if failed_front:
        w("> **ICP-ftf rejected its own alignment** (verdict not ok, the last motion kept, so its "
          "column there is the constant-velocity fallback and the other methods start from it) in: "
          + ", ".join(failed_front) + ". See each run's `verdicts.txt`.\n")
    w("## Pose accuracy on synthetic scenes (the paper's Tables I–III)\n")
    w("RMS error of each frame's relative pose against ground truth, translation in m and rotation "
      "in rad, per range-noise level σ = k % of the range. ICP-ftf, J-ftf: consecutive frames; "
      "J-full, Q-full, ICP-bundle: sliding windows. Our three scenes stand beside the paper's "
      "Datasets 1–3 by order; the scenes differ, so compare ratios, not absolute values.\n")
    if filtered:
        w("At k > 0 ICP-ftf tracks the depth after a bilateral filter matched to the noise (its "
          "normals are noise without it: it rejects every alignment at 2 % and 3 %), and every "
          "other method starts from it. The paper's methods refine the raw depth; the columns "
          "'filtered depth' (not in the paper) are the refiners on the same filtered "
          "depth as ICP-ftf (`pipeline.filtered_depth`, README \"Range noise\")"
          + filtered_revisions(a, filtered) + ".\n")
    ratios_ftf, ratios_bundle, ratios_filtered, ratios_bundle_filtered = [], [], [], []
    for i, s in enumerate(SCENES):
        paper = PAPER[f"Dataset {i + 1}"]
        for kind, unit in [("t", "translation (m)"), ("r", "rotation (rad)")]:
            w(f"### {s}: {unit} — ours vs paper Dataset {i + 1}\n")
            head = " | ".join(f"{LABEL[m]}" for m in present + filtered)
            phead = " | ".join(f"{LABEL[m]} (paper)" for m in POSE_METHODS)
            fhead = " | ICP-ftf / J-ftf, filtered depth" if filtered else ""
            w(f"| noise | {head} | {phead} | ICP-ftf / J-ftf (ours){fhead} | "
              "ICP-ftf / J-ftf (paper) |")
            w("|" + "---|" * (len(present) + len(filtered) + len(POSE_METHODS) + 3 +
                              (1 if filtered else 0)))
            for k in NOISES:
                ours = [pose[s, k, m][kind] if pose[s, k, m] else None for m in present + filtered]
                ratio = None
                if pose[s, k, "icp-ftf"] and pose[s, k, "j-ftf"] and pose[s, k, "j-ftf"][kind]:
                    ratio = pose[s, k, "icp-ftf"][kind] / pose[s, k, "j-ftf"][kind]
                    if kind == "t":
                        ratios_ftf.append(ratio)
                fratio = ""
                if filtered:
                    f = pose[s, k, "j-ftf-filtered"]
                    fr = pose[s, k, "icp-ftf"][kind] / f[kind] if (
                        f and f[kind] and pose[s, k, "icp-ftf"]) else None
                    fratio = f" | {fmt(fr, '.1f')}x" if fr else " | –"
                    if fr and kind == "t":
                        ratios_filtered.append(fr)
                # A run without consecutive ground truth has no error (null): no ratio.
                b, f = pose[s, k, "icp-bundle"], pose[s, k, "j-full"]
                if kind == "t" and b and f and b["t"] and f["t"] is not None:
                    ratios_bundle.append((s, k, f["t"] / b["t"]))
                bf, ff = pose[s, k, "icp-bundle-filtered"], pose[s, k, "j-full-filtered"]
                if kind == "t" and bf and ff and bf["t"] and ff["t"] is not None:
                    ratios_bundle_filtered.append(ff["t"] / bf["t"])
                pr = paper[kind][k][0] / paper[kind][k][3]
                w(f"| {k} % | " + " | ".join(fmt(x) for x in ours) + " | " +
                  " | ".join(fmt(x) for x in paper[kind][k]) +
                  f" | {fmt(ratio, '.1f')}x{fratio} | {pr:.1f}x |")
            w("")

    # The spread the refiners predict for themselves.
    spread = {(s, k, m): predicted_step_sd(os.path.join(a.runs, s, f"range{k}", m))
              for s in SCENES for k in NOISES for m in ("j-ftf", "j-full")}
    spread_ratio = {}  # (s, k) → J-full / J-ftf predicted, (translation, rotation)
    for s in SCENES:
        for k in NOISES:
            f, j = spread[s, k, "j-ftf"], spread[s, k, "j-full"]
            if f and j and f["t"] > 0 and f["r"] > 0:
                spread_ratio[s, k] = (j["t"] / f["t"], j["r"] / f["r"])
    if any(spread.values()):
        w("### J-ftf and J-full: measured error against their predicted spread\n")
        steps = max(v["steps"] for v in spread.values() if v)
        w("Predicted = RMS over the refined steps of each step's standard deviation in report.json "
          "(`step_translation_sd_m`, from the pose covariance reuse · σ² S⁻¹: the spread under "
          "the sensor noise, not the bias). Measured = the tables above. Each cell has "
          f"{steps} steps or fewer, so from the noise alone a measured RMS scatters by about "
          f"±{100 / np.sqrt(6 * steps):.0f} % around the predicted one (1 / √(2 · 3 · steps) for "
          "Gaussian errors in three axes). To first order the method predicts the same spread "
          "for both: with a free quadric per pixel, a pose step is fixed by the two frames it "
          "joins, and the window's other frames add curvature, not pose (docs/findings.md, "
          "\"J-full and J-ftf\").\n")
        w("| scene | noise | J-ftf t measured | J-ftf t predicted | J-full t measured | "
          "J-full t predicted | J-full / J-ftf predicted, t | r |")
        w("|---|---|---|---|---|---|---|---|")
        for s in SCENES:
            for k in NOISES:
                f, j = spread[s, k, "j-ftf"], spread[s, k, "j-full"]
                mf, mj = pose[s, k, "j-ftf"], pose[s, k, "j-full"]
                rt, rr = spread_ratio.get((s, k), (None, None))
                w(f"| {s} | {k} % | {fmt(mf['t'] if mf else None)} | {fmt(f['t'] if f else None)} | "
                  f"{fmt(mj['t'] if mj else None)} | {fmt(j['t'] if j else None)} | "
                  f"{fmt(rt, '.3f')} | {fmt(rr, '.3f')} |")
        w("")
        # Measured / predicted per noise level: about 1 where the noise's spread dominates,
        # above where the bias does (it grows with σ², the spread with σ).
        parts = []
        for k in NOISES:
            q = [pose[s, k, m]["t"] / spread[s, k, m]["t"] for s in SCENES
                 for m in ("j-ftf", "j-full")
                 if pose[s, k, m] and spread[s, k, m] and spread[s, k, m]["t"] > 0]
            if q:
                parts.append(f"{k} %: {min(q):.1f}–{max(q):.1f}")
        if parts:
            w("Measured / predicted, J-ftf and J-full, by noise level: " + "; ".join(parts) +
              ". Near 1 the noise's spread explains the error; well above 1 a bias does (it "
              "grows as σ², the spread as σ; README, \"Range noise\"). At 0 % the residual is "
              "the quadric model's error, not noise, and the prediction does not apply.\n")

    # Curvature.
    w("## Curvature accuracy (the paper's Fig. 7)\n")
    w("RMS error of κ1 and κ2 together (1/m) over pixels valid in both the estimate and the exact "
      "ground truth, on the frames every method estimated; coverage = fraction of ground-truth "
      "pixels returned.\n")
    curv = {}
    order_holds = 0
    cells = 0
    for s in SCENES:
        for k in NOISES:
            curv[s, k] = curvature_errors(os.path.join(a.runs, s, f"range{k}"), a.bin)
    w("| scene | noise | " + " | ".join(LABEL[m] for m in CURVATURE_COLUMNS) +
      " | order J-full < J-ftf < Quad IT < Quad LS |")
    w("|" + "---|" * (len(CURVATURE_COLUMNS) + 3))
    for s in SCENES:
        for k in NOISES:
            c = curv[s, k]
            vals = [c[m]["rms"] if m in c else None for m in CURVATURE_COLUMNS]
            cover = [c[m]["coverage"] if m in c else None for m in CURVATURE_COLUMNS]
            holds = None
            if all(m in c for m in CURVATURE_METHODS):
                cells += 1
                rms = [c[m]["rms"] for m in CURVATURE_METHODS]  # LS, IT, J-ftf, J-full
                holds = rms[3] < rms[2] < rms[1] < rms[0]
                order_holds += holds
            w(f"| {s} | {k} % | " + " | ".join(
                f"{fmt(v, '.3f')} ({fmt(cv, '.0%')})" for v, cv in zip(vals, cover)) +
              f" | {'yes' if holds else ('no' if holds is not None else '–')} |")
    w("")
    own = {}
    for s in SCENES:
        for k in NOISES:
            cell = os.path.join(a.runs, s, f"range{k}")
            frames = (own_curvature_stamps(os.path.join(cell, "j-full"), "j-full") &
                      own_curvature_stamps(os.path.join(cell, "j-ftf"), "j-ftf"))
            interior = curvature_errors(cell, a.bin, frames, "pattern", "jfull_frames_interior")
            # jpcr_eval resolves "pattern" to the fit pattern's span at the maps' width.
            span = next((e["support_radius_px"] for e in interior.values()), None)
            own[s, k] = (len(frames), curvature_errors(cell, a.bin, frames, "0", "jfull_frames"),
                         interior, zero_rms(cell, frames, span) if span else None)
    spans = {e["support_radius_px"] for c in own.values() for e in c[2].values()}
    w("J-full refines the quadrics of one keyframe per window, the window's first; its map of "
      "every other keyframe is Quad IT's (report.json `keyframe_records[].curvature` says whose "
      "each map is), so the table above gives J-full Quad IT's numbers on those frames. The table "
      "below compares every method on J-full's own keyframes only, and over two pixel sets: all "
      "of them, and the interior ones, whose whole fit pattern (±" +
      "/".join(str(x) for x in sorted(spans)) + " px, `jpcr_eval curvature --support "
      "pattern`) has ground truth, i.e. sees no crease, rim or silhouette. Near those edges "
      "every patch method fits a surface that is not there. "
      "Values are interior RMS (1/m) with the coverage of the interior pixels; 'zero' is the "
      "RMS of the ground truth itself there, the error of answering κ = 0: a method above it "
      "tells, on average, nothing about the curvature at that noise.\n")
    w("| scene | noise | frames | " + " | ".join(LABEL[m] for m in CURVATURE_COLUMNS) +
      " | zero | order, interior | order, all pixels |")
    w("|" + "---|" * (len(CURVATURE_COLUMNS) + 6))
    own_holds = {"interior": 0, "all": 0}
    own_cells = 0
    for s in SCENES:
        for k in NOISES:
            n, c_all, c_int, zero = own[s, k]
            holds = {}
            if all(m in c_all and m in c_int for m in CURVATURE_METHODS):
                own_cells += 1
                for name, c in (("interior", c_int), ("all", c_all)):
                    rms = [c[m]["rms"] for m in CURVATURE_METHODS]  # LS, IT, J-ftf, J-full
                    holds[name] = rms[3] < rms[2] < rms[1] < rms[0]
                    own_holds[name] += holds[name]
            yn = lambda name: "yes" if holds.get(name) else ("no" if name in holds else "–")
            w(f"| {s} | {k} % | {n} | " + " | ".join(
                f"{fmt(c_int[m]['rms'] if m in c_int else None, '.3f')} "
                f"({fmt(c_int[m]['coverage'] if m in c_int else None, '.0%')})"
                for m in CURVATURE_COLUMNS) + f" | {fmt(zero, '.3f')} | {yn('interior')} | "
              f"{yn('all')} |")
    w("")
    w("J-ftf refines every keyframe but the last, so it has more frames of its own. On those, "
      "interior pixels (the single-frame fits and J-ftf; J-full is left out, as it refined only "
      "the first of them):\n")
    w("| scene | noise | frames | Quad LS | Quad IT | J-ftf | order J-ftf < Quad IT < Quad LS |")
    w("|---|---|---|---|---|---|---|")
    ftf_holds = ftf_cells = 0
    for s in SCENES:
        for k in NOISES:
            cell = os.path.join(a.runs, s, f"range{k}")
            frames = own_curvature_stamps(os.path.join(cell, "j-ftf"), "j-ftf")
            c = curvature_errors(cell, a.bin, frames, "pattern", "jftf_frames_interior")
            three = ["quad_ls", "quad_it", "j-ftf"]
            holds = None
            if all(m in c for m in three):
                ftf_cells += 1
                holds = c["j-ftf"]["rms"] < c["quad_it"]["rms"] < c["quad_ls"]["rms"]
                ftf_holds += holds
            n = c["j-ftf"]["frames"] if "j-ftf" in c else 0
            w(f"| {s} | {k} % | {n} | " + " | ".join(
                fmt(c[m]["rms"] if m in c else None, ".3f") for m in three) +
              f" | {'yes' if holds else ('no' if holds is not None else '–')} |")
    w("")
    curvature_sd_section(w, a, curv)
    fig, axes = plt.subplots(2, len(SCENES), figsize=(4.2 * len(SCENES), 6.4), squeeze=False)
    for row, (title, rms_of) in enumerate([
            ("all compared frames and pixels", lambda s, k, m: curv[s, k].get(m, {}).get("rms")),
            ("J-full's keyframes, interior", lambda s, k, m: own[s, k][2].get(m, {}).get("rms"))]):
        for ax, s in zip(axes[row], SCENES):
            for m in CURVATURE_COLUMNS:
                ys = [rms_of(s, k, m) for k in NOISES]
                ax.plot(NOISES, [np.nan if y is None else y for y in ys], marker="o",
                        label=LABEL[m])
            zeros = [own[s, k][3] for k in NOISES if own[s, k][3] is not None]
            if row == 1 and zeros:  # the same frames at every noise level
                ax.axhline(zeros[0], color="gray", ls="--", lw=1, label="κ = 0 (zero)")
            ax.set_title(f"{s}: {title}", fontsize=9)
            ax.set_xlabel("range noise σ (% of range)")
            ax.set_ylabel("RMS curvature error (1/m)")
            ax.grid(alpha=0.3)
    axes[0][0].legend()
    axes[1][0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(fig_dir, "curvature_vs_noise.png"), dpi=110)
    plt.close(fig)
    w("![curvature error vs noise](figures/curvature_vs_noise.png)\n")

    # Drift.
    w("## Drift along a straight rail (the paper's Fig. 6)\n")
    rail = os.path.join(a.runs, "rail")
    fig, ax = plt.subplots(figsize=(6, 3.6))
    w("| method | distance (m) | final translation error (m) | per metre | wall (s) |")
    w("|---|---|---|---|---|")
    for m in ["icp-ftf", "pipeline"]:
        est = os.path.join(rail, m, "trajectory.txt")
        if not os.path.exists(est):
            continue
        d = drift_curve(os.path.join(rail, "sequence", "groundtruth.txt"), est)
        if d is None:
            continue
        ax.plot(d[0], d[1], label=LABEL.get(m, m))
        e = pose_errors(os.path.join(rail, m)) or {}
        w(f"| {LABEL.get(m, m)} | {d[0][-1]:.3f} | {d[1][-1]:.4f} | "
          f"{fmt(d[1][-1] / max(d[0][-1], 1e-9), '.4f')} | {fmt(e.get('wall'), '.0f')} |")
    w("")
    ax.set_xlabel("distance travelled (m)")
    ax.set_ylabel("accumulated translation error (m)")
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(os.path.join(fig_dir, "rail_drift.png"), dpi=110)
    plt.close(fig)
    w("![drift along the rail](figures/rail_drift.png)\n")

    # Kinect-like noise.
    kinect = [(sc, os.path.join(a.runs, sc, "kinect")) for sc in SCENES]
    kinect = [(sc, d) for sc, d in kinect if os.path.isdir(d)]
    if kinect:
        w("## Kinect-like noise (not in the paper)\n")
        w("`jpcr_synth --noise kinect` (axial noise 1.2 mm + 1.9 mm/m² (z − 0.4 m)², 1/8 px "
          "disparity quantisation, dropouts at grazing angles and depth edges), the walk "
          "trajectory, consecutive frames. J-ftf with the built-in weights (method.md's n₀ = 4 mm, "
          "gate 14 mm) and with `configs/kinect_far.yaml` (n₀ = 20 mm, gate 50 mm). RMS relative "
          "error; ratio = ICP-ftf / J-ftf (above 1: J-ftf better).\n")
        revs = sorted({open(os.path.join(d, m, "revision")).read().strip()
                       for _, d in kinect for m in ["icp-ftf", "j-ftf", "j-ftf_kinect_far"]
                       if os.path.exists(os.path.join(d, m, "revision"))})
        if revs:
            w(f"These runs were made at revision {', '.join(f'`{r}`' for r in revs)}.\n")
        w("| scene | frames | ICP-ftf t (m) | J-ftf t (m) | J-ftf kinect_far t (m) | "
          "ICP-ftf r (rad) | J-ftf r (rad) | J-ftf kinect_far r (rad) | ratio t, built-in | ratio t, kinect_far |")
        w("|---|---|---|---|---|---|---|---|---|---|")
        for sc, d in kinect:
            e = {m: pose_errors(os.path.join(d, m)) or {}
                 for m in ["icp-ftf", "j-ftf", "j-ftf_kinect_far"]}

            def ratio(m):
                t0, t1 = e["icp-ftf"].get("t"), e[m].get("t")
                return f"{t0 / t1:.2f}x" if t0 and t1 else "–"
            w(f"| {sc} | {e['icp-ftf'].get('frames', '–')} | "
              + " | ".join(fmt(e[m].get(q)) for q in ["t", "r"]
                           for m in ["icp-ftf", "j-ftf", "j-ftf_kinect_far"])
              + f" | {ratio('j-ftf')} | {ratio('j-ftf_kinect_far')} |")
        w("")

    # Noise study (jpcr_eval noise).
    study_dir = os.path.join(a.runs, "noise_study")
    study = {}
    for name in STUDY_RUNS + CELL_RUNS:
        d = load_json(os.path.join(study_dir, name + ".json"))
        if d:
            study[name] = d
    def normals(d):  # Quad IT → refined, in degrees; runs before the field: –
        if not d or "normal_error_rad" not in d:
            return "–"
        return (f"{math.degrees(d['normal_error_initial_rad']):.1f} → "
                f"{math.degrees(d['normal_error_rad']):.1f}")

    if study:
        w("## Bias and spread over noise draws (not in the paper)\n")
        w("`jpcr_eval noise`: one frame pair, the first step of the seed-1 room_spheres walk, "
          "rendered once; each draw adds fresh range noise and refines from the true pose "
          "(n₀ = gate = 3 σ; ICP-ftf, the peer, on the noise-matched bilateral-filtered depth as "
          "in the tables above). Bias = |mean error| over the draws, in mm and mrad, with its size "
          "in standard errors of the mean; spread = RMS length of the errors about that mean; "
          "predicted = the refiner's own translation_sd / rotation_sd; step kept = the estimated "
          "step's length along the true one, as a fraction of it (translation, rotation); "
          "normals = the mean angle of the reference frame's quadric normals from the true "
          "surface normals, from Quad IT → after refinement (J-ftf, Q-full). "
          "'motion ×0' renders both frames at the same pose.\n")
        revs = sorted({open(p).read().strip() for p in
                       (os.path.join(study_dir, n + ".revision") for n in study)
                       if os.path.exists(p)})
        if revs:
            w(f"These runs were made at revision {', '.join(f'`{r}`' for r in revs)}.\n")
        w("| method | noise | motion | draws | bias t (mm) | bias r (mrad) | spread t (mm) | "
          "spread r (mrad) | predicted t (mm) / r (mrad) | step kept (t, r) | normals (deg) |")
        w("|---|---|---|---|---|---|---|---|---|---|---|")
        for name in STUDY_RUNS:
            d = study.get(name)
            if not d:
                continue
            method, noise, motion = name.split("_")
            kept = "–"
            step = d.get("step") or []
            if len(step) == 6 and any(step[:3]) and any(step[3:]):
                m = d["mean_error"]
                frac = [1 + sum(m[i] * step[i] for i in r) / sum(step[i] ** 2 for i in r)
                        for r in (range(3), range(3, 6))]
                kept = f"{frac[0]:.2f}, {frac[1]:.2f}"
            w(f"| {LABEL.get(method, method)} | {noise[5:]} % | ×{motion[6:]} | {d['draws']} | "
              f"{1e3 * d['bias_translation_m']:.2f} "
              f"({fmt(d['bias_translation_standard_errors'], '.1f')}) | "
              f"{1e3 * d['bias_rotation_rad']:.2f} ({fmt(d['bias_rotation_standard_errors'], '.1f')}) | "
              f"{1e3 * d['spread_translation_m']:.2f} | {1e3 * d['spread_rotation_rad']:.2f} | "
              f"{1e3 * d['predicted_translation_sd_m']:.2f} / "
              f"{1e3 * d['predicted_rotation_sd_rad']:.2f} | {kept} | {normals(d)} |")
        w("")
        study_cells = [(sc, k) for k in (1, 2, 3) for sc in SCENES
                 if f"icp-ftf_{sc}_range{k}" in study and f"j-ftf_{sc}_range{k}" in study]
        if study_cells:
            draws = study[f"j-ftf_{study_cells[0][0]}_range{study_cells[0][1]}"]["draws"]
            w(f"### J-ftf against ICP-ftf over noise draws, each scene's first step at {a.size}\n")
            w(f"The same comparison as one cell of the pose tables, but over {draws} noise draws "
              "of one step instead of one draw of each step: RMS error over the draws (mm, "
              "mrad); ratio = ICP-ftf / J-ftf (above 1: J-ftf better); J-ftf's bias and spread "
              "as above.\n")
            w("| scene | noise | ICP-ftf t | J-ftf t | J-ftf, filtered depth t | ICP-ftf r | "
              "J-ftf r | J-ftf, filtered depth r | ratio t | ratio r | ratio t, filtered | "
              "ratio r, filtered | J-ftf bias t / spread t | J-ftf normals (deg), raw / filtered |")
            w("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
            better = {"j-ftf": [0, 0], "j-ftf-filtered": [0, 0]}
            ties = 0  # J-ftf's translation within 1 % of ICP-ftf's: a win or loss by a hair
            for sc, k in study_cells:
                i = study[f"icp-ftf_{sc}_range{k}"]
                runs = {m: study.get(f"{m}_{sc}_range{k}") for m in better}
                ratio = {}
                for m, d in runs.items():
                    if d:
                        ratio[m] = (i["rms_translation_m"] / d["rms_translation_m"],
                                    i["rms_rotation_rad"] / d["rms_rotation_rad"])
                        better[m][0] += ratio[m][0] > 1
                        better[m][1] += ratio[m][1] > 1
                        ties += m == "j-ftf" and abs(ratio[m][0] - 1) < 0.01

                def mm(d, key):
                    return f"{1e3 * d[key]:.3f}" if d else "–"

                def rx(m, q):
                    return f"{ratio[m][q]:.2f}x" if m in ratio else "–"
                j = runs["j-ftf"]
                w(f"| {sc} | {k} % | {mm(i, 'rms_translation_m')} | {mm(j, 'rms_translation_m')} | "
                  f"{mm(runs['j-ftf-filtered'], 'rms_translation_m')} | "
                  f"{mm(i, 'rms_rotation_rad')} | {mm(j, 'rms_rotation_rad')} | "
                  f"{mm(runs['j-ftf-filtered'], 'rms_rotation_rad')} | {rx('j-ftf', 0)} | "
                  f"{rx('j-ftf', 1)} | {rx('j-ftf-filtered', 0)} | {rx('j-ftf-filtered', 1)} | "
                  f"{1e3 * j['bias_translation_m']:.2f} / {1e3 * j['spread_translation_m']:.2f} | "
                  f"{normals(j)} / {normals(runs['j-ftf-filtered'])} |")
            w("")
            n = len(study_cells)
            w(f"J-ftf's RMS error is below ICP-ftf's in {better['j-ftf'][0]} of {n} cells in "
              f"translation ({ties} within 1 %) and {better['j-ftf'][1]} of {n} in rotation; on the filtered depth "
              f"(`pipeline.filtered_depth`, the depth ICP-ftf tracks) in "
              f"{better['j-ftf-filtered'][0]} of {n} and {better['j-ftf-filtered'][1]} of {n}.\n")

    # Real data.
    real = os.path.join(a.runs, "real")
    if os.path.isdir(real):
        w(f"## Real data: TUM fr1/xyz (`{a.tum}`)\n")
        w("`jpcr_eval traj` against the sequence's ground truth (TUM conventions: ATE after Horn "
          "alignment; RPE without alignment, per frame and per second).\n")
        w("| method | frames | ATE (m) | RPE (m/frame) | RPE (deg/frame) | RPE (m/s) | "
          "RPE (deg/s) | wall (s) |")
        w("|---|---|---|---|---|---|---|---|")
        gt = os.path.join(a.tum, "groundtruth.txt")
        # J-ftf runs on the first frames only: ICP-ftf's poses of those frames (frame to frame,
        # so the same as an ICP-ftf run on them) give the row to compare it with. They go to a
        # scratch directory, not into the runs.
        scratch = tempfile.TemporaryDirectory()
        same_name = "icp-ftf, J-ftf's frames"
        jftf_traj = os.path.join(real, "j-ftf", "trajectory.txt")
        icp_traj = os.path.join(real, "icp-ftf", "trajectory.txt")
        jftf_stamps = set()
        if os.path.exists(jftf_traj):
            jftf_stamps = {row[0] for row in read_tum(jftf_traj)}
        same_frames = 0
        if jftf_stamps and os.path.exists(icp_traj):
            with open(icp_traj) as src, \
                    open(os.path.join(scratch.name, "trajectory.txt"), "w") as dst:
                for line in src:
                    f = line.split()
                    keep = f and not line.startswith("#") and float(f[0]) in jftf_stamps
                    same_frames += bool(keep)
                    if keep or line.startswith("#"):
                        dst.write(line)
        dirs = {"icp-ftf": os.path.join(real, "icp-ftf"), same_name: scratch.name,
                "j-ftf": os.path.join(real, "j-ftf"), "pipeline": os.path.join(real, "pipeline")}
        labels = {same_name: f"ICP-ftf, J-ftf's {same_frames} frames"}
        real_rows = {}
        for m, run in dirs.items():
            r = {"frames": same_frames} if m == same_name else load_json(
                os.path.join(run, "report.json"))
            e = pose_errors(run) or {}
            t = trajectory_errors(a.bin, gt, run)
            if not r or not t:
                continue
            real_rows[m] = t
            w(f"| {labels.get(m, LABEL.get(m, m))} | {r['frames']} | "
              f"{fmt(rmse(t, 'ate', 'translation_m'), '.4f')} | "
              f"{fmt(rmse(t, 'rpe_per_frame', 'translation_m'), '.5f')} | "
              f"{fmt(rmse(t, 'rpe_per_frame', 'rotation_deg'), '.3f')} | "
              f"{fmt(rmse(t, 'rpe_per_second', 'translation_m'), '.5f')} | "
              f"{fmt(rmse(t, 'rpe_per_second', 'rotation_deg'), '.3f')} | "
              f"{fmt(e.get('wall'), '.0f')} |")
        w("")
        pipeline_traj = os.path.join(real, "pipeline", "trajectory.txt")
        paired = paired_comparison(a.bin, gt, pipeline_traj, icp_traj)
        if paired:
            t, r = paired["translation"], paired["rotation"]
            w(f"The pipeline against ICP-ftf, frame pair by frame pair (`jpcr_eval traj --baseline`: "
              f"ratio of the RMS relative errors, pipeline / ICP-ftf, with a 95 % interval from a "
              f"paired block bootstrap over {paired['pairs']} frame pairs): translation "
              f"{t['ratio']:.3f} [{t['low']:.3f}, {t['high']:.3f}], {t['verdict']}; rotation "
              f"{r['ratio']:.3f} [{r['low']:.3f}, {r['high']:.3f}], {r['verdict']}.\n")
        ratio = [None, None]
        if same_name in real_rows and "j-ftf" in real_rows:
            for i, q in enumerate(("translation_m", "rotation_deg")):
                x = rmse(real_rows["j-ftf"], "rpe_per_frame", q)
                y = rmse(real_rows[same_name], "rpe_per_frame", q)
                ratio[i] = x / y if x is not None and y else None
        if None not in ratio:
            w(f"On the same {same_frames} frames, J-ftf's per-frame RPE is "
              f"{ratio[0]:.2f}x ICP-ftf's in translation and {ratio[1]:.2f}x in rotation "
              "(below 1: J-ftf better).\n")
        agree = (relative_agreement(icp_traj, jftf_traj)
                 if os.path.exists(icp_traj) and os.path.exists(jftf_traj) else None)
        rpe_t = rmse(real_rows[same_name], "rpe_per_frame", "translation_m") \
            if same_name in real_rows else None
        if agree and rpe_t:
            shared = ("Most of the per-frame RPE is thus shared by both methods: error of the "
                      "ground truth itself (motion capture, time stamps) or of the sensor model "
                      "both use." if agree[0] < 0.5 * rpe_t else "")
            w(f"How much of that the ground truth can tell: J-ftf's and ICP-ftf's frame-to-frame "
              f"motions differ from each other by {agree[0]:.5f} m and {agree[1]:.3f} deg "
              f"(RMS over {agree[2]} pairs), while each differs from the ground truth's by about "
              f"{rpe_t:.5f} m and "
              f"{fmt(rmse(real_rows[same_name], 'rpe_per_frame', 'rotation_deg'), '.3f')} deg. "
              f"{shared}\n")
        scratch.cleanup()
        peers = os.path.join(real, "peers.md")
        if os.path.exists(peers) and os.path.getsize(peers):
            w("The OpenCV peer on the same frames, in the same process (`bench_icp_peers`):\n")
            w(open(peers).read().strip() + "\n")

    # Curvature pictures (Fig. 1).
    w("## Curvature maps (the paper's Fig. 1)\n")
    pics = [("synthetic keyframe (J-full)", os.path.join(a.runs, SCENES[0], "range1", "j-full")),
            ("real keyframe (pipeline)", os.path.join(real, "pipeline"))]
    for title, d in pics:
        png = os.path.join(d, "curvature_png")
        if os.path.isdir(png) and os.listdir(png):
            name = sorted(os.listdir(png))[0]
            dst = title.split()[0] + "_curvature.png"
            shutil.copy(os.path.join(png, name), os.path.join(fig_dir, dst))
            w(f"**{title}**, `{name}` (colour key in the corner):\n\n![{title}](figures/{dst})\n")

    # Timings.
    w("## Timings on this machine (wall seconds per sequence)\n")
    w("| scene | noise | " + " | ".join(LABEL[m] for m in present) + " |")
    w("|" + "---|" * (len(present) + 2))
    for s in SCENES:
        for k in NOISES:
            w(f"| {s} | {k} % | " + " | ".join(
                fmt(pose[s, k, m]["wall"] if pose[s, k, m] else None, ".0f") for m in present) + " |")
    w("")

    # Claims.
    w("## Where jpcr stands against the paper's claims\n")
    paper_ftf = [row[0] / row[3] for d in PAPER.values() for row in d["t"]]
    paper_bundle = [100 * (1 - row[4] / row[1]) for d in PAPER.values() for row in d["t"]]
    if ratios_ftf:
        beat = sum(r > 1 for r in ratios_ftf)
        close = sum(abs(r - 1) < 0.02 for r in ratios_ftf)
        w(f"- **J-ftf vs ICP-ftf** in translation (paper: \"a consistent order of magnitude\"; "
          f"its Tables I–III {min(paper_ftf):.1f}x – {max(paper_ftf):.1f}x): ours "
          f"{min(ratios_ftf):.1f}x – {max(ratios_ftf):.1f}x, J-ftf lower in {beat} of "
          f"{len(ratios_ftf)} scene × noise cells ({close} of them within 2 %).")
    if ratios_filtered:
        w(f"- **J-ftf on the filtered depth vs ICP-ftf** in translation (not in the paper; both "
          f"on the same filtered depth): {min(ratios_filtered):.1f}x – {max(ratios_filtered):.1f}x, lower in "
          f"{sum(r > 1 for r in ratios_filtered)} of {len(ratios_filtered)} noisy cells.")
    if ratios_bundle:
        better = [f"{s} {k} %" for s, k, r in ratios_bundle if r < 1]
        w(f"- **J-full vs ICP-bundle** in translation (paper: \"approximately 30%-50%\" better; "
          f"its Tables I–III {min(paper_bundle):.0f}–{max(paper_bundle):.0f} %): J-full / ICP-bundle "
          f"= {min(r for _, _, r in ratios_bundle):.2f} – {max(r for _, _, r in ratios_bundle):.2f}; "
          f"J-full better in {len(better)} of {len(ratios_bundle)} cells.")
    else:
        w("- **J-full vs ICP-bundle**: no ICP-bundle runs in this report.")
    if ratios_bundle_filtered:
        r = ratios_bundle_filtered
        w(f"- **J-full vs ICP-bundle, both on the filtered depth** in translation (not in the "
          f"paper; on the raw depth ICP-bundle's normals are noise): J-full / ICP-bundle = "
          f"{min(r):.2f} – {max(r):.2f}; J-full better in {sum(x < 1 for x in r)} of {len(r)} "
          f"noisy cells.")
    full_ftf = [(s, k) for s in SCENES for k in NOISES
                if pose[s, k, "j-full"] and pose[s, k, "j-ftf"]]
    if full_ftf:
        below = sum(pose[s, k, "j-full"]["t"] < pose[s, k, "j-ftf"]["t"] for s, k in full_ftf)
        line = (f"- **J-full vs J-ftf** (translation): J-full lower in {below} of "
                f"{len(full_ftf)} cells.")
        if spread_ratio:
            ratios = [x for pair in spread_ratio.values() for x in pair]
            gap = 100 * max(abs(x - 1) for x in ratios)
            larger = ("J-full's" if all(x >= 1 for x in ratios) else
                      "J-ftf's" if all(x <= 1 for x in ratios) else "either's")
            line += (f" Their predicted spreads agree to within {gap:.1f} %, {larger} the "
                     f"larger: J-full / J-ftf "
                     f"{min(r for r, _ in spread_ratio.values()):.3f} – "
                     f"{max(r for r, _ in spread_ratio.values()):.3f} in translation, "
                     f"{min(r for _, r in spread_ratio.values()):.3f} – "
                     f"{max(r for _, r in spread_ratio.values()):.3f} in rotation, over "
                     f"{len(spread_ratio)} cells: the method does not make J-full's steps more "
                     f"precise; a cell's ordering is the noise draw's and the bias's, which the "
                     f"covariance does not describe.")
        w(line)
    w(f"- **Curvature order** J-full < J-ftf < Quad IT < Quad LS: holds in {order_holds} of "
      f"{cells} cells on all compared frames and pixels (J-full's non-reference keyframes carry "
      f"Quad IT's maps); on J-full's own keyframes in {own_holds['all']} of {own_cells} over all "
      f"pixels and in {own_holds['interior']} of {own_cells} over interior pixels.")
    w(f"- **J-ftf < Quad IT < Quad LS** on J-ftf's own keyframes, interior pixels: {ftf_holds} of "
      f"{ftf_cells} cells.")
    w("")
    w("## Commands\n")
    w("```sh\n" + a.command + "\n```\n")
    w("Per run: `OUT/runs/<scene>/range<k>/<method>.log` holds the exact `jpcr_run` output; "
      "`jpcr_curvature` for Quad IT / Quad LS, `jpcr_eval curvature` for the curvature table, "
      "`bench_icp_peers` for the OpenCV peer.\n")
    index = os.path.join(a.out, "index.md")
    tmp = index + ".tmp"
    with open(tmp, "w") as f:
        f.write("\n".join(md) + "\n")
    os.replace(tmp, index)
    if not a.quick:
        return 0
    # --quick is CI's check of this script and of the orderings it measured to hold at the quick
    # sizes: J-ftf below ICP-ftf in translation on the noise-free cells, and J-full below
    # ICP-bundle in every cell. Under noise at 160x120 J-ftf is not below the noise-matched
    # ICP-ftf (1 %, room_spheres: 2.22e-3 against 1.94e-3 m), so those cells are reported, not
    # checked; nor is the curvature order (it does not hold, see the claims above). What makes
    # that baseline fair is checked instead: ICP-ftf, on the noise-matched filtered depth, keeps
    # every alignment in every cell.
    problems = []
    if complete < len(SCENES) * len(NOISES):
        problems.append(f"{complete} of {len(SCENES) * len(NOISES)} pose cells complete")
    problems += [f"J-ftf not below ICP-ftf: {s} 0 %"
                 for s in SCENES
                 if pose[s, 0, "icp-ftf"] and pose[s, 0, "j-ftf"]
                 and not pose[s, 0, "j-ftf"]["t"] < pose[s, 0, "icp-ftf"]["t"]]
    problems += [f"J-full not below ICP-bundle: {s} {k} %" for s, k, r in ratios_bundle if r >= 1]
    problems += [f"ICP-ftf rejected its alignment: {c}" for c in failed_front]
    if cells < len(SCENES) * len(NOISES):
        problems.append(f"{cells} of {len(SCENES) * len(NOISES)} curvature cells complete")
    problems += [f"kinect noise: no {m} run with errors for {sc}"
                 for sc in SCENES for m in ["icp-ftf", "j-ftf", "j-ftf_kinect_far"]
                 if not pose_errors(os.path.join(a.runs, sc, "kinect", m))]
    for m in ["icp-ftf", "pipeline"]:
        if not os.path.exists(os.path.join(rail, m, "trajectory.txt")):
            problems.append(f"rail: no {m} run")
    for m in ["icp-ftf", "j-ftf", "pipeline"]:
        if not (load_json(os.path.join(real, m, "report.json")) or {}).get("errors"):
            problems.append(f"real data: no {m} run with errors")
    problems += [f"noise study: no {n} run" for n in STUDY_RUNS + CELL_RUNS if n not in study]
    peers = os.path.join(real, "peers.md")
    if not (os.path.exists(peers) and os.path.getsize(peers)):
        problems.append("real data: no OpenCV peer table")
    for p in problems:
        print(f"reproduce_report: --quick check failed: {p}", file=sys.stderr)
    if not problems:
        print(f"reproduce_report: --quick check passed: every section present; ICP-ftf kept "
              f"every alignment, J-ftf below ICP-ftf in the {len(SCENES)} noise-free cells, "
              f"J-full below ICP-bundle "
              f"in {len(ratios_bundle)} of {len(ratios_bundle)}", file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
