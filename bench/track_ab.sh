#!/usr/bin/env bash
# Tracking A/B: two gsf binaries track the same simulated drives (docs/vehicle-modes.md, "Tracking,
# 2026-12-04"). For each seed: a suite world (--zone auto, six 10 Hz stretches of 20 scans), its map,
# then `evaluate --mode track` with each binary at each odometry noise, side by side. Prints one line
# per binary and noise: tracked / within 0.3 m, 1 deg / answered / confident wrong / losses, recovered,
# and the median time of a tracked scan (a timing, so run both on an idle machine; the two binaries run
# together, so they share the load). CALLGRIND=SEED also counts track()'s instructions per call on that
# seed's world (valgrind; load-independent). LABEL_NOISE=P gives the queries' labels simulated network
# errors (`evaluate --label-noise P`, both binaries alike; default 0).
#
# Usage: bench/track_ab.sh BASE_GSF NEW_GSF OUT [SEEDS] [NOISES]
#   SEEDS default "6 7 8 9 10 11 12 13 14", NOISES default "0.02 0.3 1.0".
set -euo pipefail
. "$(dirname "$0")/vehicle_world.sh"
[ $# -ge 3 ] || { awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 2; }
base=$(realpath "$1"); new=$(realpath "$2"); out=$3
seeds=${4:-"6 7 8 9 10 11 12 13 14"}
noises=${5:-"0.02 0.3 1.0"}
labels=(--label-noise "${LABEL_NOISE:-0}")
tag=${LABEL_NOISE:+l$LABEL_NOISE-}  # the runs with label errors are kept beside those without
mkdir -p "$out"
for s in $seeds; do
  d=$out/w$s
  vehicle_world "$new" "$out" "$s"
  for n in $noises; do
    "$base" evaluate --map "$d/m.map" --dataset "$d" --mode track --odometry-noise "$n" "${labels[@]}" \
      --json "$out/${tag}base-$n-$s.json" --quiet >/dev/null &
    "$new" evaluate --map "$d/m.map" --dataset "$d" --mode track --odometry-noise "$n" "${labels[@]}" \
      --json "$out/${tag}new-$n-$s.json" --quiet >/dev/null
    wait
  done
done
python3 - "$out" "$seeds" "$noises" "$tag" <<'PY'
import json, statistics, sys
out, seeds, noises, tag = sys.argv[1], sys.argv[2].split(), sys.argv[3].split(), sys.argv[4]
keys = ["tracked", "tracked_precise", "answered", "confident_wrong", "losses", "recoveries"]
for n in noises:
    for b in ["base", "new"]:
        tot = dict.fromkeys(keys, 0)
        ms = []
        for s in seeds:
            d = json.load(open(f"{out}/{tag}{b}-{n}-{s}.json"))
            for k in keys:
                tot[k] += d["summary"][k]
            ms += [x["time_ms"] for x in d["scans"] if x["how"] == "track"]
        print(f"noise {n} {b}: {tot['tracked']} / {tot['tracked_precise']} / {tot['answered']} / "
              f"{tot['confident_wrong']} / {tot['losses']}, {tot['recoveries']}; "
              f"tracked scan median {statistics.median(ms):.2f} ms")
PY
if [ -n "${CALLGRIND:-}" ]; then
  d=$out/w$CALLGRIND
  for b in base new; do
    bin=$base; [ $b = new ] && bin=$new
    for n in $noises; do
      valgrind --tool=callgrind --callgrind-out-file="$out/cg-$b-$n.out" --toggle-collect='gsf::Localizer::track(*' \
        "$bin" evaluate --map "$d/m.map" --dataset "$d" --mode track --odometry-noise "$n" --json "$out/cg-$b-$n.json" \
        --quiet >/dev/null 2>&1
      calls=$(python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print(sum(x['how'] != 'one-shot' for x in d['scans']))" "$out/cg-$b-$n.json")
      awk -v c="$calls" -v what="callgrind seed $CALLGRIND noise $n $b" \
        '/^totals:/ { printf "%s: %.1f M instructions per track() call (%d calls)\n", what, $2 / c / 1e6, c }' \
        "$out/cg-$b-$n.out"
    done
  done
fi
