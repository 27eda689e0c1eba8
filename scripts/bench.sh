#!/usr/bin/env bash
# Runs every benchmark and keeps the tables in out/bench.txt. Timings on a
# shared 2-core machine move 10-20% between runs; run on an idle machine.
set -euo pipefail
build=${1:-build}
mkdir -p out
{
  echo "# vpm benchmarks, $(date -u +%Y-%m-%dT%H:%MZ), $(nproc) cores"
  for b in gradient_bench mesh_build_bench fem_bench warp_bench render_bench drag_loop_bench; do
    if [ -x "$build/bench/$b" ]; then
      echo; echo "## $b"; "$build/bench/$b"
    else
      echo; echo "## $b: not built"
    fi
  done
  # A 512 x 512 x 900 int16 CT (450 MiB under $VPM_BENCH_DIR, made once).
  echo; echo "## full_size.sh"; bench/full_size.sh "$build" 2
} 2>&1 | tee out/bench.txt
