#!/usr/bin/env python3
"""Replays the localizer's ambiguity on recorded per-query diagnostics (gsf evaluate --json), so an
ambiguity definition can be compared on every world of a suite without re-running the localizer.

Historical tool: it replays the OLD decision rule, "answer when ambiguity <= threshold", from before
the library decided on its calibrated confidence (LocalizeResult::confident, issue 24). The evaluation
now answers by that rule; bench/calibration.py measures it. Ambiguity remains a per-query diagnostic.

Usage: bench/ambiguity_replay.py [--mode gsf] [--threshold 0.5] NAME=DIR [NAME=DIR ...]
  DIR holds results.json files (bench/suite.sh --out DIR: DIR/<world>/results.json) or evaluate JSON
  files directly (bench/real_data.sh: DIR/*.json). Prints, per candidate definition and per DIR, the
  share of queries answered (ambiguity <= threshold), the precision of the answers, and the number of
  wrong answers. The first row replays core/src/localizer.cpp as configured; `check` counts queries whose
  replayed ambiguity differs from the recorded one (0 = the replay is faithful).

The replay uses what the diagnostics carry: the reported hypotheses (up to 16, best verified score first,
with pose, agree / disagree weights, scored voxels and whether they were fully scored) and the inliers.
"""
import argparse, glob, json, math

def load(d, mode):
    out = []
    for f in sorted(glob.glob(d + "/*/results.json") + glob.glob(d + "/*.json")):
        try:
            r = json.load(open(f))
        except (OSError, ValueError):
            continue
        if mode in r.get("modes", {}):
            out += r["modes"][mode]["queries"]
    return out

def yaw_diff(a, b):
    return abs((a - b + 180.0) % 360.0 - 180.0)

def ambiguity(q, quality="fraction", low=0.80, high=0.95, scale=0.03, rival_by_pose=True,
              same_m=2.0, same_deg=5.0, min_inliers=3):
    if q["status"] != "Ok":
        return None
    full = [h for h in q["diagnostics"].get("hypotheses", []) if h.get("fully_verified")]
    if not full:
        return 1.0
    a = full[0]
    support = min_inliers / max(q["inliers"], 1)
    rival = 0.0
    for h in full[1:]:
        if rival_by_pose and math.hypot(h["x"] - a["x"], h["y"] - a["y"]) <= same_m and \
                yaw_diff(h["yaw_deg"], a["yaw_deg"]) <= same_deg:
            continue  # the same answer, not a rival
        rival = math.exp(-max(0.0, a["verified_score"] - h["verified_score"]) / (scale * max(a["verified_voxels"], 1)))
        break
    if quality == "per-voxel":
        qq = a["verified_score"] / max(a["verified_voxels"], 1)
    else:
        w = a["verified_agree"] + a["verified_disagree"]
        qq = (a["verified_agree"] - a["verified_disagree"]) / w if w > 0 else -1.0
    return min(1.0, max(support, rival, (high - qq) / (high - low)))

def stats(queries, threshold, **kw):
    answered = right = 0
    for q in queries:
        a = ambiguity(q, **kw)
        if a is not None and a <= threshold:
            answered += 1
            right += bool(q.get("success"))
    n = max(len(queries), 1)
    return 100.0 * answered / n, 100.0 * right / answered if answered else 100.0, answered - right

CANDIDATES = [
    ("as configured", {}),
    ("before: per-voxel 0.60-0.75, twins are rivals", dict(quality="per-voxel", low=0.60, high=0.75, rival_by_pose=False)),
    ("twins not rivals, per-voxel 0.60-0.75", dict(quality="per-voxel", low=0.60, high=0.75)),
    ("fraction 0.75-0.90", dict(low=0.75, high=0.90)),
    ("fraction 0.85-0.95", dict(low=0.85, high=0.95)),
    ("fraction 0.80-0.95, margin 0.05", dict(scale=0.05)),
]

def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--mode", default="gsf")
    ap.add_argument("--threshold", type=float, default=0.5)
    ap.add_argument("sets", nargs="+", help="NAME=DIR")
    a = ap.parse_args()
    sets = [(s.split("=", 1)[0], load(s.split("=", 1)[1], a.mode)) for s in a.sets]
    for name, qs in sets:
        bad = sum(1 for q in qs if ambiguity(q) is not None and abs(ambiguity(q) - q["ambiguity"]) > 1e-3)
        print(f"check {name}: {len(qs)} queries, {bad} replayed ambiguities differ from the recorded ones")
    for label, kw in CANDIDATES:
        cells = []
        for name, qs in sets:
            ans, prec, wrong = stats(qs, a.threshold, **kw)
            cells.append(f"{name}: answered {ans:5.1f}% precision {prec:6.2f}% wrong {wrong:3d}")
        print(f"{label:48} " + "  ".join(cells))

if __name__ == "__main__":
    main()
