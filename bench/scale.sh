#!/usr/bin/env bash
# Cost growth with map size: the same kind of queries against maps of 1x, 2x and 4x the demo world's
# road length (city blocks 4x3, 6x4 -> ~2x, 8x6 -> ~4x). Per map: map bytes, bytes/km, instances,
# triangles, the builder's peak RSS (build-map's summary: getrusage ru_maxrss of the build-map process),
# and for the first N queries (same roads in every world) the per-query time, workspace and success of
# the instance-only and GSF rows.  Usage: bench/scale.sh [OUT_DIR] [N_QUERIES]
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-out/scale}
nq=${2:-60}
cmake --preset release >/dev/null && cmake --build --preset release >/dev/null
gsf=build/release/tools/gsf
mkdir -p "$out"
printf "| scale | blocks | road km | map MB | MB/km | build peak RSS MB | instances | triangles | mode | success | median ms | p95 ms | workspace MB |\n"
printf "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n"
for spec in "1x 4 3" "2x 6 4" "4x 8 6"; do
  set -- $spec
  d="$out/$1"
  $gsf simulate --out "$d/dataset" --blocks-x "$2" --blocks-y "$3" --quiet >/dev/null
  $gsf build-map --dataset "$d/dataset" --out "$d/map.gsfmap" --quiet > "$d/build-map.txt"
  rss=$(sed -n 's/.*peak RSS \([0-9]*\) MB.*/\1/p' "$d/build-map.txt")
  $gsf evaluate --map "$d/map.gsfmap" --dataset "$d/dataset" --mode instance,gsf --limit "$nq" --quiet --json "$d/results.json" >/dev/null
  python3 - "$d/results.json" "$1" "$2x$3" "$rss" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
km = r["road_length_m"] / 1000
for mode, v in r["modes"].items():
    s = v["summary"]
    print(f"| {sys.argv[2]} | {sys.argv[3]} | {km:.1f} | {r['map_bytes']/1e6:.1f} | {r['map_bytes_per_km']/1e6:.2f} | "
          f"{sys.argv[4]} | {r['map_instances']} | {r['map_triangles']} | {mode} | {100*s['success_rate']:.1f}% | {s['median_ms']:.1f} | "
          f"{s['p95_ms']:.1f} | {s['workspace_bytes']/1e6:.1f} |")
PY
done
