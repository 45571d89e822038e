#!/usr/bin/env python3
"""Fits the confidence model of core/src/confidence.cpp (kConfidenceModel) to recorded queries, and
replays any model on held-out ones.

The model (core/include/gsf/detail/confidence.h): P = s(a_r + b_r z_rival inlier_share)
s(a_p + b_f z_shift_far + b_s z_shift + b_t z_turn) s(a_i + b_i inlier_share), s the logistic function,
each z clipped to [-3, 10], the margin to [0, 1]. --factors fits other forms (e.g. z_rival+rival_margin:
the rival factor of the models before 2026-12-08). Every slope is held >= 0 (each factor rises with its
evidence), so a field that says nothing the others do not is fitted to 0 rather than to a sign flip.
The evidence is the library's own measurement, written per query by `gsf evaluate --json`
(diagnostics.confidence_evidence), so a fit needs no re-run of the localizer: fit on some runs, paste
the printed C++ line, rebuild, and report on other runs (other seeds) from the library itself.

Records: DIR is a suite directory (DIR/*/results.json), a directory of evaluate JSON files (DIR/*.json,
e.g. bench/distractors.sh's DIR/distractor) or one file; a families directory (DIR/<family>/...) is
expanded to its suites and their distractor directories. A query is a positive when it succeeded
(t < 5 m, r < 10 deg); queries without a pose are left out (their confidence is 0 by definition).
Distractor queries (a map of another world) are all negatives: without them the fit never sees a wrong
answer whose truth is absent from the map, the case a vehicle outside its map is in. (A distractor
query answered at its own true coordinates is left out: the simulated worlds share their road grid,
so there the other world can look the same.) --distractor-share sets their share of the total weight
(default 0.15: with the spur family in the training set, 0.1 answered more distractors on held-out
seeds than the model it replaced; docs/confidence.md).

Usage:
  bench/fit_confidence.py --train DIR [DIR ...] [--test DIR [DIR ...]] [--mode gsf] [--min-confidence 0.9]
  bench/fit_confidence.py --model=a_r,b_r,a_p,b_f,b_s,b_t,a_i,b_i --test DIR [DIR ...]   (replay only)
Prints the fitted numbers as the C++ initializer of kConfidenceModel, then per DIR (train and test) the
replayed rule: success, answered, precision, wrong, declined right, ECE. Standard library only."""
import argparse
import glob
import json
import math
import os

# The factors of the model, in kConfidenceModel's order: evidence field and the range it is clipped to
# (core/src/confidence.cpp clips the same way).
# A factor may read several fields (s(offset + slope_1 x_1 + slope_2 x_2)); --factors joins them with '+'.
FEATURES = {"z_rival": (-3.0, 10.0), "rival_margin": (0.0, 1.0), "z_shift": (-3.0, 10.0), "z_turn": (-3.0, 10.0),
            "z_shift_far": (-3.0, 10.0),
            "inlier_share": (0.0, 1.0), "inliers": (3.0, 12.0), "known_share": (0.0, 1.0),
            "excess_inliers": (0.0, 9.0), "excess_share": (0.0, 1.0), "beyond_clique": (0.0, 60.0),
            "explained_share": (0.0, 1.0), "explained_excess": (0.0, 20.0),
            "layer_share": (0.0, 1.0), "layer_excess": (0.0, 20.0),
            "rival_share": (-3.0, 10.0), "margin_share": (0.0, 1.0)}
FACTORS = [["rival_share"], ["z_shift_far", "z_shift", "z_turn"], ["inlier_share"]]


def parameter_count():
    return sum(1 + len(f) for f in FACTORS)


def parse_model(text):
    """--model's numbers, as many as the factors take (the nine-number models of 2026-12-06 evening to
    2026-12-07 replay with --factors z_rival+rival_margin,z_shift_far+z_shift+z_turn,inlier_share)."""
    m = [float(v) for v in text.split(",")]
    if len(m) != parameter_count():
        raise SystemExit(f"the model has {len(m)} numbers, the factors {','.join('+'.join(f) for f in FACTORS)} "
                         f"take {parameter_count()} (a nine-number model of 2026-12-07: fit_confidence.py "
                         "--factors z_rival+rival_margin,z_shift_far+z_shift+z_turn,inlier_share)")
    return m


def logistic(x):
    return 1.0 / (1.0 + math.exp(-x)) if x > -40.0 else 0.0


# Localizer::capped_for_few_instances: an answer from fewer than hypotheses.min_inliers + 2 = 5 of the
# scan's instances is capped at 0.5 whatever the model says; the replay caps the same way (the fit sees
# them uncapped: their evidence is evidence of the model's factors like any other).
FEW_INSTANCES, FEW_INSTANCES_CAP = 5, 0.5
# confidence_probability's cap for a scan mostly off the map (confidence.h, kMinKnownShare): at most 0.5
# when fewer than a third of the samples land on the map's observed cells; replayed the same way.
MIN_KNOWN_SHARE = 1.0 / 3.0
RESULTS = "results.json"  # --results: the file name of a suite's per-world results
DISTRACTOR = "distractor"  # --distractor-dir: bench/distractors.sh's directory in a suite dir


def result_files(path):
    if os.path.isfile(path):
        return [path]
    suite = sorted(glob.glob(os.path.join(path, "*", RESULTS)))
    return suite if suite else sorted(glob.glob(os.path.join(path, "*.json")))


def expand(dirs):
    """Families directories -> their suite dirs and distractor dirs; other paths as given."""
    out = []
    for d in dirs:
        subs = sorted(p for p in glob.glob(os.path.join(d, "*")) if os.path.isdir(p) and
                      glob.glob(os.path.join(p, "*", RESULTS)))
        if os.path.isdir(d) and not glob.glob(os.path.join(d, "*", RESULTS)) and subs:
            for s in subs:
                out.append(s)
                if os.path.isdir(os.path.join(s, DISTRACTOR)):
                    out.append(os.path.join(s, DISTRACTOR))
        else:
            out.append(d)
    return out


def records(path, mode):
    """(z triple, success, distractor) per query with a pose."""
    distractor = os.path.basename(os.path.normpath(path)).startswith("distractor")
    out = []
    for f in result_files(path):
        try:
            r = json.load(open(f))
        except (OSError, ValueError):
            continue
        for q in r.get("modes", {}).get(mode, {}).get("queries", []):
            e = q.get("diagnostics", {}).get("confidence_evidence")
            if q.get("status") != "Ok" or not e or e.get("samples", 0) == 0:
                continue
            if distractor and q["success"]:
                continue  # the other world happens to match here (same road grid): neither right nor wrong
            z = features(e, q)
            capped = (q.get("diagnostics", {}).get("instances", FEW_INSTANCES) < FEW_INSTANCES or
                      e.get("known_share", 1.0) < MIN_KNOWN_SHARE)
            out.append((z, bool(q["success"]) and not distractor, distractor, capped))
    return out


def features(e, q):
    """The model's inputs from a query's confidence evidence, clipped, per factor."""
    e = dict(e, inliers=e.get("inliers", q.get("inliers", 0)),
             explained=q.get("diagnostics", {}).get("answer_repeatable_instances", 0),
             layer=q.get("diagnostics", {}).get("answer_layer_instances", 0))
    return tuple(tuple(min(FEATURES[n][1], max(FEATURES[n][0], evidence(e, n))) for n in f) for f in FACTORS)


def evidence(e, name):
    """A recorded field, or one derived from them: the inliers beyond the 3 every clique explains, as a
    count and as a share of the instances on the map beyond those 3."""
    if name == "rival_share":  # z_rival (clipped) scaled by the inlier share: weak where few instances fit
        return min(10.0, max(-3.0, e["z_rival"])) * min(1.0, max(0.0, e["inlier_share"]))
    if name == "margin_share":
        return min(1.0, max(0.0, e["rival_margin"])) * min(1.0, max(0.0, e["inlier_share"]))
    if name == "excess_inliers":
        return float(e["inliers"]) - 3.0
    if name == "beyond_clique":
        return max(0.0, instances_on_map(e) - 3.0)
    if name == "explained_share":  # the instances the answer puts on a same-label map instance (< 2 m)
        on_map = max(instances_on_map(e), e["explained"], e["inliers"])
        return max(e["explained"], e["inliers"]) / on_map if on_map > 0 else 0.0
    if name == "layer_share":  # the instances the answer puts on a layer cell holding their class
        on_map = max(instances_on_map(e), e["layer"], e["inliers"])
        return max(e["layer"], e["inliers"]) / on_map if on_map > 0 else 0.0
    if name == "layer_excess":
        return max(e["layer"], e["inliers"]) - 3.0
    if name == "explained_excess":
        return max(e["explained"], e["inliers"]) - 3.0
    if name == "excess_share":
        on_map = instances_on_map(e)
        return (e["inliers"] - 3.0) / (on_map - 3.0) if on_map > 3.0 else 0.0
    return float(e[name])


def instances_on_map(e):
    """The inlier share's denominator: the scan's instances on the map's observed cells at the answer."""
    return e["inliers"] / e["inlier_share"] if e["inlier_share"] > 0 else 0.0


def factor_inputs(m, z):
    """The logistic's argument per factor."""
    out, i = [], 0
    for xs in z:
        out.append(m[i] + sum(m[i + 1 + j] * x for j, x in enumerate(xs)))
        i += 1 + len(xs)
    return out


def probability(m, z):
    p = 1.0
    for u in factor_inputs(m, z):
        p *= logistic(u)
    return p


def loss_and_gradient(m, data, l2):
    """Weighted negative log-likelihood of the product model and its gradient."""
    n = len(m)
    loss, grad = 0.0, [0.0] * n
    for z, y, w in data:
        s = [logistic(u) for u in factor_inputs(m, z)]
        p = 1.0
        for v in s:
            p *= v
        p = max(1e-12, min(1.0 - 1e-12, p))
        loss -= w * (math.log(p) if y else math.log(1.0 - p))
        scale = -w if y else w * p / (1.0 - p)  # d loss / d log p
        i = 0
        for k, xs in enumerate(z):
            g = scale * (1.0 - s[k])  # d log s_k / d u_k = 1 - s_k
            grad[i] += g
            for j, x in enumerate(xs):
                grad[i + 1 + j] += g * x
            i += 1 + len(xs)
    for i in range(n):
        loss += l2 * m[i] * m[i]
        grad[i] += 2.0 * l2 * m[i]
    return loss, grad


def fit(data, l2=1e-3, iterations=400, start=None, free=None):
    """iRprop-: a per-parameter step that grows while the gradient keeps its sign and shrinks when it
    flips (a smooth loss of a few parameters; converges in a few hundred passes). start: the numbers to
    begin from (default below); free: per number, whether it is fitted (default all; the others keep
    start's value)."""
    n = parameter_count()
    # z factors start at s(2 + z); a factor of a share (range 0..1) alone at s(10 (share - 0.5)).
    m = []
    for f in FACTORS:
        share = f[0] == "inlier_share"
        m += [-5.0 if share else 2.0] + [10.0 if share and j == 0 else 1.0 for j in range(len(f))]
    if start is not None:
        m = list(start)
    free = free or [True] * n
    slope = [j > 0 for f in FACTORS for j in range(1 + len(f))]  # False for each factor's offset
    step, last = [0.1 if free[i] else 0.0 for i in range(n)], [0.0] * n
    loss = 0.0
    for _ in range(iterations):
        loss, grad = loss_and_gradient(m, data, l2)
        for i in range(n):
            if not free[i]:
                continue
            if grad[i] * last[i] > 0:
                step[i] = min(step[i] * 1.2, 1.0)
            elif grad[i] * last[i] < 0:
                step[i] = max(step[i] * 0.5, 1e-6)
                grad[i] = 0.0
            if grad[i] > 0:
                m[i] -= step[i]
            elif grad[i] < 0:
                m[i] += step[i]
            if slope[i] and m[i] < 0.0:  # each factor rises with its evidence (tests/test_confidence.cpp)
                m[i] = 0.0
            last[i] = grad[i]
        if max(step) < 1e-5:
            break
    return m, loss


def report(name, recs, m, threshold):
    n = len(recs)
    if n == 0:
        return
    right = sum(r[1] for r in recs)
    probs = [min(FEW_INSTANCES_CAP, probability(m, z)) if capped else probability(m, z) for z, _, _, capped in recs]
    ans = [r[1] for p, r in zip(probs, recs) if p >= threshold]
    bins = [[0, 0.0, 0] for _ in range(10)]
    for p, (_, y, _, _) in zip(probs, recs):
        b = bins[min(9, int(p * 10))]
        b[0] += 1
        b[1] += p
        b[2] += y
    ece = sum(abs(b[1] - b[2]) for b in bins) / n
    print(f"{name} n={n} success={100 * right / n:.1f}% answered={100 * len(ans) / n:.1f}% "
          f"answered_of_right={100 * sum(ans) / max(right, 1):.1f}% precision={100 * sum(ans) / max(len(ans), 1):.2f}% "
          f"wrong={len(ans) - sum(ans)} declined_right={right - sum(ans)} ece={100 * ece:.2f}%")


def main():
    global RESULTS, DISTRACTOR, FACTORS
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--train", nargs="*", default=[])
    ap.add_argument("--test", nargs="*", default=[])
    ap.add_argument("--mode", default="gsf")
    ap.add_argument("--model", help="offset,slope per factor: replay this model instead of fitting")
    ap.add_argument("--min-confidence", type=float, default=0.9)
    ap.add_argument("--distractor-share", type=float, default=0.15)
    ap.add_argument("--l2", type=float, default=1e-3)
    ap.add_argument("--start", help="offset,slope per factor: start the fit here (default: the fit's own start)")
    ap.add_argument("--free", help="1 or 0 per number of --start: which the fit may move (default: all)")
    ap.add_argument("--results", default="results.json", help="per-world results file name in suite dirs")
    ap.add_argument("--distractor-dir", default="distractor", help="distractor directory name in suite dirs")
    ap.add_argument("--factors", default=",".join("+".join(f) for f in FACTORS),
                    help="the factors: comma separated, each one field or several joined by '+'")
    a = ap.parse_args()
    RESULTS, DISTRACTOR = a.results, a.distractor_dir
    FACTORS = [f.split("+") for f in a.factors.split(",")]
    for n in (n for f in FACTORS for n in f):
        if n not in FEATURES:
            raise SystemExit(f"fit_confidence.py: unknown field '{n}' (one of {', '.join(FEATURES)})")
    train = {d: records(d, a.mode) for d in expand(a.train)}
    test = {d: records(d, a.mode) for d in expand(a.test)}
    if a.model:
        m = parse_model(a.model)
    else:
        pooled = [r for rs in train.values() for r in rs]
        if not pooled:
            raise SystemExit("fit_confidence.py: no training records")
        n_d = sum(1 for r in pooled if r[2])
        n_m = len(pooled) - n_d
        w_d = a.distractor_share / (1.0 - a.distractor_share) * n_m / n_d if n_d else 0.0
        data = [(z, y, w_d if d else 1.0) for z, y, d, _ in pooled]
        start = [float(v) for v in a.start.split(",")] if a.start else None
        free = [v.strip() == "1" for v in a.free.split(",")] if a.free else None
        if free is not None and (start is None or len(free) != len(start)):
            raise SystemExit("fit_confidence.py: --free needs --start with as many numbers")
        m, loss = fit(data, a.l2, start=start, free=free)
        print(f"fitted on {n_m} in-map and {n_d} distractor queries (weight {w_d:.3f} each), loss {loss:.1f}")
        print("factors:", ", ".join("+".join(f) for f in FACTORS))
        print("const ConfidenceModel kConfidenceModel = {" + ", ".join(f"{v:.3f}f" for v in m) + "};")
    for label, runs in (("train", train), ("test", test)):
        for d, rs in runs.items():
            report(f"{label} {d}", rs, m, a.min_confidence)
        pooled = [r for rs in runs.values() for r in rs]
        report(f"{label} all in-map", [r for r in pooled if not r[2]], m, a.min_confidence)
        report(f"{label} all distractor", [r for r in pooled if r[2]], m, a.min_confidence)


if __name__ == "__main__":
    main()
