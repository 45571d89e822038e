#!/usr/bin/env bash
# Several scans against one-shot on the 10 Hz stretches (issue 27, item 3; docs/vehicle-modes.md,
# "Measured: one-shot vs N = 3 on the stretches"): per seed and zone type a suite world with six
# stretches of 20 scans (sequence 02), its map, then `gsf evaluate --sequence-window N` for N = 1
# (one-shot) and 3 (--window N: another), and the library's loop (`--mode drive`: tracking while
# confident, the window of N = 3 at a start or a loss), with the default labels and with --label-noise
# 0.15. Prints one table row per world and a total (from the evaluations' JSON summaries): success /
# answered / confident wrong of all scans, and answered of the scans in the repetitive zone. Two
# worlds at a time. --simulate adds options to gsf simulate, e.g. "--map-coverage 0.6" for stretches
# that drive off the mapped part of the road (the edge family's worlds, bench/families.sh).
#
#   bash bench/window_zones.sh OUT [--seeds "11 12 13 14"] [--zones "row lattice hall avenue"] [--window N]
#                                  [--gsf BIN] [--simulate "OPTIONS"]
set -euo pipefail
here=$(pwd)
cd "$(dirname "$0")/.."
out=${1:?usage: bench/window_zones.sh OUT [--seeds S] [--zones Z] [--window N] [--gsf BIN] [--simulate OPTIONS]}
shift
case "$out" in /*) ;; *) out=$here/$out ;; esac
seeds="11 12 13 14"
zones="row lattice hall avenue"
gsf=""
window=3
simulate=""
while [ $# -gt 0 ]; do
  case "$1" in
    --seeds) seeds=$2; shift 2 ;;
    --zones) zones=$2; shift 2 ;;
    --gsf) gsf=$2; shift 2 ;;
    --window) window=$2; shift 2 ;;
    --simulate) simulate=$2; shift 2 ;;
    *) echo "window_zones.sh: unknown option $1" >&2; exit 2 ;;
  esac
done
if [ -z "$gsf" ]; then
  cmake --preset release >/dev/null && cmake --build --preset release >/dev/null
  gsf=build/release/tools/gsf
fi
gsf=$(readlink -f "$gsf")
mkdir -p "$out"

one_world() {  # seed zone
  local d=$out/$1-$2
  mkdir -p "$d"
  "$gsf" simulate --out "$d/ds" --preset suite --seed "$1" --zone "$2" --stretches 6 --quiet $simulate
  "$gsf" build-map --dataset "$d/ds" --out "$d/m.map" --quiet >/dev/null
  for n in 1 "$window"; do
    for noise in 0 0.15; do
      "$gsf" evaluate --map "$d/m.map" --dataset "$d/ds" --sequence-window "$n" --label-noise "$noise" \
        --json "$d/w$n-$noise.json" --quiet >/dev/null
    done
  done
  for noise in 0 0.15; do
    "$gsf" evaluate --map "$d/m.map" --dataset "$d/ds" --mode drive --label-noise "$noise" \
      --json "$d/drive-$noise.json" --quiet >/dev/null
  done
  rm -rf "$d/ds" "$d/m.map"
}

running=0
for s in $seeds; do
  for z in $zones; do
    one_world "$s" "$z" &
    running=$((running + 1))
    if [ "$running" -ge 2 ]; then wait -n; running=$((running - 1)); fi
  done
done
wait

python3 - "$out" "$seeds" "$zones" "$window" <<'EOF'
import json
import sys
out, seeds, zones, window = sys.argv[1], sys.argv[2].split(), sys.argv[3].split(), sys.argv[4]
runs = [("1", "0"), (window, "0"), ("drive", "0"), ("1", "0.15"), (window, "0.15"), ("drive", "0.15")]
total = {r: [0, 0, 0, 0, 0, 0] for r in runs}  # scans, success, answered, wrong, zone scans, zone answered

print(f"| seed, zone | one-shot | N = {window} | loop | label noise 0.15: one-shot | N = {window} | loop |")
print("| --- | --- | --- | --- | --- | --- | --- |")
for s in seeds:
    for z in zones:
        cells = []
        for n, noise in runs:
            if n == "drive":  # --mode drive's summary (run_tracking.cpp)
                d = json.load(open(f"{out}/{s}-{z}/drive-{noise}.json"))["summary"]
                a = {"scans": d["scans"], "success": d["success"],
                     "answered": d["answered"], "confident_wrong": d["confident_wrong"]}
                zone = {"scans": d["zone_scans"], "answered": d["zone_answered"]}
            else:
                summary = json.load(open(f"{out}/{s}-{z}/w{n}-{noise}.json"))["summary"]
                a, zone = summary["all"], summary["zone"]
            t = total[(n, noise)]
            for i, v in enumerate((a["scans"], a["success"], a["answered"], a["confident_wrong"],
                                   zone["scans"], zone["answered"])):
                t[i] += v
            cell = f"{a['success']} / {a['answered']} / {a['confident_wrong']}"
            if zone["scans"] > 0:
                cell += f" ({zone['answered']} of {zone['scans']})"
            cells.append(cell)
        print(f"| {s} {z} | " + " | ".join(cells) + " |")
cells = []
for r in runs:
    t = total[r]
    share = f", {100.0 * t[5] / t[4]:.1f}%" if t[4] else ""
    cells.append(f"{t[1]} / {t[2]} / {t[3]} ({t[5]} of {t[4]}{share})")
print("| **all** | " + " | ".join(cells) + " |")
EOF
