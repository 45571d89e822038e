#!/usr/bin/env bash
# Queries against the map of ANOTHER world: every answer there is wrong, so the only right outcome is to
# decline. A vehicle outside its map (or given the wrong map) is in this situation, and a confidence
# calibrated only on queries whose truth is in the map would vouch for the best wrong place. Reads
# suite directories run with --keep (bench/suite.sh, bench/families.sh): for each zone type, the map of
# each seed is queried with the next seed's query drive (cyclic), into DIR/distractor/<zone>-m<a>-q<b>.json.
# bench/calibration.py and bench/fit_confidence.py read these files beside the suite's own.
#
# Usage: bench/distractors.sh [--gsf BIN] [--jobs N] [--modes LIST] DIR [DIR ...]
#   DIR: a suite output directory (DIR/<zone>-s<seed>/{map.gsfmap,dataset}); a families directory
#        (DIR/<family>/...) works too: every family in it is done.
set -euo pipefail
cd "$(dirname "$0")/.."
gsf=""
jobs=2
modes=gsf
dirs=()
while [ $# -gt 0 ]; do
  case "$1" in
    --gsf) gsf=$2; shift 2 ;;
    --jobs) jobs=$2; shift 2 ;;
    --modes) modes=$2; shift 2 ;;
    -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0 ;;
    -*) echo "distractors.sh: unknown option '$1' (see --help)" >&2; exit 2 ;;
    *) dirs+=("$1"); shift ;;
  esac
done
[ ${#dirs[@]} -gt 0 ] || { echo "distractors.sh: no directory given (see --help)" >&2; exit 2; }
if [ -z "$gsf" ]; then
  cmake --preset release >/dev/null && cmake --build --preset release -j 2 --target gsf_cli >/dev/null
  gsf=$PWD/build/release/tools/gsf
fi

# Suite directories: those holding <zone>-s<seed>/map.gsfmap.
suites=()
for d in "${dirs[@]}"; do
  if compgen -G "$d/*-s*/map.gsfmap" >/dev/null; then suites+=("$d"); fi
  for f in "$d"/*/; do compgen -G "$f*-s*/map.gsfmap" >/dev/null && suites+=("${f%/}"); done
done
[ ${#suites[@]} -gt 0 ] || { echo "distractors.sh: no suite directory with maps under ${dirs[*]}" >&2; exit 2; }

pairs=()  # "suite zone map_seed query_seed"
for s in "${suites[@]}"; do
  for zone in $(ls -d "$s"/*-s*/ | xargs -n1 basename | sed 's/-s[0-9]*$//' | sort -u); do
    seeds=($(ls -d "$s/$zone"-s*/ | xargs -n1 basename | sed "s/^$zone-s//" | sort -n))
    [ ${#seeds[@]} -ge 2 ] || continue
    for i in "${!seeds[@]}"; do
      a=${seeds[$i]} b=${seeds[$(((i + 1) % ${#seeds[@]}))]}
      [ -d "$s/$zone-s$b/dataset" ] || { echo "distractors.sh: $s/$zone-s$b has no dataset (run the suite with --keep)" >&2; exit 2; }
      pairs+=("$s $zone $a $b")
    done
  done
done
echo "distractors: ${#pairs[@]} map/query pairs over ${#suites[@]} suite directories, $jobs in parallel" >&2
run_pair() {
  local s=$1 zone=$2 a=$3 b=$4
  mkdir -p "$s/distractor"
  "$gsf" evaluate --map "$s/$zone-s$a/map.gsfmap" --dataset "$s/$zone-s$b/dataset" --mode "$modes" \
    --json "$s/distractor/$zone-m$a-q$b.json" --quiet >/dev/null 2>"$s/distractor/$zone-m$a-q$b.log" ||
    { echo "distractors: $s $zone map $a queries $b FAILED" >&2; return 1; }
}
export -f run_pair
export gsf modes
printf '%s\n' "${pairs[@]}" | xargs -P "$jobs" -n 4 bash -c 'run_pair "$0" "$1" "$2" "$3"'
for s in "${suites[@]}"; do python3 bench/calibration.py "$s/distractor" --mode "${modes%%,*}" --brief || true; done
