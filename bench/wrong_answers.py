#!/usr/bin/env python3
"""The confident wrong answers of a families run (issue 24: never a confident wrong answer), one line
each with what it looked like, and per family a count by kind:

  outside the map   at the true pose, fewer than half of the scan's sampled voxels land on cells the
                    map holds (truth_known_share < 0.5): the vehicle is beyond the map (the edge
                    family's queries past its coverage), so every answer is wrong; one that looks like a
                    mapped place (a repeated zone continues past the map's edge) is not detectable from
                    the scan
  flip              the answer is turned 180 deg (+-20) from the truth: a symmetric street or hall
  truth outscored   a fully verified hypothesis within 5 m / 10 deg of the truth existed and scored
                    below the answer
  truth not found   none did (the matching or the cliques missed it, or the search never reached it)
(the first kind that applies). Reads FAMILIES_DIR/<family>/<world>/results.json (bench/families.sh).

Usage: bench/wrong_answers.py FAMILIES_DIR [--families "p0 p3 ..."] [--quiet]
Standard library only."""
import argparse
import collections
import glob
import json
import os

FAMILY_ORDER = "p0 p3 p8 p15 o10 o20 thin b16 b64 b128 cross cheap edge ns spur".split()  # bench/families.sh's
KINDS = ["outside the map", "flip", "truth outscored", "truth not found"]


def kind_of(q):
    d = q.get("diagnostics", {})
    if d.get("verified") and d.get("truth_known_share", 1.0) < 0.5:  # (0 without a semantic layer)
        return KINDS[0]
    if abs(abs(q["rotation_error_deg"]) - 180.0) <= 20.0:
        return KINDS[1]
    hyps = [h for h in d.get("hypotheses", []) if h.get("fully_verified")]
    answer = max((h["verified_score"] for h in hyps), default=0.0)
    near = [h for h in hyps if h["distance_to_truth_m"] < 5.0 and abs(h["yaw_error_deg"]) < 10.0
            and h["verified_score"] < answer]
    return KINDS[2] if near else KINDS[3]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("dir")
    ap.add_argument("--families", default="")
    ap.add_argument("--quiet", action="store_true", help="the per-family counts only")
    a = ap.parse_args()
    fams = a.families.replace(",", " ").split() or [f for f in FAMILY_ORDER if os.path.isdir(os.path.join(a.dir, f))]
    total = collections.Counter()
    answered_all = 0
    for fam in fams:
        counts = collections.Counter()
        answered = 0
        for f in sorted(glob.glob(os.path.join(a.dir, fam, "*", "results.json"))):
            world = os.path.basename(os.path.dirname(f))
            for q in json.load(open(f))["modes"]["gsf"]["queries"]:
                if not q.get("answered"):
                    continue
                answered += 1
                if q["success"]:
                    continue
                k = kind_of(q)
                counts[k] += 1
                if a.quiet:
                    continue
                d = q.get("diagnostics", {})
                e = d.get("confidence_evidence", {})
                place = "zone" if q.get("in_zone") else "near" if q.get("near_zone") else "open"
                print(f"{fam:5} {world:11} query {q['index']:3} {place:4} {k:15} t {q['translation_error_m']:6.1f} m"
                      f" r {q['rotation_error_deg']:5.1f} deg  confidence {q['confidence']:.3f}"
                      f"  z_rival {e.get('z_rival', 0):.2f} margin {e.get('rival_margin', 0):.3f}"
                      f" inlier share {e.get('inlier_share', 0):.2f} known {e.get('known_share', 0):.2f}"
                      f"  truth known {d.get('truth_known_share', float('nan')):.2f}")
        total.update(counts)
        answered_all += answered
        print(f"{fam}: {sum(counts.values())} wrong of {answered} answered: "
              + ", ".join(f"{k} {counts[k]}" for k in KINDS))
    if len(fams) > 1:
        print(f"all: {sum(total.values())} wrong of {answered_all} answered: " + ", ".join(f"{k} {total[k]}" for k in KINDS))


if __name__ == "__main__":
    main()
