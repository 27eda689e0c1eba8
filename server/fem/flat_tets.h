// Tets that are flat up to the round-off of their vertex coordinates.
//
// Delaunay on lattice-like points meets cospherical groups; CGAL's exact
// predicates keep tets whose corners are coplanar in decimal but not in
// binary floating point (seen: volume / longest edge^3 = 8e-18 on a proxy
// mesh whose next-worst tet had 5e-4). Such a tet holds no material but its
// linear stiffness, ~ area^2 / volume, is ~1e15 times a normal one's and
// makes the stiffness numerically singular, so the FEM leaves it out.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

namespace vpm {

// A tet with |signed volume| <= this * (longest edge)^3 counts as flat
// (dimensionless; 0.118 for the regular tet). Inverted tets beyond it are
// kept, for the element set-up to reject.
inline constexpr double kFlatTetRelativeVolume = 1e-9;

// Indices of the tets that are not flat.
//   positions_mm  #V by 3, mm
//   tets          #T by 4 indices into positions_mm (valid)
// Output: ascending indices into tets.
std::vector<int32_t> NonFlatTets(const std::vector<glm::dvec3>& positions_mm,
                                 const std::vector<std::array<int32_t, 4>>& tets);

}  // namespace vpm
