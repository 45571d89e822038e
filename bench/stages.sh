#!/usr/bin/env bash
# Cost model of one query (docs/results.md, "Cost model: floor and stages"): the floor and every stage
# of a query on the same scans in the same run, as ratios to the floor (bench/bench_stages.cpp), and
# with --counts the instructions per scan of each stage, counted by valgrind's callgrind (inclusive
# instruction counts of the stage functions; no timing noise).
#
#   bash bench/stages.sh [--map MAP --dataset DIR] [--out DIR] [--limit N] [--repeat R]
#                        [--counts | --counts-only] [--count-limit N] [--build DIR] [--reuse]
#                        [--arm64-counts AARCH64_BUILD_DIR] [--set name=value,...]
# Without --map/--dataset it simulates the demo world (gsf simulate --preset demo) into OUT/dataset and
# builds OUT/map.gsfmap once (reused on the next run). --counts runs one callgrind pass per mode
# (floor, instance, gsf, gsf+refine) over the first --count-limit scans (default 20) and prints the
# instructions per scan of each stage (--counts-only: skip the timing table; --reuse: parse the
# callgrind files of an earlier run in OUT again). --build points at another build tree (default
# build/release; it is then not rebuilt). --arm64-counts runs the timing table of an aarch64 build's
# bench_stages under qemu-aarch64 with bench/qemu_icount_plugin.c, whose clock counts guest
# instructions instead of time (configure that build with -DGSF_BUILD_BENCH=ON and build bench_stages).
# --set passes config overrides (as `gsf evaluate --set`) to every mode of bench_stages.
set -euo pipefail
cd "$(dirname "$0")/.."
map=""; dataset=""; out=out/stages; limit=0; repeat=3; counts=0; count_limit=20; build=build/release; timing=1; reuse=0; arm64=""; overrides=""
while [ $# -gt 0 ]; do
  case "$1" in
    --map) map=$2; shift 2;;
    --dataset) dataset=$2; shift 2;;
    --out) out=$2; shift 2;;
    --limit) limit=$2; shift 2;;
    --repeat) repeat=$2; shift 2;;
    --counts) counts=1; shift;;
    --counts-only) counts=1; timing=0; shift;;
    --count-limit) count_limit=$2; shift 2;;
    --reuse) reuse=1; shift;;
    --arm64-counts) arm64=$2; shift 2;;
    --build) build=$2; shift 2;;
    --set) overrides=$2; shift 2;;
    *) echo "bench/stages.sh: unknown option $1" >&2; exit 2;;
  esac
done
if [ "$build" = build/release ]; then
  cmake --preset release >/dev/null && cmake --build --preset release -j2 >/dev/null
fi
gsf=$build/tools/gsf
bench=$build/bench/bench_stages
mkdir -p "$out"
if [ -z "$map" ]; then
  dataset=$out/dataset; map=$out/map.gsfmap
  if [ ! -f "$map" ]; then
    $gsf simulate --out "$dataset" --preset demo --quiet >/dev/null
    $gsf build-map --dataset "$dataset" --out "$map" --quiet >/dev/null
  fi
fi
[ -n "$dataset" ] || { echo "bench/stages.sh: --map needs --dataset" >&2; exit 2; }

if [ -n "$arm64" ]; then
  plugin=$out/qemu_icount_plugin.so
  cc -shared -fPIC -O2 -Wall -Wextra -o "$plugin" bench/qemu_icount_plugin.c
  f=/dev/shm/gsf_icount.$$
  : >"$f"
  echo "aarch64 ($arm64): guest instructions per stage under qemu-aarch64 (counts, not times), first $count_limit scans:"
  qemu-aarch64 -L /usr/aarch64-linux-gnu -plugin "$plugin,out=$f" "$arm64/bench/bench_stages" --map "$map" \
      --dataset "$dataset" --limit "$count_limit" --repeat 1 --icount-file "$f" --set "$overrides"
  rm -f "$f"
  exit 0
fi
if [ "$timing" = 1 ]; then
  $bench --map "$map" --dataset "$dataset" --limit "$limit" --repeat "$repeat" --set "$overrides"
fi
[ "$counts" = 1 ] || exit 0

command -v valgrind >/dev/null || { echo "bench/stages.sh: --counts needs valgrind (apt-get install valgrind)" >&2; exit 1; }
echo
echo "instructions per scan (callgrind, inclusive counts of the stage functions, first $count_limit scans):"
for mode in floor instance gsf gsf+refine; do
  f=$out/callgrind.$mode.out
  [ "$reuse" = 1 ] && [ -f "$f" ] && continue
  valgrind --tool=callgrind --callgrind-out-file="$f" "$bench" --map "$map" --dataset "$dataset" \
      --count "$mode" --limit "$count_limit" --set "$overrides" >"$out/callgrind.$mode.log" 2>&1
  callgrind_annotate --inclusive=yes --threshold=100 "$f" >"$out/callgrind.$mode.txt"
done
python3 - "$out" "$count_limit" <<'PY'
import re, sys
out, n = sys.argv[1], None
# stage -> (function name prefixes whose inclusive counts add up, prefixes counted exclusively)
STAGES = [
    ("floor", ["bench_floor_bucket("], []),
    ("voxel layer", ["gsf::VoxelLayer::build("], []),
    ("clustering", ["gsf::InstanceClustering::build("], []),
    # the gather and the fit of every query instance (before 2026-12-07: collect_field_points + fit)
    ("query fields", ["gsf::fit_instance_field("], []),
    ("triangles", ["gsf::TriangleBuilder::build("], []),
    ("matching", ["gsf::TriangleMatcher::match("], []),
    ("GSF filter", ["gsf::GsfFilter::similarity("], []),
    ("hypotheses", ["gsf::PoseHypotheses::generate("], []),
    # the whole answer choice (every verify_pose and pattern search of the hypotheses, the rarity
    # weights and the ranking); until 2026-12-01 verify_pose inclusive + verify_pose_refined exclusive,
    # 0.05 M a scan less on the demo
    ("verification", ["gsf::AnswerSelector::choose("], []),
    ("confidence", ["gsf::AnswerConfidence::measure("], []),
    ("refinement", ["gsf::Refiner::refine("], []),
    ("total query", ["gsf::Localizer::localize("], []),
]
def load(mode):
    incl, excl = {}, {}
    txt = open(f"{out}/callgrind.{mode}.txt").read()
    for line in txt.splitlines():
        m = re.match(r"\s*([\d,]+) \([\s\d.]+%\)\s+[^:\s]*:(\S.*?)(?: \[.*\])?$", line)
        if not m: continue
        v = int(m.group(1).replace(",", ""))
        name = m.group(2)
        name = re.sub(r"^\(anonymous namespace\)::", "", name)
        incl[name] = incl.get(name, 0) + v
    return incl
log = open(f"{out}/callgrind.gsf.log").read()
scans = int(re.search(r"scans: (\d+)", log).group(1))
modes = ["instance", "gsf", "gsf+refine"]
data = {m: load(m) for m in ["floor"] + modes}
# exclusive counts for the few exclusive entries come from a second, non-inclusive annotate
import subprocess
def excl(mode, prefix):
    txt = subprocess.run(["callgrind_annotate", "--inclusive=no", "--threshold=100", f"{out}/callgrind.{mode}.out"],
                         capture_output=True, text=True).stdout
    tot = 0
    for line in txt.splitlines():
        m = re.match(r"\s*([\d,]+) \([\s\d.]+%\)\s+[^:\s]*:(\S.*?)(?: \[.*\])?$", line)
        if m and m.group(2).startswith(prefix): tot += int(m.group(1).replace(",", ""))
    return tot
def stage(mode, s):
    d = data[mode]
    v = sum(val for name, val in d.items() for p in s[1] if name.startswith(p))
    v += sum(excl(mode, p) for p in s[2])
    return v / scans
floor = stage("floor", STAGES[0])
print(f"scans: {scans}; floor {floor/1e3:.0f} k instructions per scan")
print("| stage | GSF off instr. | x floor | GSF on instr. | x floor | GSF + refine instr. | x floor |")
print("| --- | ---: | ---: | ---: | ---: | ---: | ---: |")
rows = {}
for s in STAGES:
    cells = []
    for m in modes:
        v = floor if s[0] == "floor" else stage(m, s)
        rows.setdefault(m, {})[s[0]] = v
        cells.append(f"{v/1e6:.2f} M | {v/floor:.2f}")
    print(f"| {s[0]} | " + " | ".join(cells) + " |")
cells = []
for m in modes:
    r = rows[m]
    other = r["total query"] - sum(v for k, v in r.items() if k not in ("floor", "total query"))
    cells.append(f"{other/1e6:.2f} M | {other/floor:.2f}")
print("| other (in localize) | " + " | ".join(cells) + " |")
print(f"GSF on / off: {rows['gsf']['total query']/rows['instance']['total query']:.3f}; "
      f"GSF + refine / GSF on: {rows['gsf+refine']['total query']/rows['gsf']['total query']:.3f} (instruction counts)")
PY
