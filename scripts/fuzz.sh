#!/usr/bin/env bash
# Builds the volume-reader fuzz targets (clang, libFuzzer + ASan + UBSan) in
# build-fuzz and runs each for a bounded time; fails on any crash, leak,
# sanitizer report or timeout.
#
#   scripts/fuzz.sh [seconds_per_target] [target...]
#
# Builds of one tree take turns (flock on <build>/fuzz.lock): two runs at
# once wait for each other instead of racing in one build folder.
#
# Seeds come from fuzz/corpus/<name>/ (committed); inputs the fuzzer finds go
# to fuzz/corpus-work/<name>/ (ignored by git), crash reproducers to
# fuzz/corpus-work/<name>/crash-*. Reproduce one with
#   build-fuzz/fuzz/fuzz_<name> fuzz/corpus-work/<name>/crash-...
# Environment: VPM_FUZZ_BUILD_DIR (default build-fuzz), VPM_FUZZ_JOBS (build
# parallelism, default 2).
set -euo pipefail

seconds="${1:-10}"
shift || true
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${VPM_FUZZ_BUILD_DIR:-$root/build-fuzz}"
jobs="${VPM_FUZZ_JOBS:-2}"
targets=("$@")
if [ "${#targets[@]}" -eq 0 ]; then
  targets=(fuzz_nifti fuzz_nrrd fuzz_metaimage fuzz_dicom fuzz_raw)
fi

mkdir -p "$build"
(
  flock 9
  if [ ! -f "$build/build.ninja" ]; then
    CC=clang CXX=clang++ cmake -S "$root" -B "$build" -G Ninja -DVPM_FUZZ=ON \
      -DBUILD_TESTING=OFF -DCMAKE_BUILD_TYPE=RelWithDebInfo > "$build/configure.log" 2>&1 ||
      { cat "$build/configure.log"; exit 1; }
  fi
  cmake --build "$build" -j "$jobs" --target "${targets[@]}"
) 9> "$build/fuzz.lock"

status=0
for target in "${targets[@]}"; do
  name="${target#fuzz_}"
  work="$root/fuzz/corpus-work/$name"
  mkdir -p "$work"
  dict=()
  if [ -f "$root/fuzz/$name.dict" ]; then dict=(-dict="$root/fuzz/$name.dict"); fi
  echo "== $target: ${seconds}s"
  if ! "$build/fuzz/$target" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
      -malloc_limit_mb=1024 -print_final_stats=1 -artifact_prefix="$work/" "${dict[@]}" \
      "$work" "$root/fuzz/corpus/$name" > "$work.log" 2>&1; then
    echo "!! $target failed; log: $work.log"
    tail -n 40 "$work.log"
    status=1
  else
    grep -E "stat::number_of_executed_units|stat::peak_rss_mb|Done [0-9]+ runs" "$work.log" || true
  fi
done
exit "$status"
