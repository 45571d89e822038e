#!/usr/bin/env python3
"""Where the slow queries are (issue 25, item 4): per zone type of a suite or families run and per
place of the query (zone: inside the repetitive zone, near: within reach of it, open: elsewhere), the
queries, their median and p95 time, and the share that keep more than --crowded matches (the
diagnostics' triangle_matches; a crowded scan fills match.max_matches_per_scan, default 32,768, and
pays for it in matching, the GSF filter and the clique).

Usage: bench/time_by_place.py DIR [DIR ...] [--mode gsf] [--crowded 8192]
DIR: a suite or families output (any depth of */results.json below it). Standard library only."""
import argparse
import glob
import json
import os
from collections import defaultdict


def percentile(v, p):
    v = sorted(v)
    pos = p * (len(v) - 1)
    lo = int(pos)
    hi = min(lo + 1, len(v) - 1)
    return v[lo] + (v[hi] - v[lo]) * (pos - lo)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("dirs", nargs="+")
    ap.add_argument("--mode", default="gsf")
    ap.add_argument("--crowded", type=int, default=8192)
    a = ap.parse_args()
    times, crowded = defaultdict(list), defaultdict(int)
    for d in a.dirs:
        for f in glob.glob(os.path.join(d, "**", "results.json"), recursive=True):
            r = json.load(open(f))
            mode = r.get("modes", {}).get(a.mode)
            if mode is None:
                continue
            for q in mode["queries"]:
                place = "zone" if q.get("in_zone") else ("near" if q.get("near_zone") else "open")
                key = (r.get("zone_type", "?"), place)
                times[key].append(q["time_ms"])
                crowded[key] += q.get("diagnostics", {}).get("triangle_matches", 0) > a.crowded
    print(f"| zone type | place | queries | median ms | p95 ms | keep > {a.crowded} matches |")
    print("| --- | --- | ---: | ---: | ---: | ---: |")
    for key in sorted(times):
        t = times[key]
        print(f"| {key[0]} | {key[1]} | {len(t)} | {percentile(t, 0.5):.1f} | {percentile(t, 0.95):.1f} | "
              f"{100.0 * crowded[key] / len(t):.0f}% |")


if __name__ == "__main__":
    main()
