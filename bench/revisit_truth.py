#!/usr/bin/env python3
"""How far the real nuScenes revisit answers are from the truth, and from the truth ICP agrees with.

The nuScenes drives 0002 and 0004 pass one street in opposite directions. Their poses come from the
dataset, and the sweeps are not corrected for the car's motion during the 50 ms sweep. So a scan
matched against the other drive's map does not sit exactly at its listed pose: the data README's ICP
of the revisit pairs (revisit_pairs.txt, T_icp) moves it by 0.15-0.27 m. This script compares each
answer at a revisit pair's query frame with both. One is the listed pose, the other the pose the ICP
puts it at relative to the other drive's frame, whose poses built the map. An answer closer to the
second is right and the listed pose is off.

Reads bench/real_data.sh's OUT: nuscenes-M-Q.json (one-shot modes, with the pose) and
nuscenes-M-Q-track.json (tracking, its error along the true scan's axes), for M-Q = 0002-0004 and
0004-0002.

Usage: bench/revisit_truth.py OUT [DATA]   (DATA: ../shared/data/nuscenes-lidarseg-samples)"""
import json
import math
import os
import sys


def matrix(values):
    return [values[0:4], values[4:8], values[8:12], [0.0, 0.0, 0.0, 1.0]]


def mul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(4)) for j in range(4)] for i in range(4)]


def inverse(t):
    r = [[t[j][i] for j in range(3)] for i in range(3)]  # rotation transposed
    p = [-sum(r[i][k] * t[k][3] for k in range(3)) for i in range(3)]
    return [r[0] + [p[0]], r[1] + [p[1]], r[2] + [p[2]], [0.0, 0.0, 0.0, 1.0]]


def position(t):
    return [t[i][3] for i in range(3)]


def poses(data, seq):
    with open(os.path.join(data, "sequences", seq, "poses.txt")) as f:
        return [matrix([float(x) for x in line.split()]) for line in f if line.strip()]


def revisit_pairs(data):
    """(frame in 0002, frame in 0004, T_icp mapping the 0004 scan into the 0002 scan's frame)."""
    out = []
    with open(os.path.join(data, "revisit_pairs.txt")) as f:
        for line in f:
            c = line.split()
            if line.startswith("#") or len(c) < 32 or c[0] != "0002/0004" or c[3] != "revisit":
                continue
            out.append((int(c[1]), int(c[2]), matrix([float(x) for x in c[20:32]])))
    return out


def answers(out_dir, m, q):
    """frame -> {run: estimated global position} for the one-shot modes and tracking."""
    est = {}
    path = os.path.join(out_dir, f"nuscenes-{m}-{q}.json")
    if os.path.exists(path):
        for mode, run in json.load(open(path))["modes"].items():
            for x in run["queries"]:
                if x.get("status") == "Ok" and "pose" in x:
                    est.setdefault(x["frame"], {})[mode] = [x["pose"][3], x["pose"][7], x["pose"][11]]
    return est


def tracked(out_dir, m, q, truth):
    """frame -> estimated global position of the tracked scans (the truth plus its error along the
    true scan's axes)."""
    est = {}
    path = os.path.join(out_dir, f"nuscenes-{m}-{q}-track.json")
    if not os.path.exists(path):
        return est
    for x in json.load(open(path))["scans"]:
        if x["how"] != "track" or x.get("status") != "Ok":
            continue
        t, e = truth[x["frame"]], x["error_in_scan_m"]
        est[x["frame"]] = [t[i][3] + sum(t[i][k] * e[k] for k in range(3)) for i in range(3)]
    return est


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    out_dir = sys.argv[1]
    here = os.path.dirname(os.path.abspath(__file__))
    data = sys.argv[2] if len(sys.argv) > 2 else os.path.join(here, "..", "..", "shared", "data",
                                                                 "nuscenes-lidarseg-samples")
    p = {"0002": poses(data, "0002"), "0004": poses(data, "0004")}
    print("map -> query  query frame (pair)  run          to the listed pose  to ICP's  listed vs ICP")
    for m, q in (("0002", "0004"), ("0004", "0002")):
        est = answers(out_dir, m, q)
        for frame, position_ in tracked(out_dir, m, q, p[q]).items():
            est.setdefault(frame, {})["track"] = position_
        for f2, f4, t_icp in revisit_pairs(data):
            # The query scan's pose as ICP puts it against the map drive's scan of the pair.
            if q == "0004":
                frame, pair, icp = f4, f2, mul(p["0002"][f2], t_icp)
            else:
                frame, pair, icp = f2, f4, mul(p["0004"][f4], inverse(t_icp))
            listed = position(p[q][frame])
            for run, e in sorted(est.get(frame, {}).items()):
                print(f"{m} -> {q}   {frame:3d} ({pair:2d})            {run:12s} {math.dist(e, listed):6.2f} m"
                      f"         {math.dist(e, position(icp)):5.2f} m  {math.dist(listed, position(icp)):5.2f} m")


if __name__ == "__main__":
    main()
