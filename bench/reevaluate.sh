#!/usr/bin/env bash
# Evaluates the kept worlds of a bench/families.sh run (--keep: each world's map.gsfmap and dataset)
# again with another gsf binary or other settings, into OUT/<family>/<world>/results.json, so two builds
# or settings are compared on the same maps and scans (bench/compare_families.py SRC OUT,
# bench/wrong_answers.py OUT, bench/declined_right.py OUT). Two worlds at a time.
#
# Usage: bench/reevaluate.sh [--gsf BIN] [--families "p0 p3 ..."] SRC OUT [gsf evaluate options ...]
#   e.g. bench/reevaluate.sh out/fam out/fam-refine8 --set verify.refine_top=8
# Without --gsf the release preset's gsf is built and used; every family in SRC without --families.
set -euo pipefail
here=$(pwd)
cd "$(dirname "$0")/.."
absolute() { case "$1" in /*) printf '%s' "$1" ;; *) printf '%s/%s' "$here" "$1" ;; esac; }
gsf=""
families=""
while [ $# -gt 0 ]; do
  case "$1" in
    --gsf) gsf=$(absolute "$2"); shift 2 ;;
    --families) families=${2//,/ }; shift 2 ;;
    -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0 ;;
    *) break ;;
  esac
done
[ $# -ge 2 ] || { echo "reevaluate.sh: SRC and OUT are required (see --help)" >&2; exit 2; }
src=$(absolute "$1") out=$(absolute "$2")
shift 2
if [ -z "$gsf" ]; then
  cmake --preset release >/dev/null && cmake --build --preset release -j 2 --target gsf_cli >/dev/null
  gsf=build/release/tools/gsf
fi
[ -n "$families" ] || families=$(cd "$src" && for d in */; do [ -d "$d" ] && printf '%s ' "${d%/}"; done)
worlds=()
for f in $families; do
  for w in "$src/$f"/*/; do
    [ -f "$w/map.gsfmap" ] && [ -d "$w/dataset" ] && worlds+=("$f/$(basename "$w")")
  done
done
[ ${#worlds[@]} -gt 0 ] || { echo "reevaluate.sh: no kept world (map.gsfmap + dataset) under $src" >&2; exit 2; }
export gsf src out
printf '%s\0' "${worlds[@]}" | xargs -0 -P 2 -n 1 bash -c '
  w=${!#}; set -- "${@:1:$#-1}"  # xargs appends the world after the evaluate options
  mkdir -p "$out/$w" &&
  "$gsf" evaluate --map "$src/$w/map.gsfmap" --dataset "$src/$w/dataset" --mode gsf --json "$out/$w/results.json" \
    --quiet "$@" >"$out/$w/log.txt" 2>&1 || { echo "reevaluate: $w FAILED (see $out/$w/log.txt)" >&2; exit 1; }' _ "$@"
echo "reevaluate: ${#worlds[@]} worlds -> $out" >&2
