#!/usr/bin/env bash
# Real-data runs behind docs/results.md:
#  - SemanticKITTI revisits: a map from other frames of the sequence, the revisiting scan as the query
#    (seq 00: frames 52, 88, 850 -> 4501; seq 08: 720 -> 1500, opposite direction);
#  - nuScenes-lidarseg: map from scene 0004, queries = scene 0002 (same street, opposite direction).
# Usage: bench/real_data.sh [DATA_DIR (default ../shared/data)] [OUT_DIR (default out/real)]
set -euo pipefail
cd "$(dirname "$0")/.."
data=$(cd "${1:-../shared/data}" && pwd)
out=${2:-out/real}
cmake --preset release >/dev/null && cmake --build --preset release >/dev/null
gsf=$PWD/build/release/tools/gsf
rm -rf "$out" && mkdir -p "$out"
S=$data/semantickitti-samples/sequences
link() {  # link DEST_ROOT SEQ FRAME...
  local root=$1 seq=$2; shift 2
  mkdir -p "$root/sequences/$seq/velodyne" "$root/sequences/$seq/labels"
  cp "$S/$seq/poses.txt" "$S/$seq/calib.txt" "$root/sequences/$seq/"
  for f in "$@"; do
    ln -s "$S/$seq/velodyne/$f.bin" "$root/sequences/$seq/velodyne/"
    ln -s "$S/$seq/labels/$f.label" "$root/sequences/$seq/labels/"
  done
}
link "$out/kitti-map" 00 000052 000088 000850
link "$out/kitti-query" 00 004501
link "$out/kitti-map" 08 000720
link "$out/kitti-query" 08 001500
for seq in 00 08; do
  $gsf build-map --dataset "$out/kitti-map" --sequence $seq --out "$out/kitti-$seq.gsfmap" --quiet
  $gsf evaluate --map "$out/kitti-$seq.gsfmap" --dataset "$out/kitti-query" --sequence $seq --map-sequence $seq \
    --mode instance,gsf,gsf+refine --quiet --json "$out/kitti-$seq.json" >/dev/null
  python3 - "$out/kitti-$seq.json" "$seq" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
for mode, v in r["modes"].items():
    q = v["queries"][0]
    print(f"SemanticKITTI seq {sys.argv[2]} [{mode}]: {q['status']}, {q['translation_error_m']:.2f} m, "
          f"{q['rotation_error_deg']:.2f} deg, {q['inliers']} inliers, ambiguity {q['ambiguity']:.2f}")
PY
done
N=$data/nuscenes-lidarseg-samples
$gsf build-map --dataset "$N" --sequence 0004 --out "$out/nuscenes-0004.gsfmap" --quiet
$gsf inspect --map "$out/nuscenes-0004.gsfmap" | sed -n '1,6p'
$gsf evaluate --map "$out/nuscenes-0004.gsfmap" --dataset "$N" --sequence 0002 --map-sequence 0004 --quiet \
  --json "$out/nuscenes.json" | sed -n '/^mode/,/^scan-context/p'
