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
mkdir -p fuzz/crashes
for bin in build/fuzz/fuzz/fuzz_*; do
  name=$(basename "$bin")
  [ -n "$only" ] && [ "$name" != "$only" ] && continue
  mkdir -p "fuzz/corpus-work/$name" "fuzz/corpus/$name"
  echo "=== fuzzing $name for ${secs}s"
  "$bin" -max_total_time="$secs" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
    -artifact_prefix="fuzz/crashes/$name-" "fuzz/corpus-work/$name" "fuzz/corpus/$name" 2>&1 | tail -n 12
done
echo "scripts/fuzz.sh: done"
