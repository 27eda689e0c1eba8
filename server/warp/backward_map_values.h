// The backward map of docs/ALGORITHM.md section 7 on the host: its grid, its
// values, and the trilinear lookup the GPU's sampler performs
// (shaders/backward_map.glsl; docs/WARP.md).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

namespace vpm {

// Barycentric tolerance of the map: a point belongs to a deformed tet when
// its 4 weights are all >= -kBackwardMapEps (dimensionless). Large enough
// that float round-off keeps points on shared faces and on the hull inside,
// small enough to move nothing visibly (1e-5 of a tet's size).
inline constexpr double kBackwardMapEps = 1e-5;

// At most this many default map grid points per axis: the map follows the
// mesh (a lattice step h of extent / 20 by default), not the voxel count, so
// that a 512 x 512 x 900 CT's drags cost what the 256^3 phantom's do
// (docs/benchmarks/FULL_SIZE.md); 64 is the phantom's own.
inline constexpr int64_t kMaxDefaultMapPointsPerAxis = 64;

// The default map resolution: ceil(n / 4) grid points per axis, at least 2
// and at most kMaxDefaultMapPointsPerAxis.
std::array<int64_t, 3> DefaultBackwardMapDims(const std::array<int64_t, 3>& volume_dims);

struct BackwardMapValues {
  std::array<int64_t, 3> dims{0, 0, 0};  // M = (mx, my, mz) grid points, each >= 2
  glm::dvec3 extent_mm{0.0};             // the image box, (n - 1) * spacing
  // #mx*my*mz, x fastest (a + mx*(b + my*c)): (X(p) - p in mm, inside),
  // inside 1 when p lies in a deformed tet, else 0 with displacement 0.
  std::vector<glm::vec4> values;

  int64_t Index(int64_t a, int64_t b, int64_t c) const { return a + dims[0] * (b + dims[1] * c); }
  const glm::vec4& At(int64_t a, int64_t b, int64_t c) const { return values[Index(a, b, c)]; }
  // Grid step extent / (M - 1) (mm) and the position of point (a, b, c) (mm).
  glm::dvec3 StepMm() const;
  glm::dvec3 GridPointMm(int64_t a, int64_t b, int64_t c) const {
    return glm::dvec3(a, b, c) * StepMm();
  }
  // (X(p) - p, inside) at p_mm, trilinear between grid points, clamped to the
  // box: what backward_map_sample() returns (in double, without the
  // sampler's own rounding).
  glm::dvec4 Sample(const glm::dvec3& p_mm) const;
};

}  // namespace vpm
