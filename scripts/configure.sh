#!/usr/bin/env bash
# Configures a build tree with Ninja and the given compilers:
#   scripts/configure.sh DIR CC CXX [cmake arguments...]
# `make configure` (the main tree, clang unless CC/CXX are given) and
# scripts/sanitize.sh (build-asan, build-tsan: clang) call it. A tree
# configured before with another C++ compiler is configured afresh (its
# CMakeCache.txt and CMakeFiles go; CMake refuses to switch compilers in
# place), so `make test CXX=g++ CC=gcc` and back rebuild rather than fail.
set -euo pipefail
dir="${1:?usage: scripts/configure.sh DIR CC CXX [cmake arguments...]}"
cc="${2:?usage: scripts/configure.sh DIR CC CXX [cmake arguments...]}"
cxx="${3:?usage: scripts/configure.sh DIR CC CXX [cmake arguments...]}"
shift 3
cd "$(dirname "$0")/.."
for tool in "$cc" "$cxx"; do
  if ! command -v "$tool" > /dev/null; then
    echo "configure.sh: compiler '$tool' not found (make deps installs clang)" >&2
    exit 1
  fi
done
cxx_path="$(readlink -f "$(command -v "$cxx")")"
if [ -f "$dir/CMakeCache.txt" ]; then
  cached="$(sed -n 's/^CMAKE_CXX_COMPILER:[A-Z]*=//p' "$dir/CMakeCache.txt")"
  if [ -z "$cached" ] || [ "$(readlink -f "$cached")" != "$cxx_path" ]; then
    echo "configure.sh: $dir was configured with '${cached:-?}', now $cxx: configuring afresh"
    rm -rf "$dir/CMakeCache.txt" "$dir/CMakeFiles"
  fi
fi
cmake -S . -B "$dir" -G Ninja -DCMAKE_C_COMPILER="$cc" -DCMAKE_CXX_COMPILER="$cxx" "$@" > /dev/null
