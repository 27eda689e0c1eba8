#include "client/view/case_view_settings.h"

namespace vpm::view {

v3::RenderSettings WithCaseView(const v3::RenderSettings& own, const v3::RenderSettings& view) {
  v3::RenderSettings out = view;
  out.set_width(own.width());
  out.set_height(own.height());
  out.set_overlay(own.overlay());
  out.set_encoding(own.encoding());
  out.set_jpeg_quality(own.jpeg_quality());
  out.set_interactive_quality(own.interactive_quality());
  return out;
}

WorldBox CropBoxFromProto(const v3::CropBox& crop) {
  const auto at = [](const v3::Vec3& v) { return glm::dvec3(v.x(), v.y(), v.z()); };
  return WorldBox{at(crop.lo_mm()), at(crop.hi_mm())};
}

}  // namespace vpm::view
