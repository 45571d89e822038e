#!/usr/bin/env python3
"""Fits the tracking confidence model of core/src/tracker.cpp (kTrackingConfidenceModel) to recorded
tracking attempts, and replays any model on held-out ones.

The model (core/include/gsf/detail/tracker.h): P = s(a_r + b_r z_rival) s(a_s + b_s z_shift)
s(a_t + b_t z_turn), each z clipped to [-3, 10]; a tracked pose has no rivals, so z_rival is its
closest probe of either kind. The evidence is the library's own, written per scan by `gsf evaluate
--mode track --json` (`track_attempt`: every track() call's pose error and evidence, a loss's too).
An attempt is a positive when its pose is within 5 m / 10 deg of the truth (the success criterion the
probability is about). Wrong attempts come from predictions off by more than the tracker can reach:
run the evaluations with a large --odometry-noise (e.g. 3.0) beside the usual ones.

Usage:
  bench/fit_tracking.py --train FILE_OR_DIR [...] [--test FILE_OR_DIR [...]] [--min-confidence 0.9]
  bench/fit_tracking.py --model=a_r,b_r,a_s,b_s,a_t,b_t --test FILE_OR_DIR [...]   (replay only)
Prints the fitted numbers as the C++ initializer of kTrackingConfidenceModel, then per argument the
replayed rule: attempts, right, confident right, confident wrong, declined right. Standard library
only (the fitting is bench/fit_confidence.py's)."""
import argparse
import glob
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import fit_confidence as fc  # noqa: E402

fc.FACTORS = [["z_rival"], ["z_shift"], ["z_turn"]]  # kTrackingConfidenceModel's order
CURRENT = [-1.817, 3.540, 3.391, 1.827, -10.350, 3.164]  # core/src/tracker.cpp as of 2026-12-06


def files(path):
    return [path] if os.path.isfile(path) else sorted(glob.glob(os.path.join(path, "*.json")))


def attempts(path):
    """(clipped z per factor, right) per tracking attempt with evidence."""
    out = []
    for f in files(path):
        try:
            d = json.load(open(f))
        except (OSError, ValueError):
            continue
        for s in d.get("scans", []):
            t = s.get("track_attempt")
            if not t or t.get("samples", 0) == 0:
                continue
            z = tuple((min(10.0, max(-3.0, float(t[n[0]]))),) for n in fc.FACTORS)
            out.append((z, t["translation_error_m"] < 5.0 and t["rotation_error_deg"] < 10.0))
    return out


def report(name, recs, m, threshold):
    right = sum(y for _, y in recs)
    conf = [fc.probability(m, z) >= threshold for z, _ in recs]
    conf_right = sum(c and y for c, (_, y) in zip(conf, recs))
    conf_wrong = sum(c and not y for c, (_, y) in zip(conf, recs))
    print(f"  {name}: {len(recs)} attempts, {right} right; confident right {conf_right}, "
          f"confident wrong {conf_wrong}, declined right {right - conf_right}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--train", nargs="*", default=[])
    ap.add_argument("--test", nargs="*", default=[])
    ap.add_argument("--model", help="replay these six numbers instead of fitting")
    ap.add_argument("--min-confidence", type=float, default=0.9)
    a = ap.parse_args()
    if a.model:
        m = [float(x) for x in a.model.split(",")]
    else:
        data = [(z, y, 1.0) for p in a.train for z, y in attempts(p)]
        if not data:
            sys.exit("fit_tracking.py: no tracking attempts in --train")
        m, loss = fc.fit(data)
        print(f"fitted on {len(data)} attempts (loss {loss:.2f}):")
        print("const TrackingConfidenceModel kTrackingConfidenceModel = {" +
              ", ".join(f"{v:.3f}f" for v in m) + "};")
    for label, model in (("model", m), ("current", CURRENT)):
        print(f"{label} {', '.join(f'{v:.3f}' for v in model)} at {a.min_confidence}:")
        for p in a.train + a.test:
            report(("train " if p in a.train else "test ") + p, attempts(p), model, a.min_confidence)


if __name__ == "__main__":
    main()
