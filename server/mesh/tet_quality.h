// Tet shape measures (docs/ALGORITHM.md section 5) and the section-6 validity
// measure (no inverted tet).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "server/mesh/proxy_mesh.h"

namespace vpm {

// Signed volume of the tet (p0, p1, p2, p3), all in mm:
// det[p1-p0, p2-p0, p3-p0] / 6, mm^3; positive when p3 lies on the side of
// the plane (p0, p1, p2) that (p1-p0) x (p2-p0) points to.
double SignedVolume(const glm::dvec3& p0, const glm::dvec3& p1, const glm::dvec3& p2,
                    const glm::dvec3& p3);

// Smallest of the 6 dihedral angles of the tet, degrees in [0, 180);
// 70.5288 (acos 1/3) for the regular tet, 0 for a flat one.
double MinDihedralAngleDeg(const glm::dvec3& p0, const glm::dvec3& p1, const glm::dvec3& p2,
                           const glm::dvec3& p3);

// 3 * inradius / circumradius, dimensionless: 1 for the regular tet, -> 0
// as the tet degenerates, 0 for a flat or inverted one.
double RadiusRatio(const glm::dvec3& p0, const glm::dvec3& p1, const glm::dvec3& p2,
                   const glm::dvec3& p3);

// Min and mean over mesh.tets of MinDihedralAngleDeg and RadiusRatio;
// all zero when there are no tets. removed_zero_volume is left 0 (the
// tetrahedralization fills it).
TetQuality MeasureTetQuality(const ProxyMesh& mesh);

// Number of tets with signed volume <= 0 (section 6 "Validity", applied to
// deformed positions after FEM).
//   positions  #V by 3, mm
//   tets       #T by 4 indices into positions
int64_t CountInvertedTets(const std::vector<glm::dvec3>& positions,
                          const std::vector<std::array<int32_t, 4>>& tets);

}  // namespace vpm
