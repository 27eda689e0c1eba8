#include "server/mesh/sliver_steiner_points.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <utility>
#include <vector>

#include "server/mesh/steiner_point.h"
#include "server/mesh/tet_quality.h"
#include "server/mesh/tetrahedralize.h"

namespace vpm {
namespace {

using Tet = std::array<int32_t, 4>;

// Circumcentre of (a, b, c, d), mm; nullopt for a flat tet.
std::optional<glm::dvec3> Circumcentre(const glm::dvec3& a, const glm::dvec3& b,
                                       const glm::dvec3& c, const glm::dvec3& d) {
  const glm::dvec3 u = b - a, v = c - a, w = d - a;
  const double det = glm::dot(u, glm::cross(v, w));
  if (!(std::abs(det) > 0.0)) return std::nullopt;
  const glm::dvec3 offset = (glm::dot(u, u) * glm::cross(v, w) + glm::dot(v, v) * glm::cross(w, u) +
                             glm::dot(w, w) * glm::cross(u, v)) /
                            (2.0 * det);
  const glm::dvec3 centre = a + offset;
  if (!std::isfinite(centre.x) || !std::isfinite(centre.y) || !std::isfinite(centre.z)) {
    return std::nullopt;
  }
  return centre;
}

// The tets under the target, worst first (ties: tet order), with their
// smallest dihedral angle.
std::vector<std::pair<double, size_t>> BadTets(const std::vector<glm::dvec3>& p,
                                               const std::vector<Tet>& tets, double target_deg) {
  std::vector<std::pair<double, size_t>> bad;
  for (size_t t = 0; t < tets.size(); ++t) {
    const Tet& k = tets[t];
    const double angle = MinDihedralAngleDeg(p[k[0]], p[k[1]], p[k[2]], p[k[3]]);
    if (angle < target_deg) bad.emplace_back(angle, t);
  }
  std::sort(bad.begin(), bad.end());
  return bad;
}

// One round's new points: per bad tet, its circumcentre (snapped into the
// box, so a tet at a face gets a point on that face) or else its centroid,
// whichever is first at least min_spacing from every vertex and every point
// taken before it this round.
std::vector<glm::dvec3> RoundCandidates(const std::vector<glm::dvec3>& p,
                                        const std::vector<Tet>& tets,
                                        const std::vector<std::pair<double, size_t>>& bad,
                                        const glm::dvec3& extent, double min_spacing) {
  std::vector<glm::dvec3> taken;
  for (const auto& [angle, t] : bad) {
    const Tet& k = tets[t];
    std::vector<glm::dvec3> tries;
    if (auto c = Circumcentre(p[k[0]], p[k[1]], p[k[2]], p[k[3]])) {
      tries.push_back(SnapToBox(*c, extent, min_spacing));
    }
    tries.push_back(SnapToBox(0.25 * (p[k[0]] + p[k[1]] + p[k[2]] + p[k[3]]), extent, min_spacing));
    for (const glm::dvec3& candidate : tries) {
      if (NearestDistance(p, candidate) >= min_spacing &&
          NearestDistance(taken, candidate) >= min_spacing) {
        taken.push_back(candidate);
        break;
      }
    }
  }
  return taken;
}

}  // namespace

Result<SteinerStats> AddSliverSteinerPoints(ProxyMesh& mesh, const VolumeGeometry& geometry,
                                            const SteinerParams& params,
                                            const CancelToken& cancel) {
  if (!(params.min_spacing_mm > 0.0) || !(params.target_min_dihedral_deg > 0.0) ||
      params.max_rounds < 0) {
    return absl::InvalidArgumentError(
        "AddSliverSteinerPoints: min spacing and target angle must be > 0, rounds >= 0");
  }
  const glm::dvec3 extent = geometry.extent_mm();
  SteinerStats stats;
  stats.min_dihedral_before_deg = mesh.quality.min_dihedral_deg;
  for (int round = 0; round < params.max_rounds; ++round) {
    RETURN_IF_ERROR(cancel.Check());
    std::vector<glm::dvec3> p(mesh.vertices.size());
    for (size_t v = 0; v < p.size(); ++v) p[v] = mesh.vertices[v].position_mm;
    const auto bad = BadTets(p, mesh.tets, params.target_min_dihedral_deg);
    if (bad.empty()) break;
    const std::vector<glm::dvec3> added =
        RoundCandidates(p, mesh.tets, bad, extent, params.min_spacing_mm);
    if (added.empty()) break;
    AppendSteinerVertices(mesh, geometry, added);
    RETURN_IF_ERROR(Tetrahedralize(mesh, extent, cancel));
    stats.added += static_cast<int64_t>(added.size());
    stats.rounds = round + 1;
  }
  stats.min_dihedral_after_deg = mesh.quality.min_dihedral_deg;
  return stats;
}

}  // namespace vpm
