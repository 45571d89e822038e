#!/usr/bin/env python3
"""Plots bench/scale.sh's rows (OUT/scale.tsv) against road length as one SVG of four panels: build
time (wall, CPU), the builder's peak RSS (with the 256 MB target), its spill file (peak size, peak live
slots) and query time (median, p95; instance-only and GSF). Standard library only.
Usage: bench/scale_plot.py SCALE.TSV OUT.SVG"""
import csv
import sys

W, H, PAD = 330, 230, 46  # one panel, its left / bottom margin
COLOURS = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd"]


def number(text):
    try:
        return float(text)
    except ValueError:
        return None


def panel(x0, y0, title, xs, series, ref=None):
    """One panel at (x0, y0): each series (name, ys) as a polyline with points; ref: a dashed y line."""
    ys_all = [y for _, ys in series for y in ys if y is not None] + ([ref[1]] if ref else [])
    xmax, ymax = max(xs) * 1.05 or 1, max(ys_all + [1e-9]) * 1.15
    px = lambda x: x0 + PAD + (W - PAD - 10) * x / xmax
    py = lambda y: y0 + H - PAD + 10 - (H - PAD - 20) * y / ymax
    out = [f'<text x="{x0 + W / 2}" y="{y0 + 14}" text-anchor="middle" font-weight="bold">{title}</text>',
           f'<line x1="{px(0)}" y1="{py(0)}" x2="{px(xmax)}" y2="{py(0)}" stroke="black"/>',
           f'<line x1="{px(0)}" y1="{py(0)}" x2="{px(0)}" y2="{py(ymax)}" stroke="black"/>']
    for k in range(5):
        yv, xv = ymax * k / 4, xmax * k / 4
        out.append(f'<text x="{px(0) - 4}" y="{py(yv) + 4}" text-anchor="end">{yv:.3g}</text>')
        out.append(f'<text x="{px(xv)}" y="{py(0) + 15}" text-anchor="middle">{xv:.3g}</text>')
    out.append(f'<text x="{px(xmax / 2)}" y="{py(0) + 30}" text-anchor="middle">road km</text>')
    if ref:
        out.append(f'<line x1="{px(0)}" y1="{py(ref[1])}" x2="{px(xmax)}" y2="{py(ref[1])}" stroke="gray" '
                   f'stroke-dasharray="4,3"/><text x="{px(xmax)}" y="{py(ref[1]) - 3}" text-anchor="end" '
                   f'fill="gray">{ref[0]}</text>')
    for i, (name, ys) in enumerate(series):
        c = COLOURS[i % len(COLOURS)]
        pts = [(px(x), py(y)) for x, y in zip(xs, ys) if y is not None]
        if len(pts) > 1:
            out.append(f'<polyline fill="none" stroke="{c}" points="{" ".join(f"{a:.1f},{b:.1f}" for a, b in pts)}"/>')
        out += [f'<circle cx="{a:.1f}" cy="{b:.1f}" r="3" fill="{c}"/>' for a, b in pts]
        out.append(f'<text x="{px(0) + 8}" y="{y0 + 30 + 13 * i}" fill="{c}">{name}</text>')
    return out


def main():
    rows = list(csv.DictReader(open(sys.argv[1]), delimiter="\t"))
    gsf = [r for r in rows if r["mode"] == "gsf"] or rows
    inst = [r for r in rows if r["mode"] == "instance"]
    xs = [float(r["road_km"]) for r in gsf]
    col = lambda rs, k: [number(r[k]) for r in rs]
    body = panel(0, 0, "build time (s)", xs, [("wall", col(gsf, "build_s")), ("CPU", col(gsf, "build_cpu_s"))])
    body += panel(W, 0, "build peak RSS (MB)", xs, [("RSS", col(gsf, "rss_mb"))], ("target 256", 256))
    body += panel(0, H, "spill file (MB)", xs,
                  [("peak size", col(gsf, "spill_peak_mb")), ("live slots", col(gsf, "spill_live_mb"))])
    query = [("GSF median", col(gsf, "median_ms")), ("GSF p95", col(gsf, "p95_ms"))]
    if len(inst) == len(gsf):
        query += [("instance median", col(inst, "median_ms")), ("instance p95", col(inst, "p95_ms"))]
    body += panel(W, H, "query time (ms)", xs, query)
    with open(sys.argv[2], "w") as f:
        f.write(f'<svg xmlns="http://www.w3.org/2000/svg" width="{2 * W}" height="{2 * H}" font-family="sans-serif" '
                f'font-size="11">\n<rect width="100%" height="100%" fill="white"/>\n' + "\n".join(body) + "\n</svg>\n")


if __name__ == "__main__":
    main()
