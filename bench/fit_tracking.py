#!/usr/bin/env python3
"""Fits the tracking confidence model of core/src/tracker.cpp (kTrackingConfidenceModel) to recorded
tracking attempts, and replays any model on held-out ones.

The model (core/include/gsf/detail/tracker.h): P = s(a_r + b_r z_rival) s(a_s + b_s z_shift)
s(a_t + b_t z_turn), each z clipped to [-3, 10]; a tracked pose has no rivals, so z_rival is its
closest probe of either kind. The evidence is the library's own, written per scan by `gsf evaluate
--mode track --json` (`track_attempt`: every track() call's pose error, evidence and distance from its
prediction, a loss's too).

What is fitted. A tracked pose is meant to be within centimetres; one 1-5 m off is a pose the tracker
should not have vouched for, although the library's success criterion (5 m / 10 deg) counts it right.
With that criterion as the label, the many attempts that end 1-5 m from the truth at no peak (a
prediction knocked off, the search stopping short) teach the fit that a pose that is no peak is fine.
So the fit's positives are the attempts within --fit-within (default 1 m / 5 deg), a stricter event:
the model's P under-states the probability of the 5 m / 10 deg criterion, never over-states it. (5 deg,
not less: under a poor odometry ICP leaves right poses 2-4 deg off at their peak; with 2 deg as the
event the fit asked more of every pose.) The report counts confident wrong attempts by the library's
criterion, and confident attempts beyond the fit's too.

Which attempts a model decides. The tracker's reach rule makes a result farther than the pattern
search's reach from its prediction (--reach, 3.75 m by default) a loss whatever the probes say; those
attempts are left out of the fit and of the replay (their `from_prediction_m`).

Wrong attempts near and beyond the search's reach come from predictions knocked off on purpose:
`gsf evaluate --mode track --prediction-offset D` (D = 3, 4, 8) beside the usual runs (D = 0), and
runs with a poor odometry (--odometry-noise 0.3 and 1.0), each with and without --label-noise 0.15.
Name the JSON files so that --groups can pool them, e.g. att-SEED-nLABELNOISE-pD.json and
att-SEED-nLABELNOISE-oNOISE.json.

Usage:
  bench/fit_tracking.py --train FILE_OR_DIR [...] [--test FILE_OR_DIR [...]] [--min-confidence 0.9]
  bench/fit_tracking.py --model=a_r,b_r,a_s,b_s,a_t,b_t --test FILE_OR_DIR [...]   (replay only)
  --groups "p0 p3 p4 p8": pool the files whose name contains -GROUP. (default: one line per file)
Prints the fitted numbers as the C++ initializer of kTrackingConfidenceModel, then for the model and
for CURRENT (the library's) per group: attempts a model decides, right (5 m / 10 deg), confident right,
confident wrong, declined right, confident beyond the fit's event. Standard library only (the fitting
is bench/fit_confidence.py's)."""
import argparse
import glob
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import fit_confidence as fc  # noqa: E402

fc.FACTORS = [["z_rival"], ["z_shift"], ["z_turn"]]  # kTrackingConfidenceModel's order
CURRENT = [-1.817, 3.540, 3.391, 1.827, -9.125, 3.790]  # core/src/tracker.cpp as of 2026-12-06
ONE_SHOT_2026_11 = [-1.817, 3.540, 3.391, 1.827, -10.350, 3.164]  # the model tracking read before
FACTOR_NAMES = ["rival", "shift", "turn"]
SUCCESS = (5.0, 10.0)  # m, deg: the library's success criterion


def files(path):
    return [path] if os.path.isfile(path) else sorted(glob.glob(os.path.join(path, "*.json")))


def attempts(path, reach):
    """(clipped z per factor, translation error m, rotation error deg) per tracking attempt with
    evidence that a model decides (within the reach rule's distance of its prediction)."""
    out = []
    for f in files(path):
        try:
            d = json.load(open(f))
        except (OSError, ValueError):
            continue
        for s in d.get("scans", []):
            t = s.get("track_attempt")
            if not t or t.get("samples", 0) == 0 or float(t.get("from_prediction_m", 0.0)) > reach:
                continue
            z = tuple((min(10.0, max(-3.0, float(t[n[0]]))),) for n in fc.FACTORS)
            out.append((z, float(t["translation_error_m"]), float(t["rotation_error_deg"])))
    return out


def within(rec, limits):
    return rec[1] < limits[0] and rec[2] < limits[1]


def report(name, recs, m, threshold, fit_within):
    conf = [fc.probability(m, r[0]) >= threshold for r in recs]
    right = sum(within(r, SUCCESS) for r in recs)
    conf_right = sum(c and within(r, SUCCESS) for c, r in zip(conf, recs))
    conf_wrong = sum(c and not within(r, SUCCESS) for c, r in zip(conf, recs))
    conf_loose = sum(c and not within(r, fit_within) for c, r in zip(conf, recs))
    print(f"  {name}: {len(recs)} attempts, {right} right; confident right {conf_right}, confident wrong "
          f"{conf_wrong}, declined right {right - conf_right}; confident beyond {fit_within[0]:g} m / "
          f"{fit_within[1]:g} deg {conf_loose}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--train", nargs="*", default=[])
    ap.add_argument("--test", nargs="*", default=[])
    ap.add_argument("--model", help="replay these six numbers instead of fitting")
    ap.add_argument("--min-confidence", type=float, default=0.9)
    ap.add_argument("--fit-within", default="1,5", help="M,DEG: the fit's positives (default 1,5)")
    ap.add_argument("--reach", type=float, default=3.75, help="the reach rule's distance, m (default 3.75)")
    ap.add_argument("--l2", type=float, default=1e-3)
    ap.add_argument("--groups", default="", help="pool the files whose name contains -GROUP, per group")
    ap.add_argument("--hold", default="rival,shift",
                    help="factors (rival, shift, turn) kept at the one-shot model of 2026-11; the rest is "
                         "fitted (default rival,shift; 'none' fits all six numbers)")
    a = ap.parse_args()
    fit_within = tuple(float(x) for x in a.fit_within.split(","))
    if a.model:
        m = [float(x) for x in a.model.split(",")]
    else:
        data = [(r[0], within(r, fit_within), 1.0) for p in a.train for r in attempts(p, a.reach)]
        if not data:
            sys.exit("fit_tracking.py: no tracking attempts in --train")
        # Held factors keep the one-shot model of 2026-11's numbers; the others are fitted from there.
        held = [] if a.hold == "none" else a.hold.split(",")
        free = [FACTOR_NAMES[i // 2] not in held for i in range(len(ONE_SHOT_2026_11))]
        m, loss = fc.fit(data, a.l2, start=ONE_SHOT_2026_11 if held else None, free=free)
        print(f"fitted on {len(data)} attempts (loss {loss:.2f}):")
        print("const TrackingConfidenceModel kTrackingConfidenceModel = {" +
              ", ".join(f"{v:.3f}f" for v in m) + "};")
    sets = [("train", p) for p in a.train] + [("test", p) for p in a.test]
    for label, model in (("model", m), ("current", CURRENT)):
        print(f"{label} {', '.join(f'{v:.3f}' for v in model)} at {a.min_confidence}:")
        if not a.groups:
            for kind, p in sets:
                report(f"{kind} {p}", attempts(p, a.reach), model, a.min_confidence, fit_within)
            continue
        for kind in ("train", "test"):
            for g in a.groups.split():
                recs = [r for k, p in sets if k == kind and f"-{g}" in os.path.basename(p)
                        for r in attempts(p, a.reach)]
                if recs:
                    report(f"{kind} {g}", recs, model, a.min_confidence, fit_within)


if __name__ == "__main__":
    main()
