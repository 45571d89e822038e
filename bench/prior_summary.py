#!/usr/bin/env python3
"""One line per `gsf evaluate --json` run (e.g. with --prior-sigma): queries, success, answered right,
confident wrong (answered, not within 5 m / 10 deg), queries with a pose, the prior's global checks and
contradictions (diagnostics.prior_global_check / prior_contradicted), median and mean time per query
in ms; then the totals over all files, with the median of all their queries' times (pooled). The
prior's time against one-shot's is the ratio of two runs' pooled medians, measured one after the other
on an idle machine.

Usage: bench/prior_summary.py RUN.json [RUN.json ...] [--mode gsf]
Standard library only."""
import argparse
import json
import statistics


def summary(path, mode):
    queries = json.load(open(path))["modes"][mode]["queries"]
    diag = [q.get("diagnostics", {}) for q in queries]
    times = [q["time_ms"] for q in queries]
    return dict(n=len(queries), success=sum(q["success"] for q in queries),
                right=sum(q["success"] and q["answered"] for q in queries),
                wrong=sum(q["answered"] and not q["success"] for q in queries),
                pose=sum(q["status"] == "Ok" for q in queries),
                checked=sum(bool(d.get("prior_global_check")) for d in diag),
                contradicted=sum(bool(d.get("prior_contradicted")) for d in diag),
                median=statistics.median(times) if times else float("nan"),
                mean=statistics.mean(times) if times else float("nan"), times=times)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("runs", nargs="+")
    ap.add_argument("--mode", default="gsf")
    args = ap.parse_args()
    keys = ("n", "success", "right", "wrong", "pose", "checked", "contradicted")
    total = dict.fromkeys(keys, 0)
    times = []
    print("run | queries | success | answered right | confident wrong | with a pose | checked | contradicted |"
          " median ms | mean ms")
    for path in args.runs:
        s = summary(path, args.mode)
        for k in keys:
            total[k] += s[k]
        times += s["times"]
        print(f"{path} | {s['n']} | {s['success']} | {s['right']} | {s['wrong']} | {s['pose']} | {s['checked']} |"
              f" {s['contradicted']} | {s['median']:.1f} | {s['mean']:.1f}")
    pooled = statistics.median(times) if times else float("nan")
    print("all | " + " | ".join(str(total[k]) for k in keys) + f" | {pooled:.2f} (pooled)")


if __name__ == "__main__":
    main()
