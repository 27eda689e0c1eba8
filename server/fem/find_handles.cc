#include "server/fem/find_handles.h"

#include <algorithm>
#include <cmath>

namespace vpm {
namespace {

constexpr double kInBoxRelative = 1e-6;

Status CheckGrab(const glm::dvec3& box_extent_mm, const glm::dvec3& point_mm, double radius_mm) {
  if (!std::isfinite(point_mm.x) || !std::isfinite(point_mm.y) || !std::isfinite(point_mm.z)) {
    return absl::InvalidArgumentError("grab point must be finite");
  }
  if (!std::isfinite(radius_mm) || !(radius_mm > 0.0)) {
    return absl::InvalidArgumentError(
        StrCat("grab radius must be finite and > 0 mm, got ", radius_mm));
  }
  for (int i = 0; i < 3; ++i) {
    const double slack = kInBoxRelative * box_extent_mm[i];
    if (point_mm[i] < -slack || point_mm[i] > box_extent_mm[i] + slack) {
      return absl::OutOfRangeError(StrCat("grab point (", point_mm.x, ", ", point_mm.y, ", ",
                                          point_mm.z, ") mm is outside the image box [0, (",
                                          box_extent_mm.x, ", ", box_extent_mm.y, ", ",
                                          box_extent_mm.z, ")] mm"));
    }
  }
  return absl::OkStatus();
}

// The grab within the radius: the handles, plus the deformable vertex
// nearest the point even where it lies next to a fixed one, and the
// message that says what was left in place.
GrabInfo GrabWithin(GrabInfo info, int32_t nearest, double radius_mm) {
  if (!std::binary_search(info.handles.begin(), info.handles.end(), nearest)) {
    info.handles.insert(std::lower_bound(info.handles.begin(), info.handles.end(), nearest),
                        nearest);
    --info.left_free_next_to_fixed;
  }
  info.message = StrCat("grabbed ", info.handles.size(), " vertices within ", radius_mm, " mm");
  if (info.fixed_within > 0) {
    info.message +=
        StrCat("; ", info.fixed_within, " fixed (hard) vertices within the radius stay in place");
  }
  if (info.left_free_next_to_fixed > 0) {
    info.message += StrCat("; ", info.left_free_next_to_fixed,
                           " deformable vertices next to them are left free, so that no tet "
                           "is crushed between a handle and a fixed vertex");
  }
  return info;
}

// No deformable vertex within the radius: the kNearestHandleCount nearest
// deformable ones (candidates: (distance, vertex), not empty).
GrabInfo GrabNearest(GrabInfo info, std::vector<std::pair<double, int32_t>> candidates,
                     double radius_mm) {
  const size_t count = std::min<size_t>(kNearestHandleCount, candidates.size());
  std::partial_sort(candidates.begin(), candidates.begin() + count, candidates.end());
  for (size_t i = 0; i < count; ++i) info.handles.push_back(candidates[i].second);
  std::sort(info.handles.begin(), info.handles.end());
  info.used_nearest = true;
  info.message =
      StrCat("no vertex within ", radius_mm, " mm; grabbed the ", count,
             " nearest deformable vertices (up to ", candidates[count - 1].first, " mm away)");
  return info;
}

}  // namespace

Result<GrabInfo> FindHandles(const std::vector<glm::dvec3>& positions_mm,
                             const std::vector<uint8_t>& deformable,
                             const std::vector<std::vector<int32_t>>& fixed_neighbours,
                             const glm::dvec3& box_extent_mm, const glm::dvec3& point_mm,
                             double radius_mm) {
  RETURN_IF_ERROR(CheckGrab(box_extent_mm, point_mm, radius_mm));
  if (deformable.size() != positions_mm.size()) {
    return absl::InvalidArgumentError("one deformable flag per vertex needed");
  }
  if (!fixed_neighbours.empty() && fixed_neighbours.size() != positions_mm.size()) {
    return absl::InvalidArgumentError("one fixed-neighbour list per vertex needed (or none)");
  }
  const auto next_to_fixed_within = [&](size_t v) {
    if (fixed_neighbours.empty()) return false;
    for (int32_t f : fixed_neighbours[v]) {
      if (f < 0 || static_cast<size_t>(f) >= positions_mm.size()) continue;
      if (glm::distance(positions_mm[f], point_mm) <= radius_mm) return true;
    }
    return false;
  };
  GrabInfo info;
  std::vector<std::pair<double, int32_t>> candidates;  // (distance, vertex), deformable only
  std::pair<double, int32_t> nearest_within{radius_mm, -1};
  for (size_t v = 0; v < positions_mm.size(); ++v) {
    const double distance = glm::distance(positions_mm[v], point_mm);
    const auto vertex = static_cast<int32_t>(v);
    if (deformable[v]) {
      candidates.emplace_back(distance, vertex);
      if (distance > radius_mm) continue;
      if (nearest_within.second < 0 || std::make_pair(distance, vertex) < nearest_within) {
        nearest_within = {distance, vertex};
      }
      if (next_to_fixed_within(v)) {
        ++info.left_free_next_to_fixed;
      } else {
        info.handles.push_back(vertex);
      }
    } else if (distance <= radius_mm) {
      ++info.fixed_within;
    }
  }
  if (nearest_within.second >= 0)
    return GrabWithin(std::move(info), nearest_within.second, radius_mm);
  if (info.fixed_within > 0) {
    return absl::FailedPreconditionError(
        StrCat("all ", info.fixed_within, " vertices within ", radius_mm,
               " mm of the grab point are fixed (hard tissue or box corners); grab deformable "
               "tissue or enlarge the radius"));
  }
  if (candidates.empty()) {
    return absl::FailedPreconditionError("the mesh has no deformable vertex to grab");
  }
  return GrabNearest(std::move(info), std::move(candidates), radius_mm);
}

}  // namespace vpm
