#!/usr/bin/env python3
"""The confidence's evidence on the real nuScenes drives, by outcome (issue 24): for the right answers
the rule answered, the right ones it declined, the wrong ones on the street (in-map pairs) and every
answer against the distractor map (all wrong), the 10th percentile / median / 90th percentile of each
input of the model (z_rival, rival_margin, z_shift_far, z_shift, z_turn, inlier_share). Which inputs
separate the declined right answers from the wrong ones says which factor declines them for want of
evidence and which for a threshold the real scans do not reach.

Reads bench/real_data.sh output directories (nuscenes-0004-0002.json, nuscenes-0002-0004.json and
nuscenes-0001-0002.json in each), e.g. the runs of several noise seeds:

    for s in 1 2 3; do NUSCENES_ONLY=1 NOISE="--label-noise 0.10 --object-confusion 0.15 --noise-seed $s" \\
        bash bench/real_data.sh ../shared/data out/real-s$s; done
    python3 bench/real_evidence.py out/real-s1 out/real-s2 out/real-s3

Standard library only."""
import argparse
import collections
import json
import os
import statistics

import declined_right
import fit_confidence

INPUTS = ["z_rival", "rival_margin", "z_shift_far", "z_shift", "z_turn", "inlier_share"]
PAIRS = ["nuscenes-0004-0002.json", "nuscenes-0002-0004.json"]
DISTRACTOR = "nuscenes-0001-0002.json"


def evidence(path, distractor, mode):
    """(right, answered, evidence) per query with a verified pose."""
    out = []
    if not os.path.exists(path):
        return out
    for q in json.load(open(path))["modes"][mode]["queries"]:
        e = q.get("diagnostics", {}).get("confidence_evidence")
        if q.get("status") != "Ok" or not e or e.get("samples", 0) == 0:
            continue
        out.append((bool(q["success"]) and not distractor, bool(q["answered"]), e))
    return out


def spread(values):
    if not values:
        return "-"
    v = sorted(values)
    return "%.2f / %.2f / %.2f" % (v[int(0.1 * (len(v) - 1))], statistics.median(v), v[int(0.9 * (len(v) - 1))])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("dirs", nargs="+", help="bench/real_data.sh output directories")
    ap.add_argument("--mode", default="gsf")
    a = ap.parse_args()
    in_map, distractor = [], []
    for d in a.dirs:
        for p in PAIRS:
            in_map += evidence(os.path.join(d, p), False, a.mode)
        distractor += evidence(os.path.join(d, DISTRACTOR), True, a.mode)
    groups = [
        ("right, answered", [e for r, ans, e in in_map if r and ans]),
        ("right, declined", [e for r, ans, e in in_map if r and not ans]),
        ("wrong, on the street", [e for r, ans, e in in_map if not r]),
        ("distractor map", [e for _, _, e in distractor]),
    ]
    print("| answers | n | " + " | ".join(INPUTS) + " |")
    print("| --- | ---: |" + " --- |" * len(INPUTS))
    for name, g in groups:
        print(f"| {name} | {len(g)} | " + " | ".join(spread([e[k] for e in g]) for k in INPUTS) + " |")
    print("\n(10th percentile / median / 90th percentile; a wrong answer the rule answered is counted in its row)")
    # The model's factor that limits each declined right answer (the smallest; declined_right.py's reading).
    model = declined_right.library_model()
    limiting = collections.Counter()
    for r, ans, e in in_map:
        if r and not ans:
            f = fit_confidence.factor_inputs(model, fit_confidence.features(e, {}))
            limiting[declined_right.FACTOR_NAMES[min(range(len(f)), key=lambda k: f[k])]] += 1
    print("declined right answers by limiting factor:", dict(limiting))


if __name__ == "__main__":
    main()
