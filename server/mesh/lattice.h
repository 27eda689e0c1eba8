// The regular lattice of docs/ALGORITHM.md section 1 over a volume.
//
// Vertex (a,b,c), linear id a + Gx*(b + Gy*c), owns the cell of voxels
// i in [floor(a*nx/Gx), floor((a+1)*nx/Gx)) (likewise j, k); its position is
// the centre of its cell, p = ((a+0.5)*nx/Gx - 0.5) * sx (mm, physical voxel
// space); voxel(v) is the voxel nearest to p, round half up, clamped, which
// in exact integer arithmetic is floor((2a+1)*nx / (2*Gx)).
#pragma once

#include <array>
#include <cstdint>

#include <glm/glm.hpp>

#include "server/common/status.h"
#include "server/volume/volume.h"

namespace vpm {

class Lattice {
 public:
  // Each G component in 1..n along its axis (every cell holds a voxel).
  static Result<Lattice> Create(const VolumeGeometry& geometry, std::array<int64_t, 3> grid);

  const std::array<int64_t, 3>& grid() const { return grid_; }
  int64_t size() const { return grid_[0] * grid_[1] * grid_[2]; }
  std::array<int64_t, 3> Coords(int64_t id) const {
    return {id % grid_[0], (id / grid_[0]) % grid_[1], id / (grid_[0] * grid_[1])};
  }
  int64_t Id(int64_t a, int64_t b, int64_t c) const { return a + grid_[0] * (b + grid_[1] * c); }

  glm::dvec3 Position(int64_t id) const;            // mm, physical voxel space
  std::array<int64_t, 3> Voxel(int64_t id) const;   // nearest voxel index
  // Half-open voxel range of the vertex's cell along `axis`.
  std::array<int64_t, 2> CellRange(int axis, int64_t coord) const;
  // Lattice step along each axis (mm): n*s/G.
  glm::dvec3 step_mm() const;
  // h = the largest lattice step (mm).
  double h_mm() const;
  const VolumeGeometry& geometry() const { return geometry_; }

 private:
  Lattice(const VolumeGeometry& geometry, std::array<int64_t, 3> grid)
      : geometry_(geometry), grid_(grid) {}
  VolumeGeometry geometry_;
  std::array<int64_t, 3> grid_;
};

// Nearest voxel to a point (mm): round half up of p/s per axis, clamped.
std::array<int64_t, 3> NearestVoxel(const VolumeGeometry& geometry, const glm::dvec3& p_mm);

}  // namespace vpm
