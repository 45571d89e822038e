# Sourced by bench/track_ab.sh, bench/prior_ab.sh and bench/prior_time.sh: the world of one seed those
# vehicle-mode benchmarks share (a suite world with its zone chosen by the seed, 6 stretches, and its
# map), made once under OUT and reused by the others when they are given the same OUT.
#
#   vehicle_world GSF OUT SEED   # makes OUT/wSEED/{dataset files, m.map} unless m.map is there
vehicle_world() {
  local gsf=$1 out=$2 seed=$3
  local d=$out/w$seed
  [ -f "$d/m.map" ] && return 0
  "$gsf" simulate --out "$d" --preset suite --seed "$seed" --zone auto --stretches 6 --quiet >"$out/sim$seed.log"
  "$gsf" build-map --dataset "$d" --out "$d/m.map" --quiet >>"$out/sim$seed.log"
}
