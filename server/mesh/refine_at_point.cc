#include "server/mesh/refine_at_point.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "server/mesh/point_grid.h"

namespace vpm {
namespace {

Status CheckParams(const VolumeGeometry& g, const RefineParams& p) {
  const glm::dvec3 extent = g.extent_mm();
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(p.point_mm[a])) {
      return absl::InvalidArgumentError("manipulation point has a non-finite coordinate");
    }
    if (p.point_mm[a] < 0.0 || p.point_mm[a] > extent[a]) {
      return absl::OutOfRangeError(
          StrCat("manipulation point (", p.point_mm.x, ", ", p.point_mm.y, ", ", p.point_mm.z,
                 ") mm is outside the image box (0..", extent.x, ", 0..", extent.y, ", 0..",
                 extent.z, ") mm"));
    }
  }
  if (!(p.roi_radius_mm > 0.0) || !std::isfinite(p.roi_radius_mm)) {
    return absl::InvalidArgumentError(StrCat("roi radius ", p.roi_radius_mm, " mm must be > 0"));
  }
  if (p.refine_count < 0) return absl::InvalidArgumentError("refine count must be >= 0");
  return absl::OkStatus();
}

// Fine lattice ids whose position lies in the ball, ascending.
std::vector<int64_t> CandidatesInBall(const Lattice& fine, const glm::dvec3& m, double radius) {
  const glm::dvec3 step = fine.step_mm();
  const auto& g = fine.grid();
  std::array<int64_t, 2> range[3];
  for (int a = 0; a < 3; ++a) {
    // Position of coord c is (c + 0.5) * step - 0.5 * s; bound c generously.
    const double s = fine.geometry().spacing_mm[a];
    const double lo = (m[a] - radius + 0.5 * s) / step[a] - 0.5;
    const double hi = (m[a] + radius + 0.5 * s) / step[a] - 0.5;
    range[a] = {std::max<int64_t>(0, static_cast<int64_t>(std::floor(lo)) - 1),
                std::min<int64_t>(g[a] - 1, static_cast<int64_t>(std::ceil(hi)) + 1)};
  }
  std::vector<int64_t> ids;
  for (int64_t c = range[2][0]; c <= range[2][1]; ++c)
    for (int64_t b = range[1][0]; b <= range[1][1]; ++b)
      for (int64_t a = range[0][0]; a <= range[0][1]; ++a) {
        const int64_t id = fine.Id(a, b, c);
        if (PointDistance(fine.Position(id), m) <= radius) ids.push_back(id);
      }
  std::sort(ids.begin(), ids.end());
  return ids;
}

}  // namespace

Result<std::vector<MeshVertex>> RefineAtPoint(const Volume& volume, const Lattice& coarse,
                                              const TransferFunction& tf, double g_max,
                                              const std::vector<MeshVertex>& existing,
                                              const RefineParams& params) {
  RETURN_IF_ERROR(CheckParams(volume.geometry(), params));
  const auto& g = coarse.grid();
  // Three times the coarse lattice, but no finer than the voxels along an
  // axis (a stack of fewer than 3 G slices: thick-slice CT, most MR series).
  const auto& dims = volume.dims();
  auto fine_or = Lattice::Create(
      volume.geometry(),
      {std::min(3 * g[0], dims[0]), std::min(3 * g[1], dims[1]), std::min(3 * g[2], dims[2])});
  if (!fine_or.ok()) {
    return absl::InvalidArgumentError(
        StrCat("refinement needs a lattice 3x finer than G: ", fine_or.status().message()));
  }
  const Lattice& fine = *fine_or;
  const std::vector<int64_t> ids = CandidatesInBall(fine, params.point_mm, params.roi_radius_mm);
  const LatticeCosts costs = EvaluateVertexCostsCpu(volume, fine, tf, ids);
  const auto& ci = costs.ci(params.footprint);
  const auto& gv = costs.g(params.footprint);
  std::vector<double> score(ids.size());
  for (size_t n = 0; n < ids.size(); ++n) score[n] = ci[n] * (g_max > 0.0 ? gv[n] / g_max : 0.0);
  std::vector<size_t> order(ids.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),  // ids ascending, so ties keep the smaller id
                   [&](size_t a, size_t b) { return score[a] > score[b]; });
  const double min_gap = coarse.h_mm() / 3.0;
  std::vector<glm::dvec3> taken;
  for (const auto& v : existing) taken.push_back(v.position_mm);
  std::vector<MeshVertex> accepted;
  for (size_t n : order) {
    if (static_cast<int64_t>(accepted.size()) >= params.refine_count) break;
    const glm::dvec3 p = fine.Position(ids[n]);
    const bool far = std::all_of(taken.begin(), taken.end(), [&](const glm::dvec3& q) {
      return PointDistance(p, q) >= min_gap;
    });
    if (!far) continue;
    taken.push_back(p);
    accepted.push_back({.position_mm = p,
                        .lattice_id = -1,
                        .kind = VertexKind::kRefined,
                        .voxel = fine.Voxel(ids[n]),
                        .cost = score[n]});
  }
  return accepted;
}

}  // namespace vpm
