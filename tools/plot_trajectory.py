#!/usr/bin/python3
"""Draws ground truth and estimated trajectories (TUM format) to a PNG: a top view after Horn
alignment of each estimate onto the ground truth (as ATE does), and the translation error over
time. Uses Debian's python3-matplotlib: run it with /usr/bin/python3.

  tools/plot_trajectory.py --gt groundtruth.txt --est icp.txt:ICP-ftf --est jftf.txt:J-ftf \
      --out trajectories.png
"""
import argparse
import os
import sys

import numpy as np


def read_tum(path):
    stamps, xyz = [], []
    try:
        lines = open(path).read().splitlines()
    except OSError as e:
        sys.exit(f"plot_trajectory: error: {path}: {e.strerror}")
    for number, line in enumerate(lines, 1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        fields = line.split()
        try:
            values = [float(f) for f in fields]
        except ValueError:
            sys.exit(f"plot_trajectory: error: {path}:{number}: not a number")
        if len(values) != 8 or not np.all(np.isfinite(values)):
            sys.exit(f"plot_trajectory: error: {path}:{number}: expected 8 finite numbers")
        stamps.append(values[0])
        xyz.append(values[1:4])
    if not stamps:
        sys.exit(f"plot_trajectory: error: {path}: no poses")
    return np.array(stamps), np.array(xyz)


def associate(a, b, max_difference):
    """Greedy nearest-in-time pairs within max_difference (TUM associate.py)."""
    pairs = []
    for i, t in enumerate(a):
        j = int(np.argmin(np.abs(b - t)))
        if abs(b[j] - t) < max_difference:
            pairs.append((i, j))
    return pairs


def horn(model, data):
    """Rotation and translation that map model points onto data points (no scale)."""
    mm, dm = model.mean(0), data.mean(0)
    W = (model - mm).T @ (data - dm)
    U, _, Vh = np.linalg.svd(W.T)
    S = np.eye(3)
    if np.linalg.det(U) * np.linalg.det(Vh) < 0:
        S[2, 2] = -1
    R = U @ S @ Vh
    return R, dm - R @ mm


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--gt", required=True, help="ground-truth trajectory (TUM format)")
    parser.add_argument("--est", action="append", default=[],
                        help="estimate as FILE or FILE:LABEL; repeat for several")
    parser.add_argument("--out", required=True, help="output PNG")
    parser.add_argument("--title", default="", help="figure title")
    parser.add_argument("--max-difference", type=float, default=0.02,
                        help="timestamp association window in seconds (default 0.02)")
    args = parser.parse_args()

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    gt_t, gt_xyz = read_tum(args.gt)
    fig, (top, err) = plt.subplots(1, 2, figsize=(12, 5))
    top.plot(gt_xyz[:, 0], gt_xyz[:, 1], "k-", lw=2, label="ground truth")
    for spec in args.est:
        # FILE or FILE:LABEL: the shortest prefix that names a file is FILE (a path or a label
        # may hold ':'); without one, the part before the first ':'.
        cuts = [i for i, c in enumerate(spec) if c == ":"]
        at = next((i for i in cuts if os.path.isfile(spec[:i])), None)
        if os.path.isfile(spec):
            path, label = spec, ""
        elif at is not None:
            path, label = spec[:at], spec[at + 1:]
        else:
            path, _, label = spec.partition(":")
        t, xyz = read_tum(path)
        pairs = associate(t, gt_t, args.max_difference)
        if len(pairs) < 3:
            sys.exit(f"plot_trajectory: error: {path}: fewer than 3 poses match the ground truth")
        est_idx, gt_idx = zip(*pairs)
        R, tr = horn(xyz[list(est_idx)], gt_xyz[list(gt_idx)])
        aligned = xyz @ R.T + tr
        e = np.linalg.norm(aligned[list(est_idx)] - gt_xyz[list(gt_idx)], axis=1)
        name = label or path
        top.plot(aligned[:, 0], aligned[:, 1], lw=1, label=f"{name} (ATE {np.sqrt(np.mean(e**2)):.4f} m)")
        err.plot(t[list(est_idx)] - gt_t[0], e, lw=1, label=name)
    top.set_xlabel("x (m)")
    top.set_ylabel("y (m)")
    top.set_title("top view (aligned)")
    top.axis("equal")
    top.legend(fontsize=8)
    err.set_xlabel("time (s)")
    err.set_ylabel("translation error (m)")
    err.set_title("error over time")
    if args.est:
        err.legend(fontsize=8)
    if args.title:
        fig.suptitle(args.title)
    fig.tight_layout()
    tmp = args.out + ".tmp.png"
    try:
        fig.savefig(tmp, dpi=110)
        os.replace(tmp, args.out)
    except OSError as e:
        if os.path.exists(tmp):
            os.remove(tmp)
        sys.exit(f"plot_trajectory: error: {args.out}: {e.strerror or e}")
    print(f"plot_trajectory: wrote {args.out}")


if __name__ == "__main__":
    main()
