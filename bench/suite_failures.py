#!/usr/bin/env python3
"""Why a suite run's queries failed, from its per-query diagnostics (results.json of each world), counted
by region (zone / near / else) and cause. A failure is read against the verified hypotheses the
evaluation records (the best 16) and the truth's own verified score:
  <3 instances      fewer than 3 query instances: no triangle
  no hypothesis     no clique or vote reached min_inliers
  top at truth      the best hypothesis is within 2 m / 5 deg of the truth (the answer's height is off)
  truth outscored   a hypothesis within 2 m / 5 deg exists but another scored higher
  absent, higher    no hypothesis near the truth, whose own score beats the answer's (hypothesis recall)
  absent, lower     no hypothesis near the truth, and the truth scores lower (verification's limit)
It also counts the queries matched again at the sparse tolerance (`sparse_rematch`: their first pass
found few map triangles, triangle_matcher.h) and how many of them succeeded, and answers 100 m or more
away turned 180 deg (+-10), and how many of those were declined
(not "answered" under the library's decision rule, status Ok and confident; with --min-confidence P:
confidence < P): a zone's two approach roads look alike.
Python standard library only.  Usage: bench/suite_failures.py OUT_DIR [--mode gsf] [--min-confidence P]"""
import argparse
import collections
import glob
import json
import os

ap = argparse.ArgumentParser()
ap.add_argument("suite_dir")
ap.add_argument("--mode", default="gsf")
ap.add_argument("--min-confidence", type=float, default=None,
                help="decline when confidence < P (default: the recorded decision rule, \"answered\")")
args = ap.parse_args()

causes = collections.Counter()
rematched = collections.Counter()
far_turned = collections.Counter()
declined = collections.Counter()
total = 0
for path in sorted(glob.glob(os.path.join(args.suite_dir, "*", "results.json"))):
    for q in json.load(open(path))["modes"][args.mode]["queries"]:
        total += 1
        if q["diagnostics"].get("sparse_rematch"):
            rematched["all"] += 1
            rematched["success"] += bool(q["success"])
        if q["success"]:
            continue
        region = "zone" if q["in_zone"] else ("near" if q["near_zone"] else "else")
        d = q["diagnostics"]
        hs = d["hypotheses"]
        near_truth = [h["distance_to_truth_m"] < 2 and abs(h["yaw_error_deg"]) < 5 for h in hs]
        if d["instances"] < 3:
            cause = "<3 instances"
        elif not hs:
            cause = "no hypothesis"
        elif near_truth[0]:
            cause = "top at truth"
        elif any(near_truth):
            cause = "truth outscored"
        elif (d["truth_verified_score"] or 0) > hs[0]["verified_score"]:
            cause = "absent, higher"
        else:
            cause = "absent, lower"
        causes[(region, cause)] += 1
        if hs and hs[0]["distance_to_truth_m"] >= 100 and abs(abs(hs[0]["yaw_error_deg"]) - 180) <= 10:
            far_turned[region] += 1
            if args.min_confidence is None:
                declined[region] += not q["answered"]
            else:
                declined[region] += q["status"] != "Ok" or q["confidence"] < args.min_confidence
failures = sum(causes.values())
print(f"{args.mode}: {failures} failures of {total} queries")
print("| region | cause | queries |\n| --- | --- | --- |")
for (region, cause), n in sorted(causes.items()):
    print(f"| {region} | {cause} | {n} |")
print(f"sparse rematch: {rematched['all']} queries, {rematched['success']} of them successes")
for region in sorted(far_turned):
    print(f"{region}: {far_turned[region]} failures answered >= 100 m away turned 180 deg, "
          f"{declined[region]} of them declined ("
          + ("the decision rule" if args.min_confidence is None else f"confidence < {args.min_confidence}") + ")")
