#!/usr/bin/env bash
# Builds the libFuzzer targets (fuzz preset, clang) and runs each one.
#   scripts/fuzz.sh            60 s per target (override with GSF_FUZZ_SECONDS)
#   scripts/fuzz.sh --ci       the short CI run (GSF_FUZZ_SECONDS, default 20 s per target)
#   scripts/fuzz.sh NAME SECS  one target for a long run, e.g. scripts/fuzz.sh fuzz_map_loader 3600
# New inputs go to fuzz/corpus-work/<target>/ (git-ignored); crashes to fuzz/crashes/ - copy each crash
# into fuzz/corpus/<target>/ and add a regression test.
set -euo pipefail
cd "$(dirname "$0")/.."
secs=${GSF_FUZZ_SECONDS:-60}
if [ "${1:-}" = "--ci" ]; then secs=${GSF_FUZZ_SECONDS:-20}; fi
only=""
if [ "${1:-}" = "--ci" ]; then shift; elif [ -n "${1:-}" ]; then only=$1; secs=${2:-$secs}; fi
cmake --preset fuzz >/dev/null
cmake --build --preset fuzz
mkdir -p fuzz/crashes fuzz/logs
# Targets run side by side, one per core (GSF_FUZZ_JOBS): each is single-threaded, so a CI run of eight
# targets takes four rounds of `secs`, not eight. Each target's log is printed as it ends; any target
# that finds a crash (or fails to run) fails the script after all have ended.
jobs=${GSF_FUZZ_JOBS:-$(nproc)}
failed=()
declare -A pids=()
report() {  # pid, exit status
  local name=${pids[$1]}
  if [ "$2" -eq 0 ]; then echo "=== $name: no crash"; else failed+=("$name"); echo "=== $name: FAILED ($2)"; fi
  tail -n 12 "fuzz/logs/$name.log"
  unset "pids[$1]"
}
for bin in build/fuzz/fuzz/fuzz_*; do
  name=$(basename "$bin")
  [ -n "$only" ] && [ "$name" != "$only" ] && continue
  mkdir -p "fuzz/corpus-work/$name" "fuzz/corpus/$name"
  while [ ${#pids[@]} -ge "$jobs" ]; do
    rc=0
    wait -n -p done_pid "${!pids[@]}" || rc=$?
    report "$done_pid" "$rc"
  done
  echo "=== fuzzing $name for ${secs}s"
  "$bin" -max_total_time="$secs" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
    -artifact_prefix="fuzz/crashes/$name-" "fuzz/corpus-work/$name" "fuzz/corpus/$name" >"fuzz/logs/$name.log" 2>&1 &
  pids[$!]=$name
done
for pid in "${!pids[@]}"; do
  rc=0
  wait "$pid" || rc=$?
  report "$pid" "$rc"
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "scripts/fuzz.sh: FAILED: ${failed[*]} (inputs in fuzz/crashes/)"
  exit 1
fi
echo "scripts/fuzz.sh: done"
