#!/usr/bin/env python3
"""Which KITTI odometry frames does a short estimated trajectory match?

Compares the frame-to-frame motion of an estimate (KITTI format, cam0 convention, pose i = frame i, e.g.
`rotolidar slam --kitti DIR` -> trajectory.kitti) with every window of the same length in KITTI ground-truth pose
files, by frame-independent invariants (translation norm and rotation angle of T_0_k, k = 1..n-1), and prints the
best windows. Used to check data provenance (docs/registration.md: the kitti00 bins against kitti_poses/).

usage: kitti_find_frames.py ESTIMATE.kitti POSES.txt [POSES.txt ...] [--top N]
"""
import argparse
import math
import os


def load(path):
    poses = []
    with open(path) as f:
        for line_no, line in enumerate(f, 1):
            v = [float(x) for x in line.split()]
            if len(v) != 12:
                raise SystemExit(f"{path}:{line_no}: expected 12 numbers, got {len(v)}")
            poses.append(([[v[0], v[1], v[2]], [v[4], v[5], v[6]], [v[8], v[9], v[10]]], [v[3], v[7], v[11]]))
    return poses


def relative(a, b):
    """Translation norm [m] and rotation angle [deg] of T_a^-1 T_b."""
    (ra, ta), (rb, tb) = a, b
    d = [tb[i] - ta[i] for i in range(3)]
    t = [sum(ra[j][i] * d[j] for j in range(3)) for i in range(3)]
    trace = sum(sum(ra[k][i] * rb[k][i] for k in range(3)) for i in range(3))
    angle = math.degrees(math.acos(max(-1.0, min(1.0, (trace - 1) / 2))))
    return math.hypot(*t), angle


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("estimate")
    ap.add_argument("poses", nargs="+")
    ap.add_argument("--top", type=int, default=8)
    args = ap.parse_args()
    est = load(args.estimate)
    n = len(est)
    if n < 2:
        raise SystemExit(f"{args.estimate}: need at least 2 poses")
    want = [relative(est[0], est[k]) for k in range(1, n)]
    rows = []
    for path in args.poses:
        gt = load(path)
        for i in range(len(gt) - n + 1):
            got = [relative(gt[i], gt[i + k]) for k in range(1, n)]
            dt = max(abs(g[0] - w[0]) for g, w in zip(got, want))
            dr = max(abs(g[1] - w[1]) for g, w in zip(got, want))
            rows.append((dt + dr / 4.0, dt, dr, os.path.basename(path), i))
    rows.sort()
    print(f"estimate: |t_0k| = {[round(w[0], 3) for w in want]} m, angle_0k = {[round(w[1], 3) for w in want]} deg")
    print("rank  poses      first_frame  max|dt| [m]  max|dangle| [deg]")
    for rank, (_, dt, dr, name, i) in enumerate(rows[: args.top], 1):
        print(f"{rank:4d}  {name:10s} {i:11d}  {dt:11.4f}  {dr:17.3f}")


if __name__ == "__main__":
    main()
