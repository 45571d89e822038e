#!/usr/bin/env bash
# Cost growth with map size: the same kind of queries against maps of 1x, 2x, 4x, 10x and 16x the demo
# world's road length (city blocks 4x3 = 3.5 km, 6x4 -> ~2x, 8x6 -> ~4x, 15x11 -> ~10x, 19x14 -> ~16x =
# 57 km; 10x is the scale of issue 11's query-time target). Per map:
# map bytes, bytes/km, instances, triangles, the builder's wall and CPU time (user + sys), peak RSS
# (/usr/bin/time's maximum resident set of the build-map process; the builder streams in tiles,
# build-map --tile-size) and its spill file (peak size and the peak of the live slots it held,
# tools/mapping/tile_store.h), and for the first N queries (same roads in every world) success, median
# and p95 time, candidates per query (triangle match candidates, median), the median match-stage time
# and the workspace of the instance-only and GSF rows. The rows also go to OUT_DIR/scale.tsv and a plot
# of build time, RSS, spill file and query times against map size to OUT_DIR/scale.svg
# (bench/scale_plot.py).
# Usage: bench/scale.sh [OUT_DIR] [N_QUERIES]
# Environment: SCALES (default "1x 2x 4x"; any of 1x 2x 4x 10x 16x), GSF (a gsf binary to use instead of
# building build/release, e.g. a copy for a long background run), BUILD_MAP_ARGS (extra build-map options).
# A dataset already under OUT_DIR/<scale>/dataset is reused (16x: 3.9 GB, 5,728 scans).
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
tsv="$out/scale.tsv"
printf "scale\troad_km\tscans\tmap_mb\tmb_per_km\tbuild_s\tbuild_cpu_s\trss_mb\tspill_peak_mb\tspill_live_mb\tresident_peak_mb\tmode\tmedian_ms\tp95_ms\n" > "$tsv"
printf "| scale | blocks | road km | scans | map MB | MB/km | build s | build CPU s | build peak RSS MB | spill file peak MB | spill live peak MB | resident peak MB | instances | triangles | mode | success | median ms | p95 ms | candidates/query | match ms | workspace MB |\n"
printf "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n"
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
  # Wall and CPU seconds (user + sys; the run may share the machine) and the maximum resident set (KB).
  # shellcheck disable=SC2086
  /usr/bin/time -f "%e %U %S %M" -o "$d/build-map.time" \
    $gsf build-map --dataset "$d/dataset" --out "$d/map.gsfmap" --quiet ${BUILD_MAP_ARGS:-} > "$d/build-map.txt"
  read -r wall user sys rss_kb < "$d/build-map.time"
  secs=$(awk -v u="$user" -v s="$sys" 'BEGIN {print u + s}')
  rss=$((rss_kb * 1024 / 1000000))  # KiB -> MB (10^6 bytes, as build-map prints)
  scans=$(sed -n 's/.*labels): \([0-9]*\) scans.*/\1/p' "$d/build-map.txt")
  spill=$(sed -n 's/.*spill file peak \([0-9]*\) MB (its live slots at most \([0-9]*\) MB.*/\1 \2/p' "$d/build-map.txt")
  grep -q "no spill file" "$d/build-map.txt" && spill="0 0"  # built block by block (--block-tiles)
  [ -n "$spill" ] || spill="- -"  # one tile, nothing spilled (or a gsf that does not report it)
  # The largest resident working set: the tiles' voxels in spill records (192 B each).
  resident=$(sed -n 's/.*voxels, \([0-9]*\) MB as spill records.*/\1/p' "$d/build-map.txt")
  [ -n "$resident" ] || resident="-"
  $gsf evaluate --map "$d/map.gsfmap" --dataset "$d/dataset" --mode instance,gsf --limit "$nq" --quiet --json "$d/results.json" >/dev/null
  # shellcheck disable=SC2086
  python3 - "$d/results.json" "$1" "$2x$3" "$rss" "$secs" "$wall" "$scans" $spill "$resident" "$tsv" <<'PY'
import json, statistics, sys
r = json.load(open(sys.argv[1]))
scale, blocks, rss, cpu, wall, scans, spill, live, resident, tsv = sys.argv[2:12]
km = r["road_length_m"] / 1000
for mode, v in r["modes"].items():
    s = v["summary"]
    cand = statistics.median(q["diagnostics"]["match_candidates"] for q in v["queries"] if "diagnostics" in q)
    print(f"| {scale} | {blocks} | {km:.1f} | {scans} | {r['map_bytes']/1e6:.1f} | {r['map_bytes_per_km']/1e6:.2f} | "
          f"{float(wall):.0f} | {float(cpu):.0f} | {rss} | {spill} | {live} | {resident} | {r['map_instances']} | "
          f"{r['map_triangles']} | {mode} | {100*s['success_rate']:.1f}% | {s['median_ms']:.1f} | {s['p95_ms']:.1f} | "
          f"{cand:.0f} | {s['median_stage_ms']['match']:.1f} | {s['workspace_bytes']/1e6:.1f} |")
    with open(tsv, "a") as f:
        f.write(f"{scale}\t{km:.2f}\t{scans}\t{r['map_bytes']/1e6:.2f}\t{r['map_bytes_per_km']/1e6:.3f}\t{wall}\t"
                f"{float(cpu):.1f}\t{rss}\t{spill}\t{live}\t{resident}\t{mode}\t{s['median_ms']:.2f}\t{s['p95_ms']:.2f}\n")
PY
done
python3 bench/scale_plot.py "$tsv" "$out/scale.svg"
