#!/usr/bin/env python3
"""The GSF gate's evidence: how often a true correspondence's best similarity (omega) stays below the gate,
by its query instance's range and the query's region, from a suite run's per-query diagnostics.

Run the suite with the gate off and every pair kept, so each true pair's best omega over all its matches
is recorded:
    bash bench/suite.sh --seeds "6 7 8 9 10" --gsf BIN --jobs 2 --out OUT \
        --set match.min_similarity=0,match.max_correspondences=4096   # gate 0: nothing below it to fill
    python3 bench/true_pair_omega.py OUT [--gate 0.3]
"""
import argparse
import glob
import json
import os

ap = argparse.ArgumentParser()
ap.add_argument("suite_dir")
ap.add_argument("--gate", type=float, default=0.3)
args = ap.parse_args()
buckets = [(0, 15), (15, 30), (30, 50), (50, 1e9)]
rows = {}
for f in sorted(glob.glob(os.path.join(args.suite_dir, "*", "results.json"))):
    for q in json.load(open(f))["modes"]["gsf"]["queries"]:
        region = "zone" if q["in_zone"] else ("near zone" if q["near_zone"] else "elsewhere")
        for w, r in q["diagnostics"].get("true_pairs", []):
            for lo, hi in buckets:
                if lo <= r < hi:
                    n, below = rows.get((region, lo), (0, 0))
                    rows[(region, lo)] = (n + 1, below + (w < args.gate))
print("| region | range m | true pairs | best omega below %.2f |" % args.gate)
print("| --- | --- | --- | --- |")
for region in ("zone", "near zone", "elsewhere"):
    for lo, hi in buckets:
        n, below = rows.get((region, lo), (0, 0))
        if n:
            print("| %s | %s | %d | %.0f%% |" % (region, "%d-%d" % (lo, hi) if hi < 1e9 else ">= %d" % lo, n, 100.0 * below / n))
