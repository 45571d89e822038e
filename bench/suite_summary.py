#!/usr/bin/env python3
"""Aggregates bench/suite.sh: per mode, per zone type and overall, the MEAN and WORST over the worlds
(seeds) of success over all queries / in the zone / near it / elsewhere, precision and share answered
under the library's decision rule (status Ok and confident), median and p95 ms per query. Worst = lowest
for rates, highest for times. Then per mode, pooled over all worlds' queries (bench/calibration.py): the
confidence's reliability table, ECE, Brier, precision and share answered at the rule, wrong answers and
declined right ones, overall and per zone type. Prints Markdown tables and writes OUT/summary.json
(per-world numbers, the aggregates, and "calibration": {mode: {"overall"|zone: {...}}}).
Python standard library only.  Usage: bench/suite_summary.py OUT_DIR [--seconds S] [--set OVERRIDES]"""
import argparse
import glob
import json
import os
import statistics
import sys

import calibration

# (key in summary.json, results.json summary key(s): the first present counts (older results.json named
# the rule's numbers *_at_threshold, for ambiguity <= 0.5), column header, higher is better, scale, format)
METRICS = [
    ("success", "success_rate", "success", True, 100, "{:.1f}%"),
    ("zone", "zone_success_rate", "zone", True, 100, "{:.1f}%"),
    ("near_zone", "near_zone_success_rate", "near zone", True, 100, "{:.1f}%"),
    ("elsewhere", "elsewhere_success_rate", "elsewhere", True, 100, "{:.1f}%"),
    ("precision", ("precision_at_rule", "precision_at_threshold"), "prec@rule", True, 100, "{:.1f}%"),
    ("answered", ("answered_at_rule", "answered_at_threshold"), "answered", True, 100, "{:.1f}%"),
    ("median_ms", "median_ms", "median ms", False, 1, "{:.1f}"),
    ("p95_ms", "p95_ms", "p95 ms", False, 1, "{:.1f}"),
]
# A rate over no queries (e.g. no near-zone query in a world) is not a measurement.
COUNT_OF = {"zone": "zone_queries", "near_zone": "near_zone_queries", "elsewhere": "elsewhere_queries"}
ZONE_ORDER = ["row", "lattice", "hall", "avenue"]


def summary_value(s, src):
    for key in (src,) if isinstance(src, str) else src:
        if key in s:
            return s[key]
    return None


def load_worlds(out):
    """Per world its numbers (summary.json's "worlds") and {mode: queries} (for the pooled calibration)."""
    worlds, queries = [], []
    for path in sorted(glob.glob(os.path.join(out, "*", "results.json"))):
        d = os.path.dirname(path)
        r = json.load(open(path))
        meta = json.load(open(os.path.join(d, "meta.json"))) if os.path.exists(os.path.join(d, "meta.json")) else {}
        zone = r.get("zone_type") or meta.get("zone", {}).get("type", "?")
        secs = None
        if os.path.exists(os.path.join(d, "seconds.txt")):
            secs = float(open(os.path.join(d, "seconds.txt")).read().strip() or 0)
        w = {"world": os.path.basename(d), "zone": zone, "seed": meta.get("seed"), "seconds": secs,
             "queries": None, "zone_queries": None, "near_zone_queries": None, "elsewhere_queries": None,
             "repeated_instances": meta.get("zone", {}).get("repeated_instances"),
             "cued_instances": meta.get("zone", {}).get("cued_instances"),
             "sensing": meta.get("sensing"), "modes": {}}
        queries.append({mode: v.get("queries", []) for mode, v in r["modes"].items()})
        for mode, v in r["modes"].items():
            s = v["summary"]
            m = {}
            for key, src, _, _, _, _ in METRICS:
                val = summary_value(s, src)
                if key in COUNT_OF and not s.get(COUNT_OF[key]):
                    val = None
                m[key] = val
            m["min_confidence"] = s.get("min_confidence")  # the decision rule's threshold
            w["modes"][mode] = m
            for c in ("queries", "zone_queries", "near_zone_queries", "elsewhere_queries"):
                w[c] = s.get(c)
        worlds.append(w)
    return worlds, queries


def aggregate(worlds, mode):
    agg = {"worlds": 0}
    rows = [w["modes"][mode] for w in worlds if mode in w["modes"]]
    agg["worlds"] = len(rows)
    for key, _, _, higher, _, _ in METRICS:
        vals = [r[key] for r in rows if r.get(key) is not None]
        if not vals:
            agg[key] = {"mean": None, "worst": None, "n": 0}
            continue
        agg[key] = {"mean": statistics.fmean(vals), "worst": min(vals) if higher else max(vals), "n": len(vals)}
    return agg


def print_calibration(worlds, queries, modes, zones):
    """Per mode, the pooled calibration over all worlds (table) and per zone type (one line each)."""
    out = {}
    for mode in modes:
        with_conf = [(w, q[mode]) for w, q in zip(worlds, queries)
                     if mode in q and all("confidence" in x and "answered" in x for x in q[mode])]
        if not with_conf:
            print(f"\ncalibration {mode}: no per-query confidence (results.json older than the decision rule)")
            continue
        out[mode] = {}
        recorded = {w["modes"][mode]["min_confidence"] for w, _ in with_conf} - {None}
        threshold = calibration.threshold_text(None, recorded)
        print(f"\ncalibration {mode}, pooled over {len(with_conf)} worlds (no pose = confidence 0, a failure):")
        for label in zones + ["overall"]:
            qs = [x for w, q in with_conf if label == "overall" or w["zone"] == label for x in q]
            if not qs:
                continue
            c = calibration.calibration(qs)
            out[mode][label] = c
            print(calibration.summary_line(label, mode, c, threshold))
        print("\n".join(calibration.table_lines(out[mode]["overall"])))
    return out


def fmt(v, scale, f):
    return "-" if v is None else f.format(v * scale)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out")
    ap.add_argument("--seconds", type=float, default=None, help="wall time of the whole suite")
    ap.add_argument("--set", default="", help="config overrides the suite ran with (recorded)")
    a = ap.parse_args()
    worlds, queries = load_worlds(a.out)
    if not worlds:
        print(f"suite_summary: no */results.json under {a.out}", file=sys.stderr)
        return 1
    modes = []
    for w in worlds:
        for m in w["modes"]:
            if m not in modes:
                modes.append(m)
    zones = [z for z in ZONE_ORDER if any(w["zone"] == z for w in worlds)]
    zones += sorted({w["zone"] for w in worlds} - set(zones))
    summary = {"out": a.out, "seconds": a.seconds, "set": a.set, "worlds": worlds, "aggregates": {}}
    nq = sum(w["queries"] or 0 for w in worlds)
    nz = sum(w["zone_queries"] or 0 for w in worlds)
    nn = sum(w["near_zone_queries"] or 0 for w in worlds)
    print(f"suite: {len(worlds)} worlds, {nq} queries ({nz} in a zone, {nn} near one)"
          + (f", overrides {a.set}" if a.set else "") + (f", {a.seconds:.0f} s" if a.seconds is not None else ""))
    print("each cell: mean over seeds / worst seed (lowest rate, highest time); '-' = no such query")
    for mode in modes:
        summary["aggregates"][mode] = {}
        print(f"\nmode {mode}\n")
        head = ["zone", "worlds"] + [h for _, _, h, _, _, _ in METRICS]
        print("| " + " | ".join(head) + " |")
        print("| " + " | ".join(["---"] * len(head)) + " |")
        for label, subset in [(z, [w for w in worlds if w["zone"] == z]) for z in zones] + [("overall", worlds)]:
            agg = aggregate(subset, mode)
            summary["aggregates"][mode][label] = agg
            cells = [f"**{label}**" if label == "overall" else label, str(agg["worlds"])]
            for key, _, _, _, scale, f in METRICS:
                cells.append(f"{fmt(agg[key]['mean'], scale, f)} / {fmt(agg[key]['worst'], scale, f)}")
            print("| " + " | ".join(cells) + " |")
    summary["calibration"] = print_calibration(worlds, queries, modes, zones)
    secs = [w["seconds"] for w in worlds if w["seconds"] is not None]
    if secs:
        print(f"\nper world: {statistics.fmean(secs):.0f} s mean, {max(secs):.0f} s max (simulate + build-map + evaluate)")
    with open(os.path.join(a.out, "summary.json"), "w") as f:
        json.dump(summary, f, indent=1)
    print(f"wrote {os.path.join(a.out, 'summary.json')}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
