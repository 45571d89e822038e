#!/usr/bin/env bash
# Position prior A/B: two gsf binaries localize the same simulated worlds' queries with a prior drawn
# around each truth (docs/vehicle-modes.md, "The global check without its pattern search"). For each
# seed: a suite world (--zone auto, as bench/track_ab.sh makes it, which it reuses), its map, one-shot
# with NEW, then each binary with a 20 m prior (sigma 5 m) and with the prior BIASES metres off.
# LABELS gives the queries' labels simulated network errors (e.g. LABELS="--label-noise 0.15";
# both binaries alike; the runs are kept under a tag of it). Prints bench/prior_summary.py's pooled
# line per run (queries | success | answered right | confident wrong | with a pose | checked |
# contradicted | pooled median ms), then per world answered right: one-shot, base, new. HEADING=T gives
# the priors a heading T deg wide (`evaluate --prior-heading-tolerance T`, a GNSS course). The binaries
# run one after the other, so the medians compare on an idle machine; a time target is the ratio of
# the prior's pooled median to one-shot's.
#
# Usage: bench/prior_ab.sh BASE_GSF NEW_GSF OUT [SEEDS] [BIASES]
#   SEEDS default "6 7 8 9 10 11 12 13 14", BIASES default "100".
set -euo pipefail
. "$(dirname "$0")/vehicle_world.sh"
[ $# -ge 3 ] || { awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 2; }
base=$(realpath "$1"); new=$(realpath "$2"); out=$3
seeds=${4:-"6 7 8 9 10 11 12 13 14"}
biases=${5:-"100"}
read -r -a labels <<<"${LABELS:-}"
tag=$(echo "${LABELS:-default}" | tr -c 'a-zA-Z0-9.\n' '_' | sed 's/^_*//')
here=$(dirname "$0")
mkdir -p "$out"
prior=(--mode gsf --prior-sigma 5 --prior-radius 20 --quiet)
if [ -n "${HEADING:-}" ]; then
  prior+=(--prior-heading-tolerance "$HEADING")
  tag=$tag-heading$HEADING
fi
for s in $seeds; do
  d=$out/w$s
  vehicle_world "$new" "$out" "$s"
  r=(--map "$d/m.map" --dataset "$d" "${labels[@]}")
  "$new" evaluate "${r[@]}" --mode gsf --quiet --json "$out/$tag-oneshot-$s.json" >/dev/null
  for b in base new; do
    bin=$base
    [ $b = new ] && bin=$new
    "$bin" evaluate "${r[@]}" "${prior[@]}" --json "$out/$tag-$b-p20-$s.json" >/dev/null
    for off in $biases; do
      "$bin" evaluate "${r[@]}" "${prior[@]}" --prior-bias "$off" --json "$out/$tag-$b-off$off-$s.json" >/dev/null
    done
  done
done
line() { python3 "$here/prior_summary.py" "$@" | tail -1 | sed 's/^all | //'; }
pooled() {  # the pooled line of one run over every seed's world
  local runs=()
  for s in $seeds; do runs+=("$out/$tag-$1-$s.json"); done
  line "${runs[@]}"
}
echo "labels: ${LABELS:-default}; prior heading: ${HEADING:-none}; seeds: $seeds"
echo "one-shot: $(pooled oneshot)"
for b in base new; do
  echo "$b, 20 m prior: $(pooled "$b-p20")"
  for off in $biases; do echo "$b, prior $off m off: $(pooled "$b-off$off")"; done
done
echo "answered right per world: one-shot / base / new (20 m prior)"
for s in $seeds; do
  row=""
  for f in oneshot base-p20 new-p20; do row="$row $(line "$out/$tag-$f-$s.json" | cut -d'|' -f3)"; done
  echo "w$s:$row"
done
