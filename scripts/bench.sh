#!/usr/bin/env bash
# Runs every benchmark and keeps the tables in out/bench.txt. Timings on a
# shared 2-core machine move 10-20% between runs; run on an idle machine.
set -euo pipefail
build=${1:-build}
mkdir -p out
{
  echo "# vpm benchmarks, $(date -u +%Y-%m-%dT%H:%MZ), $(nproc) cores"
  for b in gradient_bench mesh_build_bench fem_bench grab_drag_bench warp_bench render_bench sample_rate_bench drag_loop_bench render_storm_bench slice_bench; do
    if [ -x "$build/bench/$b" ]; then
      echo; echo "## $b"; "$build/bench/$b"
    else
      echo; echo "## $b: not built"
    fi
  done
  # Case event writes on SQLite and on a throwaway PostgreSQL server.
  echo; echo "## case_store_bench"
  pg_dir=$(mktemp -d /tmp/vpm-bench-pg.XXXXXX)
  if scripts/pg-test-server.sh start "$pg_dir" >/dev/null; then
    "$build/bench/case_store_bench" --postgres "$(cat "$pg_dir/conninfo")"
  else
    "$build/bench/case_store_bench"
  fi
  scripts/pg-test-server.sh stop "$pg_dir"
  # vpm against VTK's mappers (bench/peer_vtk.py): needs Debian's VTK and a
  # virtual X server, installed by bench/setup_peer.sh, not by make test.
  echo; echo "## peer_vtk"
  if /usr/bin/python3 -c "import vtk" 2>/dev/null && command -v xvfb-run >/dev/null; then
    xvfb-run -a -s "-screen 0 1280x1024x24" /usr/bin/python3 bench/peer_vtk.py \
      --build "$build" --out out/peer
  else
    echo "skipped: VTK's Python bindings or xvfb-run missing (run bench/setup_peer.sh)"
  fi
  # A 512 x 512 x 900 int16 CT (450 MiB under $VPM_BENCH_DIR, made once).
  echo; echo "## full_size.sh"; bench/full_size.sh "$build" 2
} 2>&1 | tee out/bench.txt
