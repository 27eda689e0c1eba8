#include "server/mesh/lattice.h"

#include <algorithm>
#include <cmath>

namespace vpm {

Result<Lattice> Lattice::Create(const VolumeGeometry& geometry, std::array<int64_t, 3> grid) {
  static constexpr const char* kAxis[3] = {"x", "y", "z"};
  for (int a = 0; a < 3; ++a) {
    if (grid[a] < 1 || grid[a] > geometry.dims[a]) {
      return absl::InvalidArgumentError(
          StrCat("grid ", kAxis[a], " is ", grid[a], "; it must be in 1..", geometry.dims[a],
                 " (the volume's voxels along ", kAxis[a], ") so that every cell holds a voxel"));
    }
  }
  return Lattice(geometry, grid);
}

glm::dvec3 Lattice::Position(int64_t id) const {
  const auto c = Coords(id);
  glm::dvec3 p;
  for (int a = 0; a < 3; ++a) {
    p[a] = ((static_cast<double>(c[a]) + 0.5) * static_cast<double>(geometry_.dims[a]) /
                static_cast<double>(grid_[a]) -
            0.5) *
           geometry_.spacing_mm[a];
  }
  return p;
}

std::array<int64_t, 3> Lattice::Voxel(int64_t id) const {
  const auto c = Coords(id);
  std::array<int64_t, 3> v;
  for (int a = 0; a < 3; ++a) {
    v[a] = std::clamp<int64_t>((2 * c[a] + 1) * geometry_.dims[a] / (2 * grid_[a]), 0,
                               geometry_.dims[a] - 1);
  }
  return v;
}

std::array<int64_t, 2> Lattice::CellRange(int axis, int64_t coord) const {
  const int64_t n = geometry_.dims[axis], g = grid_[axis];
  return {coord * n / g, (coord + 1) * n / g};
}

glm::dvec3 Lattice::step_mm() const {
  glm::dvec3 s;
  for (int a = 0; a < 3; ++a) {
    s[a] = static_cast<double>(geometry_.dims[a]) * geometry_.spacing_mm[a] /
           static_cast<double>(grid_[a]);
  }
  return s;
}

double Lattice::h_mm() const {
  const glm::dvec3 s = step_mm();
  return std::max({s.x, s.y, s.z});
}

std::array<int64_t, 3> NearestVoxel(const VolumeGeometry& geometry, const glm::dvec3& p_mm) {
  std::array<int64_t, 3> v;
  for (int a = 0; a < 3; ++a) {
    double index = std::floor(p_mm[a] / geometry.spacing_mm[a] + 0.5);
    if (!std::isfinite(index)) index = 0.0;  // callers reject non-finite points first
    v[a] = static_cast<int64_t>(
        std::clamp(index, 0.0, static_cast<double>(geometry.dims[a] - 1)));
  }
  return v;
}

}  // namespace vpm
