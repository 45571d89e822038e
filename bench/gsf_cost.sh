#!/usr/bin/env bash
# Does the GSF filter pay for itself on every segmentation family (issue 25, item 2)? Per family one
# kept world of a bench/families.sh run (the zone type rotating over the families), timed by
# bench_stages: the modes interleaved per scan, each cell the median over scans of the fastest of
# --repeat runs. Prints per family GSF off and GSF on medians of the whole query, their ratio (the
# target: <= 1) and the median of the per-scan ratios, then the ratio's spread over the families; and
# the tail of each mode, p95 over the median of the whole query (issue 25, item 4; target <= 1.5).
#
#   bash bench/gsf_cost.sh FAMILIES_DIR [--seed 6] [--limit N] [--repeat 3] [--bench BIN] [--families "p0 p3 ..."]
#                          [--set name=value,...]
# FAMILIES_DIR comes from `bash bench/families.sh --seeds 6 --keep --out FAMILIES_DIR` (its datasets
# kept). --bench points at another bench_stages (default build/release/bench/bench_stages), to run an
# older build on the same worlds; --set passes config overrides to both modes.
set -euo pipefail
cd "$(dirname "$0")/.."
[ $# -ge 1 ] || { sed -n 2,13p "$0"; exit 2; }
dir=$1; shift
seed=6; limit=0; repeat=3; bench=build/release/bench/bench_stages; overrides=""
families="p0 p3 p8 p15 o10 o20 thin b16 b64 b128 cross cheap edge"
while [ $# -gt 0 ]; do
  case "$1" in
    --seed) seed=$2; shift 2 ;;
    --limit) limit=$2; shift 2 ;;
    --repeat) repeat=$2; shift 2 ;;
    --bench) bench=$2; shift 2 ;;
    --families) families=$2; shift 2 ;;
    --set) overrides=$2; shift 2 ;;
    *) echo "gsf_cost.sh: unknown option '$1'" >&2; exit 2 ;;
  esac
done
zones=(row lattice hall avenue)
echo "| family | world | scans | GSF off median ms | GSF on median ms | ratio of medians | median per-scan ratio | p95 / median off | p95 / median on |"
echo "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
ratios=()
tails=()
i=0
for f in $families; do
  world=${zones[$((i % 4))]}-s$seed
  i=$((i + 1))
  w=$dir/$f/$world
  if [ ! -f "$w/map.gsfmap" ] || [ ! -d "$w/dataset" ]; then
    echo "| $f | $world | missing (run families.sh with --keep) | | | | | | |"
    continue
  fi
  args=(--map "$w/map.gsfmap" --dataset "$w/dataset" --repeat "$repeat")
  [ "$limit" -gt 0 ] && args+=(--limit "$limit")
  [ -n "$overrides" ] && args+=(--set "$overrides")
  log=$("$bench" "${args[@]}" 2>/dev/null)
  scans=$(sed -n 's/^scans: \([0-9]*\).*/\1/p' <<<"$log")
  total=$(grep '^| total query' <<<"$log" | tr -d ' ')  # |totalquery|OFF|x|ON|x|REF|x|
  off=$(cut -d'|' -f3 <<<"$total"); on=$(cut -d'|' -f5 <<<"$total")
  line=$(grep '^GSF on / GSF off' <<<"$log")
  r=$(sed -n 's/.*ratio of medians \([0-9.]*\).*/\1/p' <<<"$line")
  p=$(sed -n 's/.*per-scan ratios \([0-9.]*\).*/\1/p' <<<"$line")
  tail=$(grep '^tail (total query)' <<<"$log")  # ... instance p95 X us (Y.YYx median) ...; gsf p95 ...
  toff=$(sed -n 's/.* instance p95 [0-9]* us (\([0-9.]*\)x median).*/\1/p' <<<"$tail")
  ton=$(sed -n 's/.*; gsf p95 [0-9]* us (\([0-9.]*\)x median).*/\1/p' <<<"$tail")
  ratios+=("$r")
  tails+=("$ton")
  awk -v f="$f" -v w="$world" -v n="$scans" -v off="$off" -v on="$on" -v r="$r" -v p="$p" -v toff="$toff" -v ton="$ton" \
    'BEGIN {printf "| %s | %s | %s | %.2f | %.2f | %s | %s | %s | %s |\n", f, w, n, off / 1000, on / 1000, r, p, toff, ton}'
done
if [ ${#ratios[@]} -gt 0 ]; then
  printf '%s\n' "${ratios[@]}" | sort -n | awk '{v[NR]=$1} END {printf "ratio of medians over %d families: min %s, median %s, max %s; at most 1 on %d\n", NR, v[1], v[int((NR+1)/2)], v[NR], c+0} $1 <= 1 {c++}'
fi
if [ ${#tails[@]} -gt 0 ]; then
  printf '%s\n' "${tails[@]}" | sort -n | awk '{v[NR]=$1} END {printf "GSF on p95 / median over %d families: min %s, median %s, max %s; at most 1.5 on %d\n", NR, v[1], v[int((NR+1)/2)], v[NR], c+0} $1 <= 1.5 {c++}'
fi
