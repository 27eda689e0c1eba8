#include "server/fem/flat_tets.h"

#include <algorithm>
#include <cmath>

#include "server/mesh/tet_quality.h"

namespace vpm {

std::vector<int32_t> NonFlatTets(const std::vector<glm::dvec3>& positions_mm,
                                 const std::vector<std::array<int32_t, 4>>& tets) {
  std::vector<int32_t> kept;
  kept.reserve(tets.size());
  for (size_t t = 0; t < tets.size(); ++t) {
    const auto& q = tets[t];
    double longest = 0.0;
    for (int a = 0; a < 4; ++a) {
      for (int b = a + 1; b < 4; ++b) {
        longest = std::max(longest, glm::distance(positions_mm[q[a]], positions_mm[q[b]]));
      }
    }
    const double volume = SignedVolume(positions_mm[q[0]], positions_mm[q[1]], positions_mm[q[2]],
                                       positions_mm[q[3]]);
    if (std::abs(volume) > kFlatTetRelativeVolume * longest * longest * longest) {
      kept.push_back(static_cast<int32_t>(t));
    }
  }
  return kept;
}

}  // namespace vpm
