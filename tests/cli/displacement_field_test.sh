#!/usr/bin/env bash
# `vpm render --out-displacement`: the field resamples the source into the
# deformed volume `--out-volume` writes, by an independent trilinear
# resampling in world LPS (tests/cli/resample_with_field.py), on the phantom
# (identity direction) and on the abdominal CT (LPS direction diag(-1, -1,
# 1), origin far from 0): a sign or frame error moves the kidney the wrong
# way and the mean difference grows to tens of HU.
set -euo pipefail
build=$1
source_dir=$2
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
vpm="$build/client/vpm"
check() {  # SOURCE GRAB... -- DRAG...: render, export, resample, compare
  local src=$1 name=$2
  shift 2
  "$vpm" volume export "$src" "$out/$name.nii" >/dev/null
  "$vpm" render --volume "$src" "$@" --size 64 64 --out "$out/$name.png" \
    --out-volume "$out/${name}_deformed.nii" --out-displacement "$out/$name.mha" >/dev/null
  python3 "$source_dir/tests/cli/resample_with_field.py" "$out/$name.nii" \
    "$out/${name}_deformed.nii" "$out/$name.mha" --max-mean 2.0
}
check "phantom:abdomen?size=48" phantom --grid 10 10 10 --grab-landmark left_renal_artery \
  --drag 0 0 12
check "$source_dir/tests/data/ct-abdomen-kidney/ct_abdomen.nii.gz" kidney --grab 79 -125.3 358.3 \
  --drag 0 0 15
# A name the writer does not know is refused with a clear error.
if "$vpm" render --volume "phantom:abdomen?size=48" --grid 10 10 10 --size 64 64 \
    --out "$out/x.png" --out-displacement "$out/field.vtk" 2>"$out/err"; then
  echo "--out-displacement field.vtk was accepted"; exit 1
fi
grep -q "write .mha or .nrrd" "$out/err" || { cat "$out/err"; exit 1; }
echo "displacement field: ok"
