#!/usr/bin/env python3
"""Why the confidence declines right answers (issue 24): per family, the declined right answers (the
query succeeded, t < 5 m and r < 10 deg, but confidence < --min-confidence) by the model's limiting
factor (the smallest of its logistic factors: rival, peak (shifted and turned probes), inlier share; with the right
answers' median inlier share beside it), and for those the
rival factor limits, where the best-scoring rival is: its distance and heading from the answer and its
verified score over the answer's. A rival far away (another place or a flip) that scores nearly as
well means the scan's own evidence is ambiguous, and declining is the rule working, not a calibration
defect; a rival close to the answer would be a defect (both would be right). Beside it, the share of
right answers answered by place: on open road, near the world's repetitive zone (hall, avenue, row,
lattice) and in it (the query's in_zone / near_zone flags), where a single scan can be ambiguous, with
the answered wrong ones by place; and
the best rival's inlier count over the answer's (median) for the declined right and the wrong answers.

Reads the per-query JSON of `gsf evaluate` (diagnostics.confidence_evidence and .hypotheses).

Usage: bench/declined_right.py FAMILIES_DIR [--families "p0 p3 ..."] [--model=a_r,...] [--min-confidence 0.9]
FAMILIES_DIR is a bench/families.sh output (FAMILIES_DIR/<family>/<world>/results.json). The model
defaults to kConfidenceModel of core/src/confidence.cpp. Standard library only."""
import argparse
import glob
import json
import math
import os
import re

import fit_confidence as fc

FACTOR_NAMES = ["rival", "peak", "inlier"]  # kConfidenceModel's factors, in fit_confidence.FACTORS order
PLACES = ["open", "near", "zone"]  # open road, near the repetitive zone, in it
FAMILY_ORDER = "p0 p3 p8 p15 o10 o20 thin b16 b64 b128 cross cheap edge ns spur".split()  # bench/families.sh's


def library_model():
    src = os.path.join(os.path.dirname(__file__), "..", "core", "src", "confidence.cpp")
    m = re.search(r"kConfidenceModel = \{([^}]*)\}", open(src).read())
    return [float(v.rstrip("f")) for v in m.group(1).split(",")]


def heading_gap(a, b):
    return abs((a - b + 180.0) % 360.0 - 180.0)


def best_rival(hyps):
    """The best fully verified hypothesis not within 2 m and 5 deg of the answer (the top one)."""
    h = sorted((x for x in hyps if x.get("fully_verified")), key=lambda x: -x["verified_score"])
    if len(h) < 2:
        return None, None
    a = h[0]
    for r in h[1:]:
        d = math.hypot(r["x"] - a["x"], r["y"] - a["y"])
        if d >= 2.0 or heading_gap(r["yaw_deg"], a["yaw_deg"]) >= 5.0:
            return a, r
    return a, None


def median(values):
    v = sorted(values)
    return v[len(v) // 2] if v else float("nan")


def add_inlier_ratio(out, diagnostics):
    """The best rival's inlier count over the answer's (instance-level evidence beside the verification's)."""
    a, r = best_rival(diagnostics.get("hypotheses", []))
    if r is not None and a["inliers"] > 0:
        out.append(r["inliers"] / a["inliers"])


def family_line(name, files, model, threshold):
    count = {"declined": 0, "far": 0, "near": 0, "close_score": 0}
    right_shares = []  # inlier share of every right answer: is the factor alike over sensors?
    by_factor = dict.fromkeys(FACTOR_NAMES, 0)
    by_place = {p: [0, 0] for p in PLACES}  # [right answers, answered]
    wrong_by_place = {p: [0, 0] for p in PLACES}  # [answered, answered and wrong]
    inlier_ratio = {"declined right": [], "wrong above 0.5": []}  # best rival's inliers / the answer's
    for f in files:
        for q in json.load(open(f))["modes"]["gsf"]["queries"]:
            d = q.get("diagnostics", {})
            e = d.get("confidence_evidence")
            where = "zone" if q.get("in_zone") else "near" if q.get("near_zone") else "open"
            if e and q["confidence"] >= threshold:
                wrong_by_place[where][0] += 1
                wrong_by_place[where][1] += not q["success"]
            if e and not q["success"] and q["confidence"] > 0.5:
                add_inlier_ratio(inlier_ratio["wrong above 0.5"], d)
            if not e or not q["success"]:
                continue
            right_shares.append(e["inlier_share"])
            place = by_place[where]
            place[0] += 1
            if q["confidence"] >= threshold:
                place[1] += 1
                continue
            count["declined"] += 1
            add_inlier_ratio(inlier_ratio["declined right"], d)
            u = fc.factor_inputs(model, fc.features(e, q))
            limiting = FACTOR_NAMES[min(range(len(FACTOR_NAMES)), key=lambda k: u[k])]
            by_factor[limiting] += 1
            if limiting != "rival":
                continue
            a, r = best_rival(d.get("hypotheses", []))
            if r is None:
                continue
            far = math.hypot(r["x"] - a["x"], r["y"] - a["y"]) > 10.0 or heading_gap(r["yaw_deg"], a["yaw_deg"]) > 20.0
            count["far" if far else "near"] += 1
            if a["verified_score"] > 0 and r["verified_score"] >= 0.9 * a["verified_score"]:
                count["close_score"] += 1
    factors = " ".join(f"{k}={v}" for k, v in by_factor.items())
    right_shares.sort()
    share = right_shares[len(right_shares) // 2] if right_shares else 0.0
    return (f"{name} declined_right={count['declined']} limiting: {factors}; rival-limited with the best rival "
            f"> 10 m or > 20 deg away: {count['far']}, nearer: {count['near']}, scoring >= 0.9 of the answer: "
            f"{count['close_score']}; right answers' median inlier share {share:.2f}; answered of right: "
            + ", ".join(f"{p} {100.0 * answered / max(1, n):.1f}% of {n}" for p, (n, answered) in by_place.items())
            + "; answered wrong: "
            + ", ".join(f"{p} {wrong} of {n}" for p, (n, wrong) in wrong_by_place.items())
            + "; best rival's inliers over the answer's, median: "
            + ", ".join(f"{k} {median(v):.2f} of {len(v)}" for k, v in inlier_ratio.items()))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("dir")
    ap.add_argument("--families", default="")
    ap.add_argument("--model", default="")
    ap.add_argument("--min-confidence", type=float, default=0.9)
    a = ap.parse_args()
    model = fc.parse_model(a.model) if a.model else library_model()
    fams = a.families.replace(",", " ").split() or [f for f in FAMILY_ORDER if os.path.isdir(os.path.join(a.dir, f))]
    allfiles = []
    for fam in fams:
        files = sorted(glob.glob(os.path.join(a.dir, fam, "*", "results.json")))
        if files:
            print(family_line(fam, files, model, a.min_confidence))
            allfiles += files
    if len(fams) > 1:
        print(family_line("all", allfiles, model, a.min_confidence))


if __name__ == "__main__":
    main()
