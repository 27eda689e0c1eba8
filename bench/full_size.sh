#!/bin/sh
# Full-size volumes (issue 16, point 2): a 512 x 512 x 900 int16 CT made
# from the phantom (bench/make_ct_nifti.cc; 450 MiB, written once under
# $VPM_BENCH_DIR, not committed), then a table of
#   - `vpm mesh` on it: peak RSS (/usr/bin/time -v) against the goal of
#     5 bytes per voxel + 300 MiB, and wall time (load + upload + mesh)
#     against 3 s; best of REPS runs;
#   - the interactive frame and drag figures of drag_loop_bench (250-vertex
#     mesh) on the CT and on the 256^3 phantom, same image sizes, so the
#     same pixels: the ray caster's cost should follow the image.
# Usage: bench/full_size.sh [BUILD_DIR] [REPS]
set -eu
BUILD=${1:-build}
REPS=${2:-3}
DIR=${VPM_BENCH_DIR:-/tmp/vpm-bench}
CT=$DIR/ct_512x512x900_int16.nii
mkdir -p "$DIR"
[ -f "$CT" ] || "$BUILD/bench/make_ct_nifti" "$CT" 512 512 900
VOXELS=$((512 * 512 * 900))
GOAL_KIB=$(( (VOXELS * 5 + 300 * 1024 * 1024) / 1024 ))

best_rss=0; best_wall=999999
for r in $(seq "$REPS"); do
  /usr/bin/time -v "$BUILD/client/vpm" mesh --volume "$CT" >"$DIR/mesh.out" 2>"$DIR/mesh.time"
  rss=$(sed -n 's/.*Maximum resident set size (kbytes): //p' "$DIR/mesh.time")
  wall=$(sed -n 's/.*Elapsed (wall clock) time (h:mm:ss or m:ss): //p' "$DIR/mesh.time" |
         awk -F: '{ s = 0; for (i = 1; i <= NF; ++i) s = s * 60 + $i; print s }')
  [ "$best_rss" -eq 0 ] || [ "$rss" -lt "$best_rss" ] && best_rss=$rss
  best_wall=$(awk -v a="$wall" -v b="$best_wall" 'BEGIN { print (a < b) ? a : b }')
done
echo "full-size volumes, $(nproc) cores, load: $(cut -d' ' -f1-3 /proc/loadavg)"
printf "%-44s %12s %12s\n" "vpm mesh, 512x512x900 int16 CT" "measured" "goal"
printf "%-44s %9d MiB %9d MiB\n" "peak RSS (best of $REPS)" $((best_rss / 1024)) $((GOAL_KIB / 1024))
printf "%-44s %8.2f s %10s\n" "wall: load + upload + mesh (best of $REPS)" "$best_wall" "3 s"
printf "%-44s %12s\n" "bytes per voxel (RSS - 300 MiB)" \
  "$(awk -v r="$best_rss" -v v="$VOXELS" 'BEGIN { printf "%.2f", (r * 1024 - 300 * 1048576) / v }')"
echo "stages of the last run:"
grep -E "^(upload|evaluate|decimate|refine|classify|tetrahedralize|total)" "$DIR/mesh.out"

for source in "phantom:abdomen" "$CT"; do
  echo
  "$BUILD/bench/drag_loop_bench" "$source" --max-vertices 400 | sed -n '1,40p'
done
