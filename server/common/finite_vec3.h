// Whether a point or vector has three finite coordinates (no NaN, no
// infinity): the first check on any coordinate that comes from a client.
#pragma once

#include <cmath>

#include <glm/vec3.hpp>

namespace vpm {

inline bool IsFinite(const glm::dvec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

}  // namespace vpm
