#!/usr/bin/env python3
"""What the prior's check reads before it runs (issue 27: a wrong prior never gives a confident wrong
pose; docs/vehicle-modes.md, *The prior's check at the whole-scan probes*). For a run with a position
prior (bench/reevaluate.sh SRC OUT --prior-sigma 5 --prior-radius 20 [--prior-bias B]) prints: the
answers confident before the check, the wrong ones among them with the z_rival the trigger read, which
trigger would check each (a thin margin z_rival < THRESHOLD, a clique-only answer, a copy beyond the
disc), the confident wrong answers left after the check, and for thresholds 2.5-5 how many right and
wrong answers only the thin-margin trigger checks.

Reads DIR/<family>/<world>/results.json (fields prior_confident_before_check, prior_trigger_z_rival,
prior_dropped_best_inliers, inliers of the gsf mode's queries).

Usage: bench/prior_check_margin.py DIR [--threshold 4] [--min-inliers 3] [--copy-share 0.8]
Standard library only."""
import argparse
import glob
import json
import os


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("dir")
    ap.add_argument("--threshold", type=float, default=4.0, help="Localizer::kPriorGlobalCheckZ")
    ap.add_argument("--min-inliers", type=int, default=3, help="hypotheses.min_inliers")
    ap.add_argument("--copy-share", type=float, default=0.8, help="Localizer::kPriorCopyInlierShare")
    a = ap.parse_args()
    rows = []
    for f in sorted(glob.glob(os.path.join(a.dir, "*", "*", "results.json"))):
        family = os.path.basename(os.path.dirname(os.path.dirname(f)))
        for q in json.load(open(f))["modes"]["gsf"]["queries"]:
            d = q.get("diagnostics", {})
            if not d.get("prior_confident_before_check"):
                continue
            inliers = q.get("inliers", 0)
            rows.append({
                "family": family,
                "z": d["prior_trigger_z_rival"],
                "clique_only": inliers <= a.min_inliers,
                "copy": d["prior_dropped_best_inliers"] >= a.copy_share * inliers,
                "right": q["success"],
                "answered": q["answered"],
            })
    wrong = [r for r in rows if not r["right"]]
    print(f"{a.dir}: {len(rows)} confident before the check, {len(wrong)} of them wrong, "
          f"{sum(r['answered'] for r in wrong)} of those still answered after it")
    for r in sorted(wrong, key=lambda r: r["z"]):
        print(f"  z_rival {r['z']:.2f}  clique-only {int(r['clique_only'])}  copy beyond the disc "
              f"{int(r['copy'])}  answered after {int(r['answered'])}  {r['family']}")
    only_thin = [r for r in wrong if not r["clique_only"] and not r["copy"]]
    if only_thin:
        print(f"wrong answers only the thin margin checks: {len(only_thin)}, z_rival "
              f"{min(r['z'] for r in only_thin):.2f}-{max(r['z'] for r in only_thin):.2f}")
    for t in (2.5, 3.0, 3.5, 4.0, 4.5, 5.0):
        right = sum(1 for r in rows if r["right"] and r["z"] < t and not r["clique_only"] and not r["copy"])
        bad = sum(1 for r in only_thin if r["z"] < t)
        print(f"threshold {t:.1f}: checked by the thin margin alone: {right} right, {bad} of "
              f"{len(only_thin)} wrong")


if __name__ == "__main__":
    main()
