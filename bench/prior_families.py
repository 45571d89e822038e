#!/usr/bin/env python3
"""Several evaluations of the same family worlds side by side, per family: success / answered right /
confident wrong (answered, not within 5 m / 10 deg). Each RUN is a directory of bench/reevaluate.sh
(or bench/families.sh --keep) output, RUN/<family>/<world>/results.json; the first run names the
worlds. Made for the position prior against one-shot (docs/vehicle-modes.md, *The prior on every
family*):

    bash bench/reevaluate.sh SRC ONE                                          # one-shot
    bash bench/reevaluate.sh SRC P20 --prior-sigma 5 --prior-radius 20        # a 20 m prior
    bash bench/reevaluate.sh SRC OFF --prior-sigma 5 --prior-radius 20 --prior-bias 100
    python3 bench/prior_families.py ONE P20 OFF

Usage: bench/prior_families.py RUN [RUN ...] [--mode gsf]
Standard library only."""
import argparse
import collections
import glob
import json
import os


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("runs", nargs="+")
    ap.add_argument("--mode", default="gsf")
    args = ap.parse_args()
    first = args.runs[0]
    families = sorted(d for d in os.listdir(first) if os.path.isdir(os.path.join(first, d)))
    total = collections.Counter()
    print("family | " + " | ".join(args.runs) + "  (success / answered right / confident wrong)")
    for fam in families:
        count = collections.Counter()
        for f in sorted(glob.glob(os.path.join(first, fam, "*", "results.json"))):
            world = os.path.relpath(f, first)
            for run in args.runs:
                path = os.path.join(run, world)
                if not os.path.exists(path):
                    continue
                for q in json.load(open(path))["modes"][args.mode]["queries"]:
                    count[run, "success"] += q["success"]
                    count[run, "right"] += q["success"] and q["answered"]
                    count[run, "wrong"] += q["answered"] and not q["success"]
        total.update(count)
        print(fam + " | " + " | ".join(f"{count[r, 'success']} / {count[r, 'right']} / {count[r, 'wrong']}"
                                       for r in args.runs))
    print("all | " + " | ".join(f"{total[r, 'success']} / {total[r, 'right']} / {total[r, 'wrong']}"
                                for r in args.runs))


if __name__ == "__main__":
    main()
