#!/usr/bin/env bash
# The main job on the built-in phantom: inspect it, build its volume proxy
# mesh (refined at the left renal artery), compare meshes, export the volume.
# Outputs go to out/.
set -euo pipefail
build=${1:-build}
vpm="$build/client/vpm"
mkdir -p out
echo "== vpm volume info phantom:abdomen"
"$vpm" volume info phantom:abdomen
echo
echo "== vpm mesh (20^3 lattice -> 250 vertices, refined at the left renal artery)"
"$vpm" mesh --volume phantom:abdomen --refine-at-landmark left_renal_artery \
  --json out/mesh.json --vtu out/mesh.vtu
echo
echo "== vpm compare-meshes (same vertex budget)"
"$vpm" compare-meshes --volume phantom:abdomen --json out/compare-meshes.json
echo
echo "== vpm volume export"
"$vpm" volume export phantom:abdomen out/phantom_abdomen.nii.gz
echo
echo "demo outputs in out/: mesh.json, mesh.vtu (open in ParaView or 3D Slicer),"
echo "compare-meshes.json, phantom_abdomen.nii.gz"
