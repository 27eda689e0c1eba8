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
# A skull phantom (interior dark in any window) with plastic inserts: grab
# the central plastic insert and drag it 10 mm superior (physical mm).
ct=tests/data/ct-philips-tilt
ct_mesh=(--grid 20 20 18 --grab -0.5 102.3 770.4)
"$vpm" volume info "$ct"
ct_before=$("$vpm" render --volume "$ct" "${ct_mesh[@]}" --out out/ct_before.png)
echo "$ct_before" | tail -1
"$vpm" render --volume "$ct" "${ct_mesh[@]}" --drag 0 0 10 --out out/ct_after.png | tail -1
ct_pixel=$(echo "$ct_before" | sed -n 's/^grab point at pixel (\([0-9.-]*\), \([0-9.-]*\))$/\1 \2/p')
# shellcheck disable=SC2086
python3 scripts/region_difference.py out/ct_before.png out/ct_after.png $ct_pixel 40
for plane in coronal sagittal; do
  "$vpm" slice --volume "$ct" "${ct_mesh[@]}" --plane $plane \
    --out out/ct_${plane}_before.png | tail -1
  "$vpm" slice --volume "$ct" "${ct_mesh[@]}" --drag 0 0 10 --plane $plane \
    --out out/ct_${plane}_after.png | tail -1
done
"$vpm" slice --volume "$ct" "${ct_mesh[@]}" --drag 0 0 10 --plane sagittal --overlay \
  --out out/ct_sagittal_after_overlay.png | tail -1
echo
echo "== a real patient's abdominal CT: grab the left kidney, drag it 15 mm superior"
# tests/data/ct-abdomen-kidney: the grab at the left kidney's centre
# (physical mm; world LPS (79, -125, 358)) takes the organ (the tissue
# connected to the point) and drags it superior; Slicer's CT-Soft-Tissue with
# the view cut shows it in 3D.
kidney=tests/data/ct-abdomen-kidney/ct_abdomen.nii.gz
kidney_grab=(--grab 79 -125.3 358.3)
kidney_before=$("$vpm" render --volume "$kidney" "${kidney_grab[@]}" --preset CT-Soft-Tissue \
  --out out/kidney_before.png)
echo "$kidney_before" | grep -E '^grab|^mesh'
"$vpm" render --volume "$kidney" "${kidney_grab[@]}" --preset CT-Soft-Tissue --drag 0 0 15 \
  --out out/kidney_after.png | grep -E '^mesh'
kidney_pixel=$(echo "$kidney_before" | sed -n 's/^grab point at pixel (\([0-9.-]*\), \([0-9.-]*\))$/\1 \2/p')
# shellcheck disable=SC2086
python3 scripts/region_difference.py out/kidney_before.png out/kidney_after.png $kidney_pixel 40
"$vpm" slice --volume "$kidney" "${kidney_grab[@]}" --plane coronal --pixel 1 \
  --out out/kidney_coronal_before.png | tail -1
"$vpm" slice --volume "$kidney" "${kidney_grab[@]}" --drag 0 0 15 --plane coronal --pixel 1 \
  --out out/kidney_coronal_after.png | tail -1
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
echo "  ct_before/after.png          the tilted head CT: 3D frames before and after a 10 mm drag"
echo "  ct_{coronal,sagittal}_*.png  its slices through the grab, before and after"
echo "  kidney_*.png                 the abdominal CT: its left kidney dragged 15 mm superior,"
echo "                               3D (CT-Soft-Tissue, cut) and coronal slice, before and after"
echo "  deformed.nii.gz              the deformed volume, source geometry"
echo "  compare-meshes.json          section-6 reconstruction measures"
echo "  phantom_abdomen.nii.gz       the phantom itself"
echo
echo "== the service: vpm-server on loopback, vpm play, vpm-load (scripts/demo_server.sh)"
scripts/demo_server.sh "$build"
