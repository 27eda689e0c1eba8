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
echo "== vpm render: before (grabbed, not yet dragged: the view cut passes through the grab)"
before=$("$vpm" render --volume phantom:abdomen --mesh-json out/mesh.json \
  --grab-landmark left_renal_artery --out out/before.png)
echo "$before"
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
pixel=$(echo "$before" | sed -n 's/^grab point at pixel (\([0-9.-]*\), \([0-9.-]*\))$/\1 \2/p')
# shellcheck disable=SC2086
python3 scripts/region_difference.py out/before.png out/after.png $pixel 20
echo
echo "== vpm slice: coronal through the dragged artery, before and after, cut tets outlined"
"$vpm" slice --volume phantom:abdomen --mesh-json out/mesh.json --grab-landmark left_renal_artery \
  --plane coronal --overlay --out out/slice_before.png | tail -1
"$vpm" slice --volume phantom:abdomen --mesh-json out/mesh.json --grab-landmark left_renal_artery \
  --drag 0 0 20 --plane coronal --overlay --out out/slice_after.png | tail -1
echo
echo "== a real scanner's CT: the gantry-tilted Philips series (tests/data/ct-philips-tilt)"
"$vpm" volume info tests/data/ct-philips-tilt
"$vpm" render --volume tests/data/ct-philips-tilt --grid 20 20 18 --grab 123 145 64 \
  --out out/ct_before.png | tail -1
"$vpm" render --volume tests/data/ct-philips-tilt --grid 20 20 18 --grab 123 145 64 \
  --drag 0 0 10 --out out/ct_after.png | tail -1
"$vpm" slice --volume tests/data/ct-philips-tilt --grid 20 20 18 --grab 123 145 64 \
  --drag 0 0 10 --plane sagittal --overlay --out out/ct_slice_after.png | tail -1
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
echo "  slice_before/after.png       coronal slices through the grab (cut tets outlined)"
echo "  ct_*.png                     the tilted head CT: before/after frames, a sagittal slice"
echo "  deformed.nii.gz              the deformed volume, source geometry"
echo "  compare-meshes.json          section-6 reconstruction measures"
echo "  phantom_abdomen.nii.gz       the phantom itself"
echo
echo "== the service: vpm-server on loopback, vpm play, vpm-load (scripts/demo_server.sh)"
scripts/demo_server.sh "$build"
