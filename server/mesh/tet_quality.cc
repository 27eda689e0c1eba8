#include "server/mesh/tet_quality.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace vpm {

double SignedVolume(const glm::dvec3& p0, const glm::dvec3& p1, const glm::dvec3& p2,
                    const glm::dvec3& p3) {
  return glm::dot(glm::cross(p1 - p0, p2 - p0), p3 - p0) / 6.0;
}

double MinDihedralAngleDeg(const glm::dvec3& p0, const glm::dvec3& p1, const glm::dvec3& p2,
                           const glm::dvec3& p3) {
  const glm::dvec3 p[4] = {p0, p1, p2, p3};
  // Outward unit normal of the face opposite each vertex.
  glm::dvec3 normal[4];
  for (int v = 0; v < 4; ++v) {
    const glm::dvec3& a = p[(v + 1) % 4];
    const glm::dvec3& b = p[(v + 2) % 4];
    const glm::dvec3& c = p[(v + 3) % 4];
    glm::dvec3 n = glm::cross(b - a, c - a);
    const double length = glm::length(n);
    if (!(length > 0.0)) return 0.0;  // a face with no area: the tet is flat
    n /= length;
    if (glm::dot(n, p[v] - a) > 0.0) n = -n;
    normal[v] = n;
  }
  // The dihedral angle at the edge shared by the faces opposite u and w is
  // pi minus the angle between their outward normals.
  double smallest = 180.0;
  for (int u = 0; u < 4; ++u) {
    for (int w = u + 1; w < 4; ++w) {
      const double cosine = std::clamp(glm::dot(normal[u], normal[w]), -1.0, 1.0);
      const double angle = 180.0 - std::acos(cosine) * 180.0 / std::numbers::pi;
      smallest = std::min(smallest, angle);
    }
  }
  return smallest;
}

double RadiusRatio(const glm::dvec3& p0, const glm::dvec3& p1, const glm::dvec3& p2,
                   const glm::dvec3& p3) {
  const glm::dvec3 a = p1 - p0, b = p2 - p0, c = p3 - p0;
  const double det = glm::dot(a, glm::cross(b, c));  // 6 * volume
  if (!(det > 0.0)) return 0.0;
  const double area_sum =
      0.5 * (glm::length(glm::cross(a, b)) + glm::length(glm::cross(b, c)) +
             glm::length(glm::cross(c, a)) + glm::length(glm::cross(p2 - p1, p3 - p1)));
  const double inradius = 0.5 * det / area_sum;  // 3 V / A with V = det / 6
  const glm::dvec3 centre_offset =
      (glm::dot(a, a) * glm::cross(b, c) + glm::dot(b, b) * glm::cross(c, a) +
       glm::dot(c, c) * glm::cross(a, b)) /
      (2.0 * det);
  const double circumradius = glm::length(centre_offset);
  return 3.0 * inradius / circumradius;
}

TetQuality MeasureTetQuality(const ProxyMesh& mesh) {
  TetQuality q;
  if (mesh.tets.empty()) return q;
  q.min_dihedral_deg = 180.0;
  q.min_radius_ratio = 1.0;
  double dihedral_sum = 0.0, ratio_sum = 0.0;
  for (const auto& t : mesh.tets) {
    const glm::dvec3& p0 = mesh.vertices[t[0]].position_mm;
    const glm::dvec3& p1 = mesh.vertices[t[1]].position_mm;
    const glm::dvec3& p2 = mesh.vertices[t[2]].position_mm;
    const glm::dvec3& p3 = mesh.vertices[t[3]].position_mm;
    const double dihedral = MinDihedralAngleDeg(p0, p1, p2, p3);
    const double ratio = RadiusRatio(p0, p1, p2, p3);
    q.min_dihedral_deg = std::min(q.min_dihedral_deg, dihedral);
    q.min_radius_ratio = std::min(q.min_radius_ratio, ratio);
    dihedral_sum += dihedral;
    ratio_sum += ratio;
  }
  const double count = static_cast<double>(mesh.tets.size());
  q.mean_min_dihedral_deg = dihedral_sum / count;
  q.mean_radius_ratio = ratio_sum / count;
  return q;
}

int64_t CountInvertedTets(const std::vector<glm::dvec3>& positions,
                          const std::vector<std::array<int32_t, 4>>& tets) {
  int64_t inverted = 0;
  for (const auto& t : tets) {
    if (SignedVolume(positions[t[0]], positions[t[1]], positions[t[2]], positions[t[3]]) <= 0.0) {
      ++inverted;
    }
  }
  return inverted;
}

}  // namespace vpm
