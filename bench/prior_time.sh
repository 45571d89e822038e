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
. "$(dirname "$0")/vehicle_world.sh"
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
  vehicle_world "$gsf" "$out" "$s"
  "$gsf" evaluate --map "$d/m.map" --dataset "$d" "${labels[@]}" --mode gsf --prior-sigma 5 --prior-radius 20 \
    --one-shot-too --repeat "$repeat" --quiet --json "$out/time-$tag-$s.json" >/dev/null
  runs+=("$out/time-$tag-$s.json")
done
python3 - "$(dirname "$0")" "$repeat" "${LABELS:-default}" "${runs[@]}" <<'EOF'
import statistics, sys
sys.path.insert(0, sys.argv[1])
import prior_summary  # its per-run counts: queries, answered right, confident wrong, times
repeat, labels, paths = sys.argv[2], sys.argv[3], sys.argv[4:]
modes = ("gsf", "gsf-one-shot")
totals = {m: {"n": 0, "right": 0, "wrong": 0, "times": []} for m in modes}
print(f"fastest of {repeat} runs a query; prior: 20 m radius, sigma 5 m; labels: {labels}")
print("| world | queries | prior: right / wrong | one-shot: right / wrong | prior median ms | one-shot median ms | ratio |")
print("| --- | ---: | --- | --- | ---: | ---: | ---: |")
for p in paths:
    a, b = prior_summary.summary(p, "gsf"), prior_summary.summary(p, "gsf-one-shot")
    for m, s in zip(modes, (a, b)):
        for k in totals[m]: totals[m][k] += s[k]
    print(f"| {p} | {a['n']} | {a['right']} / {a['wrong']} | {b['right']} / {b['wrong']} | {a['median']:.2f} |"
          f" {b['median']:.2f} | {a['median'] / b['median']:.3f} |")
a, b = totals["gsf"], totals["gsf-one-shot"]
ma, mb = statistics.median(a["times"]), statistics.median(b["times"])
print(f"| pooled | {a['n']} | {a['right']} / {a['wrong']} | {b['right']} / {b['wrong']} | {ma:.2f} | {mb:.2f} |"
      f" **{ma / mb:.3f}** |")
EOF
