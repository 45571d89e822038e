#!/usr/bin/env bash
# The position prior's time against one-shot's (issue 27: median <= 0.6x one-shot), measured so the
# machine's load cancels: each query is localized with the 20 m prior and then without it, back to
# back (`gsf evaluate --one-shot-too`), each REPEAT times in a row keeping the fastest run (`--repeat`).
# The worlds are bench/prior_ab.sh's (a suite world per seed, --zone auto, made here when OUT lacks
# them, so OUT can be prior_ab.sh's own directory). Prints per world and pooled over the seeds (the
# median of all their queries' times): queries, answered right, confident wrong and the median for
# the prior and for one-shot, and the ratio of the medians. LABELS gives the queries' labels simulated
# network errors (e.g. LABELS="--label-noise 0.15"), as in bench/prior_ab.sh.
#
# Usage: bench/prior_time.sh GSF OUT [SEEDS] [REPEAT]
#   SEEDS default "15 16 17 18 19 20 21 22 23", REPEAT default 3.
set -euo pipefail
[ $# -ge 2 ] || { awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 2; }
gsf=$(realpath "$1"); out=$2
seeds=${3:-"15 16 17 18 19 20 21 22 23"}
repeat=${4:-3}
read -r -a labels <<<"${LABELS:-}"
tag=$(echo "${LABELS:-default}" | tr -c 'a-zA-Z0-9.\n' '_' | sed 's/^_*//')
mkdir -p "$out"
runs=()
for s in $seeds; do
  d=$out/w$s
  if [ ! -f "$d/m.map" ]; then
    "$gsf" simulate --out "$d" --preset suite --seed "$s" --zone auto --stretches 6 --quiet >"$out/sim$s.log"
    "$gsf" build-map --dataset "$d" --out "$d/m.map" --quiet >>"$out/sim$s.log"
  fi
  "$gsf" evaluate --map "$d/m.map" --dataset "$d" "${labels[@]}" --mode gsf --prior-sigma 5 --prior-radius 20 \
    --one-shot-too --repeat "$repeat" --quiet --json "$out/time-$tag-$s.json" >/dev/null
  runs+=("$out/time-$tag-$s.json")
done
python3 - "$repeat" "${LABELS:-default}" "${runs[@]}" <<'EOF'
import json, statistics, sys
repeat, labels, paths = sys.argv[1], sys.argv[2], sys.argv[3:]
def stats(queries):
    t = [q["time_ms"] for q in queries]
    return (len(t), sum(q["success"] and q["answered"] for q in queries),
            sum(q["answered"] and not q["success"] for q in queries), statistics.median(t) if t else float("nan"))
pooled = {"gsf": [], "gsf-one-shot": []}
print(f"fastest of {repeat} runs a query; prior: 20 m radius, sigma 5 m; labels: {labels}")
print("| world | queries | prior: right / wrong | one-shot: right / wrong | prior median ms | one-shot median ms | ratio |")
print("| --- | ---: | --- | --- | ---: | ---: | ---: |")
for p in paths:
    modes = json.load(open(p))["modes"]
    a, b = stats(modes["gsf"]["queries"]), stats(modes["gsf-one-shot"]["queries"])
    for m in pooled: pooled[m] += modes[m]["queries"]
    print(f"| {p} | {a[0]} | {a[1]} / {a[2]} | {b[1]} / {b[2]} | {a[3]:.2f} | {b[3]:.2f} | {a[3] / b[3]:.3f} |")
a, b = stats(pooled["gsf"]), stats(pooled["gsf-one-shot"])
print(f"| pooled | {a[0]} | {a[1]} / {a[2]} | {b[1]} / {b[2]} | {a[3]:.2f} | {b[3]:.2f} | **{a[3] / b[3]:.3f}** |")
EOF
