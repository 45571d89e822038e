#!/usr/bin/env bash
# The README's test command: builds and runs the test suite on the host (release and ASan+UBSan),
# on ARM64 under qemu, and the two-thread test under ThreadSanitizer (the tsan presets build and run
# test_threads only), after checking that every C/C++ file follows .clang-format ("format"). Pass names to
# run a subset, e.g. `scripts/test.sh release` or `scripts/test.sh format release`.
set -euo pipefail
cd "$(dirname "$0")/.."
presets=("$@")
[ ${#presets[@]} -eq 0 ] && presets=(format release asan aarch64 tsan)
for p in "${presets[@]}"; do
  if [ "$p" = format ]; then
    echo "=== [format] scripts/format.sh --check"
    bash scripts/format.sh --check
    continue
  fi
  echo "=== [$p] configure + build"
  t0=$(date +%s)
  cmake --preset "$p" >/dev/null
  cmake --build --preset "$p"
  t1=$(date +%s)
  echo "=== [$p] test"
  ctest --preset "$p"
  echo "=== [$p] build $((t1 - t0)) s, test $(($(date +%s) - t1)) s"
done
echo "scripts/test.sh: all presets passed (${presets[*]})"
