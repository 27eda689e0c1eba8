#include "server/measures/largest_empty_sphere.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "server/volume/sample_trilinear.h"
#include "server/measures/tf_positive_set.h"

namespace vpm {
namespace {

// Nearest-vertex queries on a uniform grid of about one vertex per cell.
class NearestVertexGrid {
 public:
  NearestVertexGrid(const std::vector<glm::dvec3>& points, glm::dvec3 lo, glm::dvec3 hi)
      : points_(points), lo_(lo) {
    const glm::dvec3 span = glm::max(hi - lo, glm::dvec3(1e-300));
    const double largest = std::max({span.x, span.y, span.z});
    cell_ = std::max(std::cbrt(span.x * span.y * span.z / std::max<size_t>(points.size(), 1)),
                     largest / 256.0);
    for (int a = 0; a < 3; ++a) {
      cells_[a] = std::max<int64_t>(1, static_cast<int64_t>(std::ceil(span[a] / cell_)));
    }
    begin_.assign(cells_[0] * cells_[1] * cells_[2] + 1, 0);
    for (const glm::dvec3& p : points) ++begin_[CellOf(p) + 1];
    for (size_t c = 1; c < begin_.size(); ++c) begin_[c] += begin_[c - 1];
    items_.resize(points.size());
    std::vector<int64_t> cursor(begin_.begin(), begin_.end() - 1);
    for (size_t v = 0; v < points.size(); ++v) items_[cursor[CellOf(points[v])]++] = v;
  }

  // Distance (mm) from x to the nearest point; shells of cells grow until
  // no unvisited cell can hold a closer point.
  double Distance(const glm::dvec3& x) const {
    int64_t c[3];
    for (int a = 0; a < 3; ++a) c[a] = Coordinate(x[a], a);
    double best = std::numeric_limits<double>::infinity();
    const int64_t max_ring = std::max({cells_[0], cells_[1], cells_[2]});
    for (int64_t ring = 0; ring <= max_ring; ++ring) {
      // Points in ring r are at least (r - 1) cells away from x.
      if (ring >= 1 && static_cast<double>(ring - 1) * cell_ > best) break;
      for (int64_t k = c[2] - ring; k <= c[2] + ring; ++k) {
        for (int64_t j = c[1] - ring; j <= c[1] + ring; ++j) {
          for (int64_t i = c[0] - ring; i <= c[0] + ring; ++i) {
            const bool on_shell =
                std::max({std::abs(i - c[0]), std::abs(j - c[1]), std::abs(k - c[2])}) == ring;
            if (!on_shell || i < 0 || j < 0 || k < 0 || i >= cells_[0] || j >= cells_[1] ||
                k >= cells_[2]) {
              continue;
            }
            const int64_t cell = i + cells_[0] * (j + cells_[1] * k);
            for (int64_t n = begin_[cell]; n < begin_[cell + 1]; ++n) {
              best = std::min(best, glm::distance(x, points_[items_[n]]));
            }
          }
        }
      }
    }
    return best;
  }

 private:
  int64_t Coordinate(double x, int axis) const {
    const double c = std::floor((x - lo_[axis]) / cell_);
    return static_cast<int64_t>(std::clamp(c, 0.0, static_cast<double>(cells_[axis] - 1)));
  }
  int64_t CellOf(const glm::dvec3& p) const {
    return Coordinate(p.x, 0) + cells_[0] * (Coordinate(p.y, 1) + cells_[1] * Coordinate(p.z, 2));
  }

  const std::vector<glm::dvec3>& points_;
  glm::dvec3 lo_;
  double cell_ = 1.0;
  int64_t cells_[3] = {1, 1, 1};
  std::vector<int64_t> begin_;
  std::vector<size_t> items_;
};

// Circumcentre of a tet (mm); false for a flat one.
bool Circumcentre(const glm::dvec3& p0, const glm::dvec3& p1, const glm::dvec3& p2,
                  const glm::dvec3& p3, glm::dvec3& centre) {
  const glm::dvec3 a = p1 - p0, b = p2 - p0, c = p3 - p0;
  const double det = glm::dot(a, glm::cross(b, c));
  if (det == 0.0 || !std::isfinite(det)) return false;
  centre = p0 + (glm::dot(a, a) * glm::cross(b, c) + glm::dot(b, b) * glm::cross(c, a) +
                 glm::dot(c, c) * glm::cross(a, b)) /
                    (2.0 * det);
  return true;
}

// Every stride-th voxel centre per axis (the last index too) with TF > 0.
void AddVoxelSamples(const Volume& volume, const TfPositiveSet& tf_positive,
                     const NearestVertexGrid& nearest, int64_t stride, EmptySphere& best) {
  const auto& dims = volume.dims();
  auto next = [stride](int64_t i, int64_t n) {
    return i + 1 == n ? n : std::min(i + stride, n - 1);
  };
  for (int64_t k = 0; k < dims[2]; k = next(k, dims[2])) {
    for (int64_t j = 0; j < dims[1]; j = next(j, dims[1])) {
      for (int64_t i = 0; i < dims[0]; i = next(i, dims[0])) {
        if (!tf_positive.Contains(volume.At(i, j, k))) continue;
        ++best.samples_in_body;
        const glm::dvec3 x = volume.geometry().IndexToPhysical(glm::dvec3(i, j, k));
        const double radius = nearest.Distance(x);
        if (radius > best.radius_mm) {
          best.radius_mm = radius;
          best.centre_mm = x;
          best.centre_is_sample = true;
        }
      }
    }
  }
}

}  // namespace

Result<EmptySphere> LargestEmptySphere(const ProxyMesh& mesh, const Volume& volume,
                                       const TransferFunction& tf,
                                       const LargestEmptySphereOptions& options) {
  if (mesh.vertices.empty()) {
    return absl::InvalidArgumentError("LargestEmptySphere: the mesh has no vertices");
  }
  if (options.voxel_stride < 0) {
    return absl::InvalidArgumentError("LargestEmptySphere: voxel_stride must be >= 0");
  }
  std::vector<glm::dvec3> positions(mesh.vertices.size());
  for (size_t v = 0; v < positions.size(); ++v) positions[v] = mesh.vertices[v].position_mm;
  for (const auto& t : mesh.tets) {
    for (int32_t v : t) {
      if (v < 0 || static_cast<size_t>(v) >= positions.size()) {
        return absl::InvalidArgumentError(
            StrCat("LargestEmptySphere: vertex index ", v, " out of range"));
      }
    }
  }
  const glm::dvec3 extent = volume.geometry().extent_mm();
  glm::dvec3 lo = glm::min(glm::dvec3(0.0), positions[0]), hi = glm::max(extent, positions[0]);
  for (const glm::dvec3& p : positions) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  const NearestVertexGrid nearest(positions, lo, hi);
  const TfPositiveSet tf_positive(tf);
  const double slack = 1e-9 * glm::length(extent);
  auto in_body = [&](const glm::dvec3& x) {
    for (int a = 0; a < 3; ++a) {
      if (!(x[a] >= -slack && x[a] <= extent[a] + slack)) return false;
    }
    return tf_positive.Contains(SampleTrilinear(volume, x));
  };

  EmptySphere best;
  for (const auto& t : mesh.tets) {
    glm::dvec3 centre;
    if (!Circumcentre(positions[t[0]], positions[t[1]], positions[t[2]], positions[t[3]], centre) ||
        !in_body(centre)) {
      continue;
    }
    ++best.circumcentres_in_body;
    const double radius = nearest.Distance(centre);
    if (radius > best.radius_mm) {
      best.radius_mm = radius;
      best.centre_mm = centre;
    }
  }
  if (options.voxel_stride > 0) {
    AddVoxelSamples(volume, tf_positive, nearest, options.voxel_stride, best);
  }
  return best;
}

}  // namespace vpm
