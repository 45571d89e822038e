#!/usr/bin/env python3
"""How often a thin-margin answer is right, per family (issue 24, the calibration limit).

A thin-margin answer: its best rival scores nearly as well (z_rival < 1.2 and rival_margin < 0.1 in
diagnostics.confidence_evidence) while the answer explains most of the scan's instances on the map
(inlier_share > 0.5), not capped at 0.5 anyway (fewer than 5 instances, or under a third of the scan on
the map's observed cells: fit_confidence.records' flag). The confidence sees
the same evidence in every family, so it gives these answers about one probability; when the share that
is right differs by family, no single calibration can hold on every family, and the table says by how
much. Distractor directories (bench/distractors.sh) are left out: every answer there is wrong.

Usage: bench/thin_margin.py DIR [DIR ...] [--model=a_r,...]
DIR is a bench/families.sh output (DIR/<family>/<world>/results.json). The model defaults to
kConfidenceModel of core/src/confidence.cpp. Standard library only."""
import argparse
import glob
import os

import declined_right
import fit_confidence as fc

Z_RIVAL, MARGIN, SHARE = 1.2, 0.1, 0.5


def thin_margin(z):
    """z: fit_confidence.features' tuple ((z_rival, rival_margin), (z_shift_far, z_shift, z_turn), (inlier_share,)),
    clipped to ranges that hold these thresholds."""
    (z_rival, margin), _, (share,) = z
    return z_rival < Z_RIVAL and margin < MARGIN and share > SHARE


def family_rows(family_dir, m):
    """(answers with a pose, thin-margin ones, of those right, their mean predicted probability), from
    fit_confidence.records (the queries with a pose and confidence evidence)."""
    recs = fc.records(family_dir, "gsf")
    thin = [(z, y) for z, y, _, capped in recs if not capped and thin_margin(z)]
    return len(recs), len(thin), sum(y for _, y in thin), sum(fc.probability(m, z) for z, _ in thin)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("dirs", nargs="+")
    ap.add_argument("--model", default="")
    a = ap.parse_args()
    m = fc.parse_model(a.model) if a.model else declined_right.library_model()
    print("| family | answers with a pose | thin margin | of those right | mean predicted |")
    print("| --- | ---: | ---: | ---: | ---: |")
    for d in a.dirs:
        for family_dir in sorted(p for p in glob.glob(os.path.join(d, "*")) if os.path.isdir(p)):
            posed, thin, right, predicted = family_rows(family_dir, m)
            if thin:
                print(f"| {os.path.basename(family_dir)} | {posed} | {thin} | {100.0 * right / thin:.1f}% | "
                      f"{100.0 * predicted / thin:.1f}% |")


if __name__ == "__main__":
    main()
