#!/usr/bin/env bash
# Cost growth with map size: the same kind of queries against maps of 1x, 2x, 4x, 10x and 16x the demo
# world's road length (city blocks 4x3 = 3.5 km, 6x4 -> ~2x, 8x6 -> ~4x, 15x11 -> ~10x, 19x14 -> ~16x =
# 57 km; 10x is the scale of issue 11's query-time target). Per map:
# map bytes, bytes/km, instances, triangles, the builder's peak RSS (build-map's summary: getrusage
# ru_maxrss of the build-map process; the builder streams in tiles, build-map --tile-size) and CPU time
# (user + sys), and for the first N queries (same roads in every world) success, median and p95 time,
# candidates per query (triangle match candidates, median), the median match-stage time and the
# workspace of the instance-only and GSF rows.
# Usage: bench/scale.sh [OUT_DIR] [N_QUERIES]
# Environment: SCALES (default "1x 2x 4x"; any of 1x 2x 4x 10x 16x), GSF (a gsf binary to use instead of
# building build/release, e.g. a copy for a long background run), BUILD_MAP_ARGS (extra build-map options).
# A dataset already under OUT_DIR/<scale>/dataset is reused.
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-out/scale}
nq=${2:-60}
scales=${SCALES:-1x 2x 4x}
if [ -z "${GSF:-}" ]; then
  cmake --preset release >/dev/null && cmake --build --preset release >/dev/null
  gsf=build/release/tools/gsf
else
  gsf=$GSF
fi
mkdir -p "$out"
printf "| scale | blocks | road km | map MB | MB/km | build peak RSS MB | build CPU s | instances | triangles | mode | success | median ms | p95 ms | candidates/query | match ms | workspace MB |\n"
printf "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n"
for s in $scales; do
  case $s in
    1x) spec="1x 4 3" ;;
    2x) spec="2x 6 4" ;;
    4x) spec="4x 8 6" ;;
    10x) spec="10x 15 11" ;;
    16x) spec="16x 19 14" ;;
    *) echo "scale.sh: unknown scale $s" >&2; exit 2 ;;
  esac
  set -- $spec
  d="$out/$1"
  [ -f "$d/dataset/meta.json" ] || $gsf simulate --out "$d/dataset" --blocks-x "$2" --blocks-y "$3" --quiet >/dev/null
  # CPU seconds (user + sys), not wall time: the run may share the machine.
  # shellcheck disable=SC2086
  /usr/bin/time -f "%U %S" -o "$d/build-map.time" \
    $gsf build-map --dataset "$d/dataset" --out "$d/map.gsfmap" --quiet ${BUILD_MAP_ARGS:-} > "$d/build-map.txt"
  secs=$(awk '{print $1 + $2}' "$d/build-map.time")
  rss=$(sed -n 's/.*peak RSS \([0-9]*\) MB.*/\1/p' "$d/build-map.txt")
  $gsf evaluate --map "$d/map.gsfmap" --dataset "$d/dataset" --mode instance,gsf --limit "$nq" --quiet --json "$d/results.json" >/dev/null
  python3 - "$d/results.json" "$1" "$2x$3" "$rss" "$secs" <<'PY'
import json, statistics, sys
r = json.load(open(sys.argv[1]))
km = r["road_length_m"] / 1000
for mode, v in r["modes"].items():
    s = v["summary"]
    cand = statistics.median(q["diagnostics"]["match_candidates"] for q in v["queries"] if "diagnostics" in q)
    print(f"| {sys.argv[2]} | {sys.argv[3]} | {km:.1f} | {r['map_bytes']/1e6:.1f} | {r['map_bytes_per_km']/1e6:.2f} | "
          f"{sys.argv[4]} | {float(sys.argv[5]):.0f} | {r['map_instances']} | {r['map_triangles']} | {mode} | "
          f"{100*s['success_rate']:.1f}% | {s['median_ms']:.1f} | {s['p95_ms']:.1f} | {cand:.0f} | "
          f"{s['median_stage_ms']['match']:.1f} | {s['workspace_bytes']/1e6:.1f} |")
PY
done
