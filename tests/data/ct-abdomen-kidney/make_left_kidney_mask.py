#!/usr/bin/python3
"""Writes left_kidney_mask.nii.gz, the left kidney of ct_abdomen.nii.gz, once.

Region growing with SciPy (Debian's python3-scipy and python3-nibabel, not
needed by vpm itself): from a parenchyma voxel of the left kidney, the
face-connected voxels within +-36 HU of the seed's 3x3x3 median and within
80 mm of the seed, then a one-voxel opening that cuts the bridges into the
psoas and the spleen, keeping the component of the seed. The result (about
124 cm^3, parenchyma; the renal sinus and the stones are outside it) was
checked by eye on axial, coronal and sagittal slices. Independent of vpm's
own region growing (server/volume/organ_region.cc), which the organ-grab
test compares against it.
"""
import sys

import nibabel as nib
import numpy as np
from scipy import ndimage as ndi

SEED = (31, 38, 87)  # voxel indices: world LPS (85, -125, 355) mm
WINDOW_HU = 36.0
BOUND_MM = 80.0

img = nib.load("ct_abdomen.nii.gz")
a = img.get_fdata()
i, j, k = SEED
reference = np.median(a[i - 1:i + 2, j - 1:j + 2, k - 1:k + 2])
spacing = np.abs(np.diag(img.affine)[:3])
I, J, K = np.indices(a.shape)
distance = np.sqrt(((I - i) * spacing[0]) ** 2 + ((J - j) * spacing[1]) ** 2 +
                   ((K - k) * spacing[2]) ** 2)
allowed = (np.abs(a - reference) <= WINDOW_HU) & (distance <= BOUND_MM)
labels, _ = ndi.label(allowed)
grown = labels == labels[SEED]
face = ndi.generate_binary_structure(3, 1)
core_labels, _ = ndi.label(ndi.binary_erosion(grown, face))
core = core_labels == core_labels[SEED]
mask = ndi.binary_dilation(core, face) & grown
out = nib.Nifti1Image(mask.astype(np.uint8), img.affine)
out.header.set_xyzt_units("mm")
nib.save(out, "left_kidney_mask.nii.gz")
print(f"{int(mask.sum())} voxels, {mask.sum() * np.prod(spacing) / 1000:.1f} cm^3", file=sys.stderr)
