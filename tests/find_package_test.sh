#!/usr/bin/env bash
# Installs this build tree into a temporary prefix and builds tests/consumer against it with
# find_package(gsf) (gsf::gsf, gsf::port, gsf::gsf_port, gsf::mapping), then runs the C++ and the C
# consumer and a map tool on gsf::mapping.
set -euo pipefail
build=$1
src=$(cd "$(dirname "$0")" && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cmake --install "$build" --prefix "$tmp/prefix" >/dev/null
cmake -S "$src/consumer" -B "$tmp/build" -G Ninja -DCMAKE_PREFIX_PATH="$tmp/prefix" >/dev/null
cmake --build "$tmp/build" >/dev/null
"$tmp/build/app" | grep -q " Ok$"
"$tmp/build/capp" | grep -q " Ok$"
[ -x "$tmp/build/mapapp" ] || { echo "gsf::mapping was not installed"; exit 1; }
"$tmp/build/mapapp" | grep -q " Ok$"
echo "3 passed, 0 failed"
