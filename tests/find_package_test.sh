#!/usr/bin/env bash
# Installs this build tree into a temporary prefix and builds tests/consumer against it with
# find_package(gsf) (gsf::gsf, gsf::port, gsf::gsf_port), then runs the C++ and the C consumer.
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
echo "2 passed, 0 failed"
