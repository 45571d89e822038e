#!/usr/bin/env bash
# Memcheck on a sample of the test binaries (host release build): map format, back end, scene graph,
# and the localizer's hostile-input cases. The *_noheap binaries are skipped: valgrind replaces
# operator new, which the allocation counter also replaces.
set -euo pipefail
cd "$(dirname "$0")/.."
cmake --preset release >/dev/null && cmake --build --preset release >/dev/null
run() { echo "=== valgrind $*"; valgrind --error-exitcode=1 --leak-check=full -q "$@" | tail -n 2; }
# Most test files share one executable (tests/CMakeLists.txt); -# tags each test case with its file.
run build/release/tests/gsf_unit_tests -# "[#test_map_format],[#test_backend],[#test_scene_graph]"
run build/release/tests/test_localizer "Hostile input gets a status and the localizer stays usable"
echo "scripts/valgrind.sh: clean"
