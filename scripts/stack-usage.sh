#!/usr/bin/env bash
# Builds core with -fstack-usage (release flags) and reports the largest stack frames. No recursion
# exists in core (max clique is iterative with an explicit arena stack), so the deepest chain is
# bounded by the sum of the largest frames along the call levels of Localizer::localize.
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build/stack -G Ninja -DCMAKE_BUILD_TYPE=Release -DGSF_STACK_USAGE=ON -DGSF_BUILD_TESTS=OFF \
  -DGSF_BUILD_TOOLS=OFF -DGSF_BUILD_BENCH=OFF >/dev/null
cmake --build build/stack --target gsf >/dev/null
echo "largest stack frames in core (bytes, function, qualifier):"
cat build/stack/core/CMakeFiles/gsf.dir/src/*.su | sort -t$'\t' -k2 -n -r | head -15 | awk -F'\t' '{printf "  %8s  %s  (%s)\n", $2, $1, $3}'
echo "dynamic or unbounded frames:"
grep -hE $'\t(dynamic|unbounded)' build/stack/core/CMakeFiles/gsf.dir/src/*.su || echo "  none"
