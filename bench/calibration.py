#!/usr/bin/env python3
"""Calibration of the localizer's confidence, pooled over runs: per DIR and mode, the reliability table
(10 confidence bins over all queries; a query without a pose counts as confidence 0 and a failure), the
expected calibration error (ECE), the Brier score, and the decision rule's outcome (answered = status Ok
and confident): precision, share answered, wrong answers, declined right ones.

DIR is a suite directory (DIR/*/results.json, bench/suite.sh), a directory of `gsf evaluate --json`
files (DIR/*.json) or one such file. Records come from each query's "confidence", "answered", "success"
and "status"; with --min-confidence P "answered" is recomputed as status Ok and confidence >= P.

One summary line per DIR and mode (greppable), then its table unless --brief:
  DIR mode n=.. success=..% answered=..% precision=..% wrong=.. declined_right=.. ece=..% brier=.. min_confidence=..
With several DIRs a pooled line "all" follows. --svg OUT.svg draws the reliability diagram, one curve
per DIR and mode. Python standard library only; bench/suite_summary.py uses the same functions.

--by-zone adds, per DIR and mode, one summary line per place of the query in a simulated world: "zone"
(in the repetitive zone), "near" (within reach of it) and "open" (elsewhere), from each query's in_zone /
near_zone: where a single scan's declines and wrong answers are.

With --model=a_r,b_r,... each query's confidence is recomputed from its recorded evidence with that model
(bench/fit_confidence.py's form and default factors), and answered at --min-confidence (default 0.9): the
tables and the diagram of a model other than the one of the binary that ran.

Usage: bench/calibration.py DIR [DIR ...] [--mode gsf|all|a,b] [--min-confidence P] [--svg OUT.svg] [--brief]
                            [--by-zone] [--model=...]"""
import argparse
import glob
import json
import math
import os
import sys

BINS = 10
MODEL = None  # --model: the fit_confidence.py model to replay, or None for the recorded confidence


def result_files(path):
    """The evaluate JSON files of a suite dir, a dir of JSON files, or one file."""
    if os.path.isfile(path):
        return [path]
    suite = sorted(glob.glob(os.path.join(path, "*", "results.json")))
    return suite if suite else sorted(glob.glob(os.path.join(path, "*.json")))


def load_queries(path):
    """{mode: [per-query dict, ...]} pooled over the evaluate JSON files under path, and the rule's
    thresholds the files were evaluated with."""
    by_mode, thresholds = {}, set()
    for f in result_files(path):
        try:
            r = json.load(open(f))
        except (OSError, ValueError):
            continue
        for mode, v in r.get("modes", {}).items():
            if "min_confidence" in v.get("summary", {}):
                thresholds.add(v["summary"]["min_confidence"])
            by_mode.setdefault(mode, []).extend(v.get("queries", []))
    return by_mode, thresholds


def place_of(q):
    """zone (in the repetitive zone), near (within reach of it) or open; simulated worlds only."""
    return "zone" if q.get("in_zone") else ("near" if q.get("near_zone") else "open")


def has_pose(q):
    return q.get("status") == "Ok"


def confidence_of(q):
    """A query without a pose counts as confidence 0."""
    if not has_pose(q):
        return 0.0
    if MODEL is None:
        return float(q["confidence"])
    e = q.get("diagnostics", {}).get("confidence_evidence")
    if not e or e.get("samples", 0) == 0:
        return 0.0
    import fit_confidence  # bench/, beside this file
    return fit_confidence.probability(MODEL, fit_confidence.features(e, q))


def answered(q, min_confidence=None):
    """The decision rule as recorded, or recomputed at min_confidence."""
    if min_confidence is None:
        return bool(q["answered"])
    return has_pose(q) and confidence_of(q) >= min_confidence


def reliability_bin(c):
    """The largest k with c >= k / 10 (as tools/gsf/evaluation.cpp)."""
    b = 0
    while b + 1 < BINS and c >= (b + 1) / BINS:
        b += 1
    return b


def reliability(queries):
    """reliability: bins (lo, hi, count, mean_confidence, success_rate; None when empty), ece, brier."""
    n = [0] * BINS
    conf = [0.0] * BINS
    succ = [0.0] * BINS
    brier = 0.0
    for q in queries:
        c, s = confidence_of(q), 1.0 if q.get("success") else 0.0
        b = reliability_bin(c)
        n[b] += 1
        conf[b] += c
        succ[b] += s
        brier += (c - s) ** 2
    total = sum(n)
    bins, ece = [], 0.0
    for b in range(BINS):
        mean = conf[b] / n[b] if n[b] else None
        rate = succ[b] / n[b] if n[b] else None
        if n[b]:
            ece += n[b] / total * abs(rate - mean)
        bins.append({"lo": b / BINS, "hi": (b + 1) / BINS, "count": n[b], "mean_confidence": mean,
                     "success_rate": rate})
    return {"reliability": bins, "ece": ece, "brier": brier / total if total else 0.0}


def rule_outcome(queries, min_confidence=None):
    """Named as gsf evaluate's summary: answered (count) and answered_at_rule (share), wrong_at_rule
    (answered, not a success), declined_right (a success, not answered), precision_at_rule (1 when
    nothing is answered)."""
    a = w = d = s = 0
    for q in queries:
        ans, ok = answered(q, min_confidence), bool(q.get("success"))
        a += ans
        w += ans and not ok
        d += ok and not ans
        s += ok
    n = len(queries)
    return {"queries": n, "successes": s, "success_rate": s / n if n else 0.0, "answered": a,
            "answered_at_rule": a / n if n else 0.0, "precision_at_rule": (a - w) / a if a else 1.0,
            "wrong_at_rule": w, "declined_right": d}


def calibration(queries, min_confidence=None):
    """rule_outcome and reliability of one set of queries, in one dict (the evaluate summary's keys);
    min_confidence: None when the recorded "answered" was used."""
    out = rule_outcome(queries, min_confidence)
    out.update(reliability(queries))
    out["min_confidence"] = min_confidence
    return out


def threshold_text(min_confidence, recorded):
    """The rule's threshold: the one asked for, else the one the files were evaluated with."""
    if min_confidence is not None:
        return f"{min_confidence:.2f}"
    return f"{next(iter(recorded)):.2f}" if len(recorded) == 1 else ("mixed" if recorded else "?")


def summary_line(label, mode, c, threshold):
    return (f"{label} {mode} n={c['queries']} success={100 * c['success_rate']:.1f}% "
            f"answered={100 * c['answered_at_rule']:.1f}% precision={100 * c['precision_at_rule']:.1f}% "
            f"wrong={c['wrong_at_rule']} declined_right={c['declined_right']} ece={100 * c['ece']:.1f}% "
            f"brier={c['brier']:.3f} "
            f"min_confidence={threshold}")


def table_lines(c):
    lines = ["  bin            n  confidence  success"]
    for b in c["reliability"]:
        edge = "]" if b["hi"] >= 1 else ")"
        if b["count"]:
            lines.append(f"  [{b['lo']:.1f},{b['hi']:.1f}{edge}  {b['count']:6d}  {b['mean_confidence']:10.3f}  "
                         f"{b['success_rate']:7.3f}")
        else:
            lines.append(f"  [{b['lo']:.1f},{b['hi']:.1f}{edge}  {0:6d}  {'-':>10}  {'-':>7}")
    return lines


class Svg:
    """Pixel-space SVG whose viewBox is the drawn content's bounding box (text at 0.6 em a character)."""

    def __init__(self):
        self.body, self.box = [], [float("inf"), float("inf"), float("-inf"), float("-inf")]

    def include(self, x, y):
        b = self.box
        b[0], b[1], b[2], b[3] = min(b[0], x), min(b[1], y), max(b[2], x), max(b[3], y)

    def line(self, x0, y0, x1, y1, stroke, width, dash=""):
        self.include(x0, y0)
        self.include(x1, y1)
        d = f' stroke-dasharray="{dash}"' if dash else ""
        self.body.append(f'<line x1="{x0:.2f}" y1="{y0:.2f}" x2="{x1:.2f}" y2="{y1:.2f}" stroke="{stroke}" '
                         f'stroke-width="{width}"{d}/>')

    def rect(self, x, y, w, h, fill, opacity=1.0, stroke=""):
        self.include(x, y)
        self.include(x + w, y + h)
        s = f' stroke="{stroke}"' if stroke else ""
        self.body.append(f'<rect x="{x:.2f}" y="{y:.2f}" width="{w:.2f}" height="{h:.2f}" fill="{fill}" '
                         f'fill-opacity="{opacity}"{s}/>')

    def circle(self, x, y, r, fill):
        self.include(x - r, y - r)
        self.include(x + r, y + r)
        self.body.append(f'<circle cx="{x:.2f}" cy="{y:.2f}" r="{r}" fill="{fill}"/>')

    def polyline(self, points, stroke, width):
        for x, y in points:
            self.include(x, y)
        pts = " ".join(f"{x:.2f},{y:.2f}" for x, y in points)
        self.body.append(f'<polyline points="{pts}" fill="none" stroke="{stroke}" stroke-width="{width}"/>')

    def text(self, x, y, s, size, anchor="start", rotate=0, fill="#222"):
        w = 0.6 * size * len(s)
        left = {"start": 0, "middle": -w / 2, "end": -w}[anchor]
        co, si = math.cos(math.radians(rotate)), math.sin(math.radians(rotate))
        for dx in (left, left + w):
            for dy in (-size, 0.25 * size):
                self.include(x + co * dx - si * dy, y + si * dx + co * dy)
        t = f' transform="rotate({rotate} {x:.2f} {y:.2f})"' if rotate else ""
        s = s.replace("&", "&amp;").replace("<", "&lt;")
        self.body.append(f'<text x="{x:.2f}" y="{y:.2f}" font-family="sans-serif" font-size="{size}" '
                         f'text-anchor="{anchor}" fill="{fill}"{t}>{s}</text>')

    def finish(self, margin=10):
        x, y = self.box[0] - margin, self.box[1] - margin
        w, h = self.box[2] - self.box[0] + 2 * margin, self.box[3] - self.box[1] + 2 * margin
        return (f'<svg xmlns="http://www.w3.org/2000/svg" width="{w:.2f}" height="{h:.2f}" '
                f'viewBox="{x:.2f} {y:.2f} {w:.2f} {h:.2f}">\n<rect x="{x:.2f}" y="{y:.2f}" width="{w:.2f}" '
                f'height="{h:.2f}" fill="white"/>\n' + "\n".join(self.body) + "\n</svg>\n")


# The diagram's layout (as tools/gsf/reliability_svg.cpp): the curves' square, the count bars below.
LEFT, TOP, SIDE = 70, 50, 420
BARS_TOP, BARS_H, BARS_ROOM = TOP + SIDE + 18, 120, 26
COLOURS = ["#4477aa", "#ee6677", "#228833", "#ccbb44", "#aa3377", "#66ccee", "#bbbbbb", "#000000"]


def x_of(c):
    return LEFT + SIDE * c


def y_of(s):
    return TOP + SIDE * (1 - s)


def draw_axes(svg, title):
    bottom = BARS_TOP + BARS_H
    svg.rect(LEFT, TOP, SIDE, SIDE, "#ffffff", 1, "#444444")
    svg.rect(LEFT, BARS_TOP, SIDE, BARS_H, "#ffffff", 1, "#444444")
    for k in range(1, BINS):
        svg.line(x_of(k / BINS), TOP, x_of(k / BINS), TOP + SIDE, "#e4e4e4", 0.8)
        svg.line(x_of(k / BINS), BARS_TOP, x_of(k / BINS), bottom, "#e4e4e4", 0.8)
    for k in range(6):
        v = k / 5
        svg.line(x_of(v), bottom, x_of(v), bottom + 5, "#444444", 1)
        svg.text(x_of(v), bottom + 18, f"{v:.1f}", 12, "middle")
        svg.line(LEFT - 5, y_of(v), LEFT, y_of(v), "#444444", 1)
        svg.text(LEFT - 8, y_of(v) + 4, f"{v:.1f}", 12, "end")
    svg.line(x_of(0), y_of(0), x_of(1), y_of(1), "#888888", 1.2, "5 4")
    svg.text(LEFT + SIDE / 2, bottom + 38, "predicted confidence (bin mean; bins of 0.1)", 13, "middle")
    svg.text(LEFT - 42, TOP + SIDE / 2, "observed success rate (t < 5 m, r < 10 deg)", 13, "middle", -90)
    svg.text(LEFT - 42, BARS_TOP + BARS_H / 2, "queries", 13, "middle", -90)
    svg.text(LEFT, TOP - 28, title, 15)
    svg.text(LEFT, TOP - 10, "all queries; a query without a pose counts as confidence 0 and a failure", 11,
             fill="#555555")


def draw_counts(svg, series):
    most = max([1] + [b["count"] for _, c in series for b in c["reliability"]])
    bin_px = SIDE / BINS
    bar_px = (bin_px - 6) / len(series)
    bottom, scale = BARS_TOP + BARS_H, (BARS_H - BARS_ROOM) / most
    for i, (_, c) in enumerate(series):
        for k, b in enumerate(c["reliability"]):
            if not b["count"]:
                continue
            x, h = x_of(k / BINS) + 3 + bar_px * i, b["count"] * scale
            svg.rect(x, bottom - h, bar_px - 1, h, COLOURS[i % len(COLOURS)], 0.85)
            if bar_px >= 6:
                svg.text(x + bar_px / 2 + 3, bottom - h - 3, str(b["count"]), 9, "start", -90)
    for tick in (0, most):
        svg.line(LEFT - 5, bottom - tick * scale, LEFT, bottom - tick * scale, "#444444", 1)
        svg.text(LEFT - 8, bottom - tick * scale + 4, str(tick), 12, "end")


def draw_curves_and_legend(svg, series, min_confidence):
    x, y = LEFT + SIDE + 24, TOP + 10
    for i, (label, c) in enumerate(series):
        colour = COLOURS[i % len(COLOURS)]
        pts = [(x_of(b["mean_confidence"]), y_of(b["success_rate"])) for b in c["reliability"] if b["count"]]
        if len(pts) > 1:
            svg.polyline(pts, colour, 2)
        for px, py in pts:
            svg.circle(px, py, 4, colour)
        svg.line(x, y - 4, x + 22, y - 4, colour, 2)
        svg.circle(x + 11, y - 4, 4, colour)
        svg.text(x + 30, y, f"{label}: ECE {100 * c['ece']:.1f}%, Brier {c['brier']:.3f}, n={c['queries']}", 12)
        y += 22
    svg.line(x, y - 4, x + 22, y - 4, "#888888", 1.2, "5 4")
    svg.text(x + 30, y, "perfect calibration", 12)
    if min_confidence is not None:
        xt = x_of(min_confidence)
        svg.line(xt, TOP, xt, BARS_TOP + BARS_H, "#cc3311", 1.4, "3 3")
        svg.text(xt + 4, TOP + SIDE - 8, f"rule: confidence >= {min_confidence:.2f}", 11, fill="#cc3311")
        y += 22
        svg.line(x + 11, y - 12, x + 11, y + 4, "#cc3311", 1.4, "3 3")
        svg.text(x + 30, y, "decision rule threshold", 12)
    y += 22
    svg.rect(x + 6, y - 12, 10, 12, "#888888", 0.85)
    svg.text(x + 30, y, "bars: queries per bin, one per curve", 12)


def reliability_svg(series, min_confidence, title="Reliability of the localizer's confidence"):
    """series: [(label, calibration dict)]; min_confidence: the rule's threshold to mark (None: none)."""
    svg = Svg()
    draw_axes(svg, title)
    if series:
        draw_counts(svg, series)
    draw_curves_and_legend(svg, series, min_confidence)
    return svg.finish()


def pick_modes(available, spec):
    if spec == "all":
        return available
    return [m for m in spec.split(",") if m in available]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("dirs", nargs="+", metavar="DIR")
    ap.add_argument("--mode", default="gsf", help="mode(s): a comma list or all (default gsf)")
    ap.add_argument("--min-confidence", type=float, default=None,
                    help="recompute answered as status Ok and confidence >= P (default: as recorded)")
    ap.add_argument("--svg", default="", help="write the reliability diagram here")
    ap.add_argument("--brief", action="store_true", help="summary lines only, no tables")
    ap.add_argument("--by-zone", action="store_true", help="also a summary line per zone / near / open query")
    ap.add_argument("--model", help="replay this model (bench/fit_confidence.py's numbers) on the evidence")
    a = ap.parse_args()
    if a.model:
        global MODEL
        sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
        import fit_confidence  # bench/, beside this file
        MODEL = fit_confidence.parse_model(a.model)
        if a.min_confidence is None:
            a.min_confidence = 0.9
    if a.min_confidence is not None and not 0 <= a.min_confidence <= 1:
        ap.error("--min-confidence must be in [0, 1]")
    pooled, series, marks, status = {}, [], set(), 0
    for d in a.dirs:
        by_mode, recorded = load_queries(d)
        marks |= recorded
        modes = pick_modes(list(by_mode), a.mode)
        if not modes:
            print(f"{d}: no results for mode {a.mode}", file=sys.stderr)
            status = 1
        for mode in modes:
            qs = by_mode[mode]
            if any("confidence" not in q or "answered" not in q for q in qs):
                print(f"{d} {mode}: queries without 'confidence'/'answered' (older evaluate JSON); skipped",
                      file=sys.stderr)
                status = 1
                continue
            c = calibration(qs, a.min_confidence)
            print(summary_line(d, mode, c, threshold_text(a.min_confidence, recorded)))
            if a.by_zone:
                for place in ("zone", "near", "open"):
                    part = [q for q in qs if place_of(q) == place]
                    if part:
                        print(summary_line(f"{d} [{place}]", mode, calibration(part, a.min_confidence),
                                           threshold_text(a.min_confidence, recorded)))
            if not a.brief:
                print("\n".join(table_lines(c)))
            series.append((f"{os.path.basename(os.path.normpath(d))} {mode}", c))
            pooled.setdefault(mode, []).extend(qs)
    if len(a.dirs) > 1:
        for mode, qs in pooled.items():
            c = calibration(qs, a.min_confidence)
            print(summary_line("all", mode, c, threshold_text(a.min_confidence, marks)))
            if not a.brief:
                print("\n".join(table_lines(c)))
    if a.svg:
        mark = a.min_confidence if a.min_confidence is not None else (marks.pop() if len(marks) == 1 else None)
        with open(a.svg, "w") as f:
            f.write(reliability_svg(series, mark))
        print(f"wrote {a.svg}")
    return status


if __name__ == "__main__":
    sys.exit(main())
