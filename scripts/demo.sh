#!/usr/bin/env bash
# The main job on the built-in phantom: inspect it, build its volume proxy
# mesh (refined at the left renal artery), compare meshes, then grab the
# left renal artery, drag it 20 mm cranially and render before/after frames
# and the deformed volume. Outputs go to out/.
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
echo "== vpm render: before"
"$vpm" render --volume phantom:abdomen --mesh-json out/mesh.json --out out/before.png
"$vpm" render --volume phantom:abdomen --mesh-json out/mesh.json --overlay \
  --out out/before_overlay.png
echo
echo "== vpm render: grab the left renal artery, drag 20 mm cranially"
"$vpm" render --volume phantom:abdomen --mesh-json out/mesh.json \
  --grab-landmark left_renal_artery --drag 0 0 20 --out out/after.png \
  --out-volume out/deformed.nii.gz
"$vpm" render --volume phantom:abdomen --mesh-json out/mesh.json \
  --grab-landmark left_renal_artery --drag 0 0 20 --overlay --out out/after_overlay.png
"$vpm" render --volume phantom:abdomen --mesh-json out/mesh.json --mode mip --preset ct-vessels \
  --grab-landmark left_renal_artery --drag 0 0 20 --out out/after_mip.png
echo
echo "== vpm compare-meshes (same vertex budget; section-6 measures)"
"$vpm" compare-meshes --volume phantom:abdomen --json out/compare-meshes.json
echo
echo "== vpm volume export"
"$vpm" volume export phantom:abdomen out/phantom_abdomen.nii.gz
echo
echo "demo outputs in out/:"
echo "  mesh.json, mesh.vtu          the proxy mesh (ParaView, 3D Slicer)"
echo "  before*.png, after*.png      frames before and after the drag (overlay: deformable"
echo "                               vertices yellow, hard blue, handles and drag arrow)"
echo "  deformed.nii.gz              the deformed volume, source geometry"
echo "  compare-meshes.json          section-6 reconstruction measures"
echo "  phantom_abdomen.nii.gz       the phantom itself"
echo
echo "== the service: vpm-server on loopback, vpm play, vpm-load (scripts/demo_server.sh)"
scripts/demo_server.sh "$build"
