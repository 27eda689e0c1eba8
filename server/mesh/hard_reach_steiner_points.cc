#include "server/mesh/hard_reach_steiner_points.h"

#include <algorithm>
#include <utility>
#include <vector>

#include "server/mesh/steiner_point.h"
#include "server/mesh/tetrahedralize.h"

namespace vpm {
namespace {

// An edge from a hard vertex to a non-hard one within the radius, longer
// than max_reach: its length and the point max_reach from the hard end.
struct LongEdge {
  double length_mm;
  glm::dvec3 point_mm;
};

// Every such edge once, longest first (ties: vertex indices); longest_mm:
// the longest hard-to-non-hard edge within the radius, however long.
std::vector<LongEdge> LongHardEdges(const ProxyMesh& mesh, const HardReachParams& params,
                                    double& longest_mm) {
  const double max_reach = params.max_reach_mm;
  std::vector<std::pair<int32_t, int32_t>> ends;
  std::vector<LongEdge> edges;
  longest_mm = 0.0;
  for (const auto& tet : mesh.tets) {
    for (int i = 0; i < 4; ++i) {
      for (int j = 0; j < 4; ++j) {
        const MeshVertex& a = mesh.vertices[tet[i]];
        const MeshVertex& b = mesh.vertices[tet[j]];
        if (!a.hard || b.hard) continue;
        if (glm::distance(b.position_mm, params.center_mm) > params.radius_mm) continue;
        const double length = glm::distance(a.position_mm, b.position_mm);
        longest_mm = std::max(longest_mm, length);
        if (length <= max_reach) continue;
        ends.emplace_back(tet[i], tet[j]);
        edges.push_back(
            {length, a.position_mm + (max_reach / length) * (b.position_mm - a.position_mm)});
      }
    }
  }
  // An edge is in several tets: keep one copy of each.
  std::vector<size_t> order(edges.size());
  for (size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::sort(order.begin(), order.end(), [&](size_t x, size_t y) {
    if (edges[x].length_mm != edges[y].length_mm) return edges[x].length_mm > edges[y].length_mm;
    return ends[x] < ends[y];
  });
  std::vector<LongEdge> unique;
  for (size_t k = 0; k < order.size(); ++k) {
    if (k > 0 && ends[order[k]] == ends[order[k - 1]]) continue;
    unique.push_back(edges[order[k]]);
  }
  return unique;
}

}  // namespace

Result<HardReachStats> AddHardReachSteinerPoints(ProxyMesh& mesh, const Volume& volume, double R_mm,
                                                 const ClassifyParams& classify,
                                                 const HardReachParams& params,
                                                 const CancelToken& cancel) {
  if (!(params.max_reach_mm > 0.0) || !(params.min_spacing_mm > 0.0) || params.max_rounds < 0) {
    return absl::InvalidArgumentError(
        "AddHardReachSteinerPoints: max reach and min spacing must be > 0, rounds >= 0");
  }
  const VolumeGeometry& geometry = volume.geometry();
  const glm::dvec3 extent = geometry.extent_mm();
  HardReachStats stats;
  RETURN_IF_ERROR(ClassifyHardness(volume, R_mm, classify, mesh.vertices));
  for (int round = 0;; ++round) {
    RETURN_IF_ERROR(cancel.Check());
    double longest = 0.0;
    const std::vector<LongEdge> edges = LongHardEdges(mesh, params, longest);
    if (round == 0) stats.longest_before_mm = longest;
    stats.longest_after_mm = longest;
    if (edges.empty() || round == params.max_rounds) break;
    std::vector<glm::dvec3> existing(mesh.vertices.size());
    for (size_t v = 0; v < existing.size(); ++v) existing[v] = mesh.vertices[v].position_mm;
    std::vector<glm::dvec3> taken;
    for (const LongEdge& edge : edges) {
      const glm::dvec3 q = SnapToBox(edge.point_mm, extent, params.min_spacing_mm);
      if (NearestDistance(existing, q) >= params.min_spacing_mm &&
          NearestDistance(taken, q) >= params.min_spacing_mm) {
        taken.push_back(q);
      }
    }
    if (taken.empty()) break;
    AppendSteinerVertices(mesh, geometry, taken);
    RETURN_IF_ERROR(Tetrahedralize(mesh, extent, cancel));
    RETURN_IF_ERROR(ClassifyHardness(volume, R_mm, classify, mesh.vertices));
    stats.added += static_cast<int64_t>(taken.size());
    stats.rounds = round + 1;
  }
  return stats;
}

}  // namespace vpm
