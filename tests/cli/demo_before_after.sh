#!/usr/bin/env bash
# The demo's before and after frames (make demo: the left renal artery of the
# phantom grabbed and dragged 20 mm cranially, the default view cut) must
# differ clearly around the grab: mean |after - before| over R, G, B in the
# 40 x 40 pixels around the grab point at least 6/255. Measured 2026-11-25:
# 11.3/255 with the view cut (whole frame 0.4); 2026-11-24: 1.0/255 without
# it (--cut off: the drag hides under the skin; docs/RENDERING.md, "Seeing
# inside").
set -euo pipefail
build=$1
source_dir=$2
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
vpm="$build/client/vpm"
"$vpm" mesh --volume phantom:abdomen --refine-at-landmark left_renal_artery --json "$out/mesh.json" >/dev/null
before=$("$vpm" render --volume phantom:abdomen --mesh-json "$out/mesh.json" \
  --grab-landmark left_renal_artery --out "$out/before.png")
after=$("$vpm" render --volume phantom:abdomen --mesh-json "$out/mesh.json" \
  --grab-landmark left_renal_artery --drag 0 0 20 --out "$out/after.png")
# The still shows the whole 20 mm drag: a drag event's FEM work is bounded,
# and the offline commands finish (settle) the drag before they render.
moved=$(echo "$after" | sed -n 's/.*max displacement \([0-9.]*\) mm.*/\1/p')
awk -v m="$moved" 'BEGIN { exit !(m >= 19.99) }' ||
  { echo "the render's drag stopped short: max displacement '$moved' mm of 20"; exit 1; }
pixel=$(echo "$before" | sed -n 's/^grab point at pixel (\([0-9.-]*\), \([0-9.-]*\))$/\1 \2/p')
[ -n "$pixel" ] || { echo "vpm render did not print the grab pixel"; echo "$before"; exit 1; }
# shellcheck disable=SC2086
python3 "$source_dir/scripts/region_difference.py" "$out/before.png" "$out/after.png" $pixel 20 --min 6
# Without the view cut the same drag hides under the skin: the check is not
# met by any pair of frames.
"$vpm" render --volume phantom:abdomen --mesh-json "$out/mesh.json" --cut off \
  --grab-landmark left_renal_artery --out "$out/before_skin.png" >/dev/null
"$vpm" render --volume phantom:abdomen --mesh-json "$out/mesh.json" --cut off \
  --grab-landmark left_renal_artery --drag 0 0 20 --out "$out/after_skin.png" >/dev/null
# shellcheck disable=SC2086
python3 "$source_dir/scripts/region_difference.py" "$out/before_skin.png" "$out/after_skin.png" $pixel 20

# The real tilted CT as make demo drags it (the central insert 10 mm
# superior): the 3D frames differ around the grab by at least 5/255 (80 x 80
# pixels; measured 9.7/255), the coronal slices through it by at least 8/255
# (measured 16.8/255; README, "A real scanner's CT in the demo").
ct="$source_dir/tests/data/ct-philips-tilt"
ct_mesh=(--grid 20 20 18 --grab 123 145 64)
ct_before=$("$vpm" render --volume "$ct" "${ct_mesh[@]}" --out "$out/ct_before.png")
"$vpm" render --volume "$ct" "${ct_mesh[@]}" --drag 0 0 10 --out "$out/ct_after.png" >/dev/null
ct_pixel=$(echo "$ct_before" | sed -n 's/^grab point at pixel (\([0-9.-]*\), \([0-9.-]*\))$/\1 \2/p')
[ -n "$ct_pixel" ] || { echo "vpm render did not print the grab pixel"; echo "$ct_before"; exit 1; }
# shellcheck disable=SC2086
python3 "$source_dir/scripts/region_difference.py" "$out/ct_before.png" "$out/ct_after.png" \
  $ct_pixel 40 --min 5
"$vpm" slice --volume "$ct" "${ct_mesh[@]}" --plane coronal --out "$out/ct_coronal_before.png" >/dev/null
"$vpm" slice --volume "$ct" "${ct_mesh[@]}" --drag 0 0 10 --plane coronal \
  --out "$out/ct_coronal_after.png" >/dev/null
# The grab lies at the slice's pixel (255, 215): the plane passes through
# it, and the slice is 511 x 438 pixels of 0.482 mm around the volume.
python3 "$source_dir/scripts/region_difference.py" "$out/ct_coronal_before.png" \
  "$out/ct_coronal_after.png" 255 215 40 --min 8
