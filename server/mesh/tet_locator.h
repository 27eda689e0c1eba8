// Point location in a tet mesh: which tet contains a point, and where in it.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include <glm/glm.hpp>

#include "server/common/status.h"

namespace vpm {

class TetLocator {
 public:
  struct Options {
    // A point belongs to a tet when all 4 barycentric weights are >= -eps
    // (dimensionless), so points on faces and at round-off distance outside
    // the hull are still found.
    double eps = 1e-9;
    // Average number of tets per bucket of the uniform grid.
    double tets_per_bucket = 1.0;
  };

  struct Location {
    int32_t tet = -1;                 // index into tets
    std::array<double, 4> weights{};  // barycentric, sum 1, weight c for tets[tet][c]
  };

  // positions  #V by 3, mm (rest or deformed)
  // tets       #T by 4 indices into positions
  // Fails on an index out of range or a non-finite position. Flat tets
  // (zero determinant) are kept in the numbering but never contain a point.
  static Result<TetLocator> Create(std::vector<glm::dvec3> positions,
                                   std::vector<std::array<int32_t, 4>> tets,
                                   const Options& options);
  static Result<TetLocator> Create(std::vector<glm::dvec3> positions,
                                   std::vector<std::array<int32_t, 4>> tets) {
    return Create(std::move(positions), std::move(tets), Options{});
  }

  // The tet containing p_mm (3, mm) with its barycentric weights; on shared
  // faces, edges and vertices the smallest tet index wins. nullopt outside
  // the mesh.
  std::optional<Location> Locate(const glm::dvec3& p_mm) const;

  // Barycentric weights of p_mm in tet `tet` (any point, inside or not); all
  // NaN for a flat tet.
  std::array<double, 4> Barycentric(int32_t tet, const glm::dvec3& p_mm) const;

  const std::vector<glm::dvec3>& positions() const { return positions_; }
  const std::vector<std::array<int32_t, 4>>& tets() const { return tets_; }

 private:
  TetLocator() = default;
  void PrepareTets();  // inverse_, flat_, and the tets' bounding box
  void SizeGrid();     // margin, buckets_, bucket_mm_
  void FillBuckets();  // bucket_begin_, bucket_tets_
  int64_t BucketOf(const glm::dvec3& p_mm) const;

  Options options_;
  std::vector<glm::dvec3> positions_;
  std::vector<std::array<int32_t, 4>> tets_;
  std::vector<glm::dmat3> inverse_;  // per tet: inverse of [p1-p0, p2-p0, p3-p0]
  std::vector<uint8_t> flat_;        // per tet: 1 if the matrix is singular
  glm::dvec3 lo_mm_{0.0};            // grid corner (mm)
  glm::dvec3 hi_mm_{0.0};
  double margin_mm_ = 0.0;  // tet boxes widened by this (mm)
  double bucket_mm_ = 1.0;  // bucket edge (mm)
  std::array<int64_t, 3> buckets_{1, 1, 1};
  std::vector<int64_t> bucket_begin_;  // CSR offsets, #buckets + 1
  std::vector<int32_t> bucket_tets_;   // ascending tet indices per bucket
};

}  // namespace vpm
