#!/usr/bin/python3
"""An independent numpy implementation of the TUM RGB-D benchmark metrics, written from the
definitions in evaluate_ate.py and evaluate_rpe.py (Sturm et al., IROS 2012), used to check
jpcr_eval. Prints a JSON object with the same numbers jpcr_eval computes."""
import json
import sys

import numpy as np


def read_trajectory(path):
    stamps, poses = [], []
    for line in open(path):
        if line.startswith("#") or not line.strip():
            continue
        v = [float(x) for x in line.split()]
        x, y, z, w = v[4:8]
        n = np.sqrt(x * x + y * y + z * z + w * w)
        x, y, z, w = x / n, y / n, z / n, w / n
        R = np.array([
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
        T = np.eye(4)
        T[:3, :3] = R
        T[:3, 3] = v[1:4]
        stamps.append(v[0])
        poses.append(T)
    return stamps, poses


def associate(a, b, max_difference):
    candidates = sorted((abs(x - y), i, j) for i, x in enumerate(a) for j, y in enumerate(b)
                        if abs(x - y) < max_difference)
    used_a, used_b, matches = set(), set(), []
    for _, i, j in candidates:
        if i in used_a or j in used_b:
            continue
        used_a.add(i)
        used_b.add(j)
        matches.append((i, j))
    return sorted(matches)


def ate(gt, est, max_difference):
    matches = associate(gt[0], est[0], max_difference)
    data = np.array([gt[1][i][:3, 3] for i, _ in matches]).T
    model = np.array([est[1][j][:3, 3] for _, j in matches]).T
    W = (model - model.mean(1, keepdims=True)) @ (data - data.mean(1, keepdims=True)).T
    U, _, Vh = np.linalg.svd(W.T)
    S = np.eye(3)
    if np.linalg.det(U) * np.linalg.det(Vh) < 0:
        S[2, 2] = -1
    R = U @ S @ Vh
    t = data.mean(1) - R @ model.mean(1)
    err = np.linalg.norm(R @ model + t[:, None] - data, axis=0)
    return float(np.sqrt(np.mean(err ** 2))), len(matches)


def closest(stamps, t):
    return int(np.argmin(np.abs(np.asarray(stamps) - t)))


def angle(R):
    return float(np.arccos(np.clip((np.trace(R) - 1) / 2, -1.0, 1.0)))


def rpe(gt, est, delta, unit):
    gs, gp = gt
    es, ep = est
    index = es if unit == "s" else list(range(len(es)))
    gt_max = 2 * float(np.median(np.diff(gs)))
    trans, rot = [], []
    for i in range(len(es)):
        j = closest(index, index[i] + delta)
        if j == len(es) - 1:
            continue
        g0, g1 = closest(gs, es[i]), closest(gs, es[j])
        if abs(gs[g0] - es[i]) > gt_max or abs(gs[g1] - es[j]) > gt_max:
            continue
        e = np.linalg.inv(np.linalg.inv(ep[j]) @ ep[i]) @ (np.linalg.inv(gp[g1]) @ gp[g0])
        trans.append(np.linalg.norm(e[:3, 3]))
        rot.append(np.degrees(angle(e[:3, :3])))
    return float(np.sqrt(np.mean(np.square(trans)))), float(np.sqrt(np.mean(np.square(rot)))), len(trans)


def main():
    gt = read_trajectory(sys.argv[1])
    est = read_trajectory(sys.argv[2])
    a, n = ate(gt, est, 0.02)
    tf, rf, nf = rpe(gt, est, 1.0, "f")
    ts, rs, ns = rpe(gt, est, 1.0, "s")
    print(json.dumps({"ate": a, "ate_pairs": n, "rpe_frame_t": tf, "rpe_frame_r": rf,
                      "rpe_frame_pairs": nf, "rpe_second_t": ts, "rpe_second_r": rs,
                      "rpe_second_pairs": ns}))


if __name__ == "__main__":
    main()
