#!/usr/bin/env python3
"""Two bench/families.sh runs of the same worlds (the same seeds, families and zones; e.g. the build
before and after a change), query by query: per family success, answered right, confident wrong (the
worst outcome), median ATE over the successes, median and 99th percentile ARE over the successes, and
median and 99th percentile of the answer's own lean from the vertical (roll and pitch together); then
every query whose outcome (success, answered) changed.

Only queries present in both runs count. Reads the per-query JSON of `gsf evaluate` (results.json).

Usage: bench/compare_families.py BEFORE_DIR AFTER_DIR [--mode gsf]
Standard library only."""
import argparse
import glob
import json
import math
import os
import statistics


def load(root, mode):
    out = {}
    for f in glob.glob(os.path.join(root, "*", "*", "results.json")):
        world = os.path.relpath(os.path.dirname(f), root)
        family = world.split(os.sep)[0]
        modes = json.load(open(f)).get("modes", {})
        for q in modes.get(mode, {}).get("queries", []):
            pose = q.get("pose")
            lean = None
            if pose and q.get("status") == "Ok":
                lean = math.degrees(math.acos(max(-1.0, min(1.0, pose[10]))))
            out[(world, q["index"])] = dict(family=family, success=bool(q["success"]),
                                            answered=bool(q["answered"]), ate=q.get("translation_error_m"),
                                            are=q.get("rotation_error_deg"), lean=lean)
    return out


def pct(values, p):
    v = sorted(values)
    return v[min(len(v) - 1, int(p * len(v)))] if v else float("nan")


def summary(queries):
    ok = [q for q in queries if q["success"]]
    leans = [q["lean"] for q in queries if q["lean"] is not None]
    return dict(n=len(queries), success=len(ok), right=sum(q["answered"] for q in ok),
                wrong=sum(q["answered"] and not q["success"] for q in queries),
                ate=statistics.median([q["ate"] for q in ok]) if ok else float("nan"),
                are=statistics.median([q["are"] for q in ok]) if ok else float("nan"),
                are99=pct([q["are"] for q in ok], 0.99),
                lean=statistics.median(leans) if leans else float("nan"), lean99=pct(leans, 0.99))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("before")
    ap.add_argument("after")
    ap.add_argument("--mode", default="gsf")
    args = ap.parse_args()
    a, b = load(args.before, args.mode), load(args.after, args.mode)
    keys = sorted(set(a) & set(b))
    if not keys:
        raise SystemExit("compare_families.py: no query in both runs")
    families = sorted({a[k]["family"] for k in keys})
    print("| family (queries) | success | answered right | confident wrong | median ATE m | ARE deg, median / p99 |"
          " lean deg, median / p99 |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for fam in families + ["all"]:
        s = [summary([d[k] for k in keys if fam == "all" or d[k]["family"] == fam]) for d in (a, b)]
        print(f"| {fam} ({s[0]['n']}) | {s[0]['success']} -> {s[1]['success']} | {s[0]['right']} -> {s[1]['right']} |"
              f" {s[0]['wrong']} -> {s[1]['wrong']} | {s[0]['ate']:.2f} -> {s[1]['ate']:.2f} |"
              f" {s[0]['are']:.2f} / {s[0]['are99']:.1f} -> {s[1]['are']:.2f} / {s[1]['are99']:.1f} |"
              f" {s[0]['lean']:.2f} / {s[0]['lean99']:.1f} -> {s[1]['lean']:.2f} / {s[1]['lean99']:.1f} |")
    print("\nqueries whose outcome changed (success, answered; t m, r deg):")
    for k in keys:
        x, y = a[k], b[k]
        if (x["success"], x["answered"]) != (y["success"], y["answered"]):
            print(f"  {k[0]} query {k[1]}: {x['success']}, {x['answered']} ({x['ate']:.1f}, {x['are']:.1f}) -> "
                  f"{y['success']}, {y['answered']} ({y['ate']:.1f}, {y['are']:.1f})")


if __name__ == "__main__":
    main()
