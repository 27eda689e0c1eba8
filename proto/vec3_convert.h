// glm <-> v3::Vec3 (mm in physical voxel space, or N for forces), shared by
// the server and the clients.
#pragma once

#include <glm/glm.hpp>

#include "vpm/v3/vpm.pb.h"

namespace vpm {

inline v3::Vec3 ToProto(const glm::dvec3& v) {
  v3::Vec3 out;
  out.set_x(v.x);
  out.set_y(v.y);
  out.set_z(v.z);
  return out;
}

inline glm::dvec3 FromProto(const v3::Vec3& v) { return {v.x(), v.y(), v.z()}; }

}  // namespace vpm
