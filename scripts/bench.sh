#!/usr/bin/env bash
# Runs every benchmark and keeps the tables in out/bench.txt.
set -euo pipefail
build=${1:-build}
mkdir -p out
{
  echo "# vpm benchmarks, $(date -u +%Y-%m-%dT%H:%MZ), $(nproc) cores"
  "$build/bench/gradient_bench"
  "$build/bench/mesh_build_bench"
} 2>&1 | tee out/bench.txt
