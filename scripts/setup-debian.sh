#!/usr/bin/env bash
# Installs everything gsf needs on a fresh Debian 12 machine (run as root). Debian packages only.
set -euo pipefail
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
pkgs=(cmake ninja-build g++ libeigen3-dev catch2 g++-aarch64-linux-gnu qemu-user
      clang-14 libclang-rt-14-dev clang-format-14 valgrind python3
      librsvg2-bin)   # librsvg2-bin: rsvg-convert, for gsf evaluate --png and the docs' PNG pictures
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup-debian: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y --no-install-recommends "${missing[@]}"
fi
# clang/clang++ names for the fuzz preset
command -v clang++ >/dev/null || $SUDO ln -sf "$(command -v clang++-14)" /usr/local/bin/clang++
command -v clang >/dev/null || $SUDO ln -sf "$(command -v clang-14)" /usr/local/bin/clang
echo "setup-debian: ok"
