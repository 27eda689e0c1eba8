// NIfTI orientation <-> the volume's LPS geometry.
//
// NIfTI world space is RAS+ (+x = subject's Right, +y = Anterior,
// +z = Superior); this project's world space is LPS+ (DICOM, ITK): +x = Left,
// +y = Posterior. Converting between them negates the x and y rows of the
// affine (directions and origin alike).
#pragma once

#include <array>

#include "server/common/status.h"
#include "server/io/nifti_header.h"
#include "server/volume/volume.h"

namespace vpm {

// Geometry (dims, spacing_mm, origin_mm and direction, LPS) of a parsed
// header, by the standard's precedence:
//  1. sform_code > 0: the srow affine. Spacing = the column norms; direction
//     = the normalised columns. A sheared affine (columns not perpendicular)
//     has no exact spacing + rotation form: the direction becomes the nearest
//     orthonormal matrix (polar decomposition), spacing stays the column
//     norms. Degenerate affines (a zero or dependent column) are rejected.
//  2. qform_code > 0: the quaternion, qfac = pixdim[0], spacing = pixdim[1..3].
//  3. neither: spacing = pixdim[1..3], RAS axes, origin 0 (as nifti_clib).
// Rejects non-finite values and non-positive pixdim where pixdim is used.
Result<VolumeGeometry> NiftiHeaderGeometry(const NiftiHeader& header);

// The orientation fields a writer stores for `geometry`, in RAS.
struct NiftiOrientation {
  std::array<double, 4> pixdim{};   // qfac, dx, dy, dz
  std::array<double, 3> quatern{};  // b, c, d
  std::array<double, 3> qoffset{};  // x, y, z
  std::array<std::array<double, 4>, 3> srow{};
};
NiftiOrientation GeometryToNiftiOrientation(const VolumeGeometry& geometry);

}  // namespace vpm
