#!/usr/bin/env python3
"""Where the declined right answers are: the answers (status Ok) of one or more runs binned by their
confidence evidence against the nearest rival (z_rival, rival_margin; docs/confidence.md), with how
many are right and wrong in each bin and how many of the right ones the default rule declined.

A bin whose answers are wrong often cannot be vouched for without new evidence, whatever the model:
a declined right answer there is the price of never being confidently wrong.

Usage: bench/ambiguity_bins.py DIR [DIR ...]   (DIR: a bench/families.sh family directory, or any
       directory holding */results.json from `gsf evaluate --json`; mode gsf)
"""
import collections
import glob
import json
import sys

Z_EDGES = [0.5, 1.0, 1.5, 2.0, 3.0]
M_EDGES = [0.05, 0.1, 0.2]


def bin_of(value, edges):
    for i, e in enumerate(edges):
        if value < e:
            return i
    return len(edges)


def label(i, edges):
    lo = "" if i == 0 else f"{edges[i - 1]:g}"
    hi = "" if i == len(edges) else f"{edges[i]:g}"
    return f"[{lo or '-inf'}, {hi or 'inf'})"


def main(dirs):
    cells = collections.defaultdict(lambda: [0, 0, 0])  # right, wrong, declined right
    files = [f for d in dirs for f in sorted(glob.glob(d + "/**/results.json", recursive=True))]
    if not files:
        sys.exit("ambiguity_bins.py: no results.json under " + " ".join(dirs))
    for f in files:
        for q in json.load(open(f))["modes"].get("gsf", {}).get("queries", []):
            ev = q.get("diagnostics", {}).get("confidence_evidence")
            if q.get("status") != "Ok" or not ev:
                continue
            c = cells[(bin_of(ev["z_rival"], Z_EDGES), bin_of(ev["rival_margin"], M_EDGES))]
            if q["success"]:
                c[0] += 1
                c[2] += not q["answered"]
            else:
                c[1] += 1
    print(f"{len(files)} runs. Cells: right / wrong answers (share right), declined right")
    print("| z_rival \\ rival_margin | " + " | ".join(label(j, M_EDGES) for j in range(len(M_EDGES) + 1)) + " |")
    print("| --- " * (len(M_EDGES) + 2) + "|")
    tot = [0, 0, 0]
    for i in range(len(Z_EDGES) + 1):
        row = []
        for j in range(len(M_EDGES) + 1):
            r, w, d = cells[(i, j)]
            tot = [tot[0] + r, tot[1] + w, tot[2] + d]
            row.append("" if r + w == 0 else f"{r} / {w} ({r / (r + w):.0%}), {d}")
        print(f"| {label(i, Z_EDGES)} | " + " | ".join(row) + " |")
    print(f"all: {tot[0]} right, {tot[1]} wrong, {tot[2]} right answers declined")


if __name__ == "__main__":
    if len(sys.argv) < 2 or sys.argv[1] in ("-h", "--help"):
        sys.exit(__doc__)
    main(sys.argv[1:])
