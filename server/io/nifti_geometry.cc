#include "server/io/nifti_geometry.h"

#include <cmath>

#include "server/io/nifti_c_api.h"

namespace vpm {
namespace {

// RAS <-> LPS: negate x and y. Its own inverse.
const glm::dmat3 kFlipXY(glm::dvec3(-1, 0, 0), glm::dvec3(0, -1, 0), glm::dvec3(0, 0, 1));

// Below this |det| of the normalised columns an sform is too sheared (axes
// less than about 30 degrees from parallel) for any orthonormal direction to
// stand for it; such a file is broken, not merely imprecise.
constexpr double kMinNormalisedDeterminant = 0.5;
// Normalised columns closer than this to orthonormal are taken as they are.
constexpr double kOrthonormalTolerance = 1e-6;

bool AllFinite(std::initializer_list<double> values) {
  for (double v : values) {
    if (!std::isfinite(v)) return false;
  }
  return true;
}

bool IsOrthonormal(const glm::dmat3& m, double tolerance) {
  const glm::dmat3 gram = glm::transpose(m) * m;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      if (std::abs(gram[c][r] - (r == c ? 1.0 : 0.0)) > tolerance) return false;
    }
  }
  return true;
}

glm::dmat3 NearestOrthonormal(const glm::dmat3& m) {
  nifti_dmat33 a;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) a.m[r][c] = m[c][r];
  }
  const nifti_dmat33 q = nifti_dmat33_polar(a);
  glm::dmat3 out;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) out[c][r] = q.m[r][c];
  }
  return out;
}

Status SformGeometry(const NiftiHeader& h, VolumeGeometry& g) {
  glm::dmat3 columns;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) {
      if (!std::isfinite(h.srow[r][c])) {
        return absl::InvalidArgumentError(StrCat("sform row ", r, " is not finite"));
      }
    }
    for (int c = 0; c < 3; ++c) columns[c][r] = h.srow[r][c];
  }
  for (int c = 0; c < 3; ++c) {
    const double norm = glm::length(columns[c]);
    if (!(norm > 0.0) || !std::isfinite(norm)) {
      return absl::InvalidArgumentError(
          StrCat("sform column ", c, " has length ", norm, "; the spacing must be positive"));
    }
    g.spacing_mm[c] = norm;
    columns[c] /= norm;
  }
  if (!IsOrthonormal(columns, kOrthonormalTolerance)) {
    if (std::abs(glm::determinant(columns)) < kMinNormalisedDeterminant) {
      return absl::InvalidArgumentError(
          "sform is degenerate or too sheared (axes nearly parallel)");
    }
    columns = NearestOrthonormal(columns);
  }
  g.direction = columns;
  g.origin_mm = glm::dvec3(h.srow[0][3], h.srow[1][3], h.srow[2][3]);
  return absl::OkStatus();
}

Status PixdimSpacing(const NiftiHeader& h, VolumeGeometry& g) {
  for (int a = 0; a < 3; ++a) {
    const double s = h.pixdim[a + 1];
    if (!std::isfinite(s) || s <= 0.0) {
      return absl::InvalidArgumentError(StrCat("pixdim[", a + 1, "] (spacing) is ", s,
                                                     "; it must be a positive finite number"));
    }
    g.spacing_mm[a] = s;
  }
  return absl::OkStatus();
}

Status QformGeometry(const NiftiHeader& h, VolumeGeometry& g) {
  RETURN_IF_ERROR(PixdimSpacing(h, g));
  const auto& q = h.quatern;
  const auto& t = h.qoffset;
  if (!AllFinite({q[0], q[1], q[2], t[0], t[1], t[2], h.pixdim[0]})) {
    return absl::InvalidArgumentError("qform quaternion or offset is not finite");
  }
  // The standard: qfac (pixdim[0]) is -1 or 1, and 0 means 1.
  const double qfac = h.pixdim[0] < 0.0 ? -1.0 : 1.0;
  const nifti_dmat44 m = nifti_quatern_to_dmat44(q[0], q[1], q[2], 0, 0, 0, 1, 1, 1, qfac);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) g.direction[c][r] = m.m[r][c];
  }
  g.origin_mm = glm::dvec3(t[0], t[1], t[2]);
  return absl::OkStatus();
}

}  // namespace

Result<VolumeGeometry> NiftiHeaderGeometry(const NiftiHeader& h) {
  VolumeGeometry g;
  g.dims = {h.dim[1], h.dim[2], h.dim[3]};
  if (h.sform_code > 0) {
    RETURN_IF_ERROR(SformGeometry(h, g));
  } else if (h.qform_code > 0) {
    RETURN_IF_ERROR(QformGeometry(h, g));
  } else {
    RETURN_IF_ERROR(PixdimSpacing(h, g));
    g.direction = glm::dmat3(1.0);
    g.origin_mm = glm::dvec3(0.0);
  }
  g.direction = kFlipXY * g.direction;
  g.origin_mm = kFlipXY * g.origin_mm;
  return g;
}

NiftiOrientation GeometryToNiftiOrientation(const VolumeGeometry& g) {
  const glm::dmat3 direction_ras = kFlipXY * g.direction;
  const glm::dvec3 origin_ras = kFlipXY * g.origin_mm;
  NiftiOrientation out;
  nifti_dmat44 affine{};
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) affine.m[r][c] = direction_ras[c][r] * g.spacing_mm[c];
    affine.m[r][3] = origin_ras[r];
    for (int c = 0; c < 4; ++c) out.srow[r][c] = affine.m[r][c];
  }
  affine.m[3][3] = 1.0;
  double dx = 0, dy = 0, dz = 0, qfac = 0;
  nifti_dmat44_to_quatern(affine, &out.quatern[0], &out.quatern[1], &out.quatern[2],
                          &out.qoffset[0], &out.qoffset[1], &out.qoffset[2], &dx, &dy, &dz, &qfac);
  out.pixdim = {qfac, g.spacing_mm.x, g.spacing_mm.y, g.spacing_mm.z};
  return out;
}

}  // namespace vpm
