#!/usr/bin/env python3
"""Where the slow queries are (issue 25, item 4): per zone type of a suite or families run and per
place of the query (zone: inside the repetitive zone, near: within reach of it, open: elsewhere), the
queries, their median and p95 time, and the share that keep more than --crowded matches (the
diagnostics' triangle_matches; a crowded scan fills match.max_matches_per_scan, default 32,768, and
pays for it in matching, the GSF filter and the clique). A second table gives per place the median
work of a query: instances, query triangles, raw and kept triangle matches, matches past the GSF gate,
and the match / gsf / clique stage times; a last line the kept matches' median and 90th percentile
over all queries.

Usage: bench/time_by_place.py DIR [DIR ...] [--mode gsf] [--crowded 8192]
DIR: a suite or families output (any depth of */results.json below it). Standard library only."""
import argparse
import glob
import json
import os
from collections import defaultdict

# Per-query work (diagnostics fields) and stage times (diagnostics.stage_ms) of the second table.
WORK = ["instances", "triangles", "match_candidates", "triangle_matches", "gsf_survivors"]
STAGES = ["match", "gsf", "clique"]


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
    times, crowded, work = defaultdict(list), defaultdict(int), defaultdict(lambda: defaultdict(list))
    kept = []
    for d in a.dirs:
        for f in glob.glob(os.path.join(d, "**", "results.json"), recursive=True):
            r = json.load(open(f))
            mode = r.get("modes", {}).get(a.mode)
            if mode is None:
                continue
            for q in mode["queries"]:
                place = "zone" if q.get("in_zone") else ("near" if q.get("near_zone") else "open")
                key = (r.get("zone_type", "?"), place)
                diag = q.get("diagnostics", {})
                times[key].append(q["time_ms"])
                crowded[key] += diag.get("triangle_matches", 0) > a.crowded
                kept.append(diag.get("triangle_matches", 0))
                for name in WORK:
                    work[key][name].append(diag.get(name, 0))
                for name in STAGES:
                    work[key][name].append(diag.get("stage_ms", {}).get(name, 0.0))
    print(f"| zone type | place | queries | median ms | p95 ms | keep > {a.crowded} matches |")
    print("| --- | --- | ---: | ---: | ---: | ---: |")
    for key in sorted(times):
        t = times[key]
        print(f"| {key[0]} | {key[1]} | {len(t)} | {percentile(t, 0.5):.1f} | {percentile(t, 0.95):.1f} | "
              f"{100.0 * crowded[key] / len(t):.0f}% |")
    print()
    print("| zone type | place | " + " | ".join(WORK) + " | " + " | ".join(f"{n} ms" for n in STAGES) + " |")
    print("| --- | --- |" + " ---: |" * (len(WORK) + len(STAGES)))
    for key in sorted(times):
        w = work[key]
        cells = [f"{percentile(w[n], 0.5):.0f}" for n in WORK] + [f"{percentile(w[n], 0.5):.2f}" for n in STAGES]
        print(f"| {key[0]} | {key[1]} | " + " | ".join(cells) + " |")
    if kept:
        print(f"\nkept triangle matches over {len(kept)} queries: median {percentile(kept, 0.5):.0f}, "
              f"90th percentile {percentile(kept, 0.9):.0f}, more than {a.crowded}: "
              f"{100.0 * sum(k > a.crowded for k in kept) / len(kept):.0f}%")


if __name__ == "__main__":
    main()
