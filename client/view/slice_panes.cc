#include "client/view/slice_panes.h"

#include <algorithm>

namespace vpm::view {
namespace {

glm::dvec3 Vec(const v3::Vec3& v) { return {v.x(), v.y(), v.z()}; }

}  // namespace

double ScrolledSliceOffset(const v3::SliceGeometry& geometry, double at_mm, double notches) {
  const double lo = std::min(geometry.min_offset_mm(), geometry.max_offset_mm());
  const double hi = std::max(geometry.min_offset_mm(), geometry.max_offset_mm());
  return std::clamp(at_mm + notches * geometry.pixel_mm(), lo, hi);
}

glm::dvec3 SlicePointMm(const v3::SliceGeometry& geometry, double x, double y) {
  return Vec(geometry.origin_mm()) + x * Vec(geometry.step_u_mm()) +
         y * Vec(geometry.step_v_mm());
}

glm::dvec3 SliceDragOffsetMm(const v3::SliceGeometry& geometry, double dx, double dy) {
  return dx * Vec(geometry.step_u_mm()) + dy * Vec(geometry.step_v_mm());
}

}  // namespace vpm::view
