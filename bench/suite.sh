#!/usr/bin/env bash
# The localization suite: every zone type (row, lattice, hall, avenue) x several seeds, so no setting is
# chosen on one world. Per world: gsf simulate --preset suite (2 x 2-block city + the zone, label noise,
# no instance ids) -> gsf build-map -> gsf evaluate --mode instance,gsf --json; worlds run in parallel;
# then bench/suite_summary.py prints per mode the mean and worst over seeds per zone type and overall,
# and writes OUT/summary.json.
#
# Usage: bench/suite.sh [options]
#   --seeds "1 2 3 4 5"       seeds (space or comma separated; env SUITE_SEEDS)
#   --zones "row lattice hall avenue"   zone types (env SUITE_ZONES)
#   --out DIR                 output directory (env SUITE_OUT; default out/suite)
#   --set name=value,...      localizer config overrides for build-map and evaluate (env SUITE_SET)
#   --build-args "ARGS"       extra build-map options, e.g. "--triangle-min-detections 0" (env SUITE_BUILD_ARGS)
#   --jobs N                  worlds in parallel (env SUITE_JOBS; default 2)
#   --preset NAME             simulate preset (default suite; tiny-lattice for a smoke run)
#   --label-noise P           (default 0.03)    --instance-ids   keep instance ids (default: zeroed)
#   --object-confusion P      --thin-miss P     --spurious-objects P    segmentation-error families (gsf simulate; default: not
#   --beams N                 --map-beams N     --map-coverage F   passed, so an older --sim-gsf works): whole objects
#                             relabelled, thin things missed with range, query / mapping LiDAR beams
#   --label-set NAME          labels the worlds are written with: semantic-kitti (default) or nuscenes
#                             (no pole, trunk, sign or fence class; build-map/evaluate pick the table)
#   --modes LIST              evaluate modes (default instance,gsf)
#   --gsf PATH                gsf binary (default: build the release preset, use build/release/tools/gsf)
#   --sim-gsf PATH            gsf binary for `simulate` only (default: --gsf), e.g. to run another
#                             localizer build on exactly this branch's worlds
#   --keep                    keep the simulated datasets (default: deleted after evaluation, ~100 MB each)
# Per world OUT/<zone>-s<seed>/ holds meta.json, map.gsfmap, results.json, log.txt and seconds.txt.
set -euo pipefail
cd "$(dirname "$0")/.."
seeds=${SUITE_SEEDS:-"1 2 3 4 5"}
zones=${SUITE_ZONES:-"row lattice hall avenue"}
out=${SUITE_OUT:-out/suite}
set_overrides=${SUITE_SET:-}
build_args=${SUITE_BUILD_ARGS:-}
jobs=${SUITE_JOBS:-2}
preset=suite
label_noise=0.03
label_set=semantic-kitti
sim_extra=""  # the error-family options given, passed to simulate as they are
ids_flag=--no-instance-ids
modes=instance,gsf
gsf=""
sim_gsf=""
keep=0
while [ $# -gt 0 ]; do
  case "$1" in
    --seeds) seeds=$2; shift 2 ;;
    --zones) zones=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --set) set_overrides=$2; shift 2 ;;
    --build-args) build_args=$2; shift 2 ;;
    --jobs) jobs=$2; shift 2 ;;
    --preset) preset=$2; shift 2 ;;
    --label-noise) label_noise=$2; shift 2 ;;
    --label-set) label_set=$2; shift 2 ;;
    --object-confusion|--thin-miss|--spurious-objects|--beams|--map-beams|--map-coverage) sim_extra="$sim_extra $1 $2"; shift 2 ;;
    --instance-ids) ids_flag=""; shift ;;
    --modes) modes=$2; shift 2 ;;
    --gsf) gsf=$2; shift 2 ;;
    --sim-gsf) sim_gsf=$2; shift 2 ;;
    --keep) keep=1; shift ;;
    -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0 ;;
    *) echo "suite.sh: unknown option '$1' (see --help)" >&2; exit 2 ;;
  esac
done
seeds=${seeds//,/ }
zones=${zones//,/ }
if [ -z "$gsf" ]; then
  cmake --preset release >/dev/null && cmake --build --preset release -j 2 --target gsf_cli >/dev/null
  gsf=build/release/tools/gsf
fi
[ -x "$gsf" ] || { echo "suite.sh: no gsf binary at '$gsf'" >&2; exit 2; }
mkdir -p "$out"
gsf=$(cd "$(dirname "$gsf")" && pwd)/$(basename "$gsf")
sim_gsf=${sim_gsf:-$gsf}
[ -x "$sim_gsf" ] || { echo "suite.sh: no gsf binary at '$sim_gsf'" >&2; exit 2; }
sim_gsf=$(cd "$(dirname "$sim_gsf")" && pwd)/$(basename "$sim_gsf")

# One world: zone seed. Exit status non-zero (and log.txt kept) on any failure.
run_world() {
  local zone=$1 seed=$2 d="$out/$1-s$2"
  local set_args=()
  [ -n "$set_overrides" ] && set_args=(--set "$set_overrides")
  rm -rf "$d" && mkdir -p "$d"
  local t0=$SECONDS
  {
    "$sim_gsf" simulate --preset "$preset" --zone "$zone" --seed "$seed" --label-noise "$label_noise" $ids_flag $label_set_flag \
      $sim_extra --out "$d/dataset" --quiet &&
    "$gsf" build-map --dataset "$d/dataset" --out "$d/map.gsfmap" "${set_args[@]}" $build_args --quiet &&
    "$gsf" evaluate --map "$d/map.gsfmap" --dataset "$d/dataset" --mode "$modes" --json "$d/results.json" \
      "${set_args[@]}" --quiet
  } >"$d/log.txt" 2>&1 || { echo "suite: $zone seed $seed FAILED (see $d/log.txt)" >&2; return 1; }
  cp "$d/dataset/meta.json" "$d/meta.json"
  [ "$keep" = 1 ] || rm -rf "$d/dataset"
  echo $((SECONDS - t0)) >"$d/seconds.txt"
  echo "suite: $zone seed $seed done in $((SECONDS - t0)) s" >&2
}
export -f run_world
label_set_flag=""
[ "$label_set" != semantic-kitti ] && label_set_flag="--label-set $label_set"
export out gsf sim_gsf preset label_noise label_set_flag sim_extra ids_flag modes set_overrides build_args keep

start=$SECONDS
n=0
for z in $zones; do for s in $seeds; do n=$((n + 1)); done; done
echo "suite: $n worlds ($zones) x seeds ($seeds), preset $preset, label noise $label_noise${sim_extra:+,$sim_extra}, $label_set labels${ids_flag:+, no instance ids}${set_overrides:+, --set $set_overrides}${build_args:+, build-map $build_args}, $jobs in parallel -> $out" >&2
status=0
for z in $zones; do for s in $seeds; do printf '%s %s\n' "$z" "$s"; done; done |
  xargs -P "$jobs" -n 2 bash -c 'run_world "$0" "$1"' || status=1
elapsed=$((SECONDS - start))
echo "$elapsed" >"$out/seconds.txt"
python3 bench/suite_summary.py "$out" --seconds "$elapsed" --set "$set_overrides"
echo "suite: $n worlds in ${elapsed} s" >&2
exit $status
