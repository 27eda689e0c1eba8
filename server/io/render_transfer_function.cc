#include "server/io/render_transfer_function.h"

#include <cmath>

namespace vpm {
namespace {

bool InUnit(double v) { return std::isfinite(v) && v >= 0.0 && v <= 1.0; }

// Checks count and order of `points` (either list); `in_unit(i)` checks the
// i-th point's colour or opacity.
template <typename Point, typename InUnitFn>
Status CheckPoints(const std::vector<Point>& points, std::string_view what,
                   std::string_view list, InUnitFn in_unit) {
  if (points.empty() || points.size() > kMaxRenderTfPoints) {
    return absl::InvalidArgumentError(StrCat(what, ": ", points.size(), " ", list,
                                             " points; 1..", kMaxRenderTfPoints, " expected"));
  }
  for (size_t i = 0; i < points.size(); ++i) {
    if (!std::isfinite(points[i].value)) {
      return absl::InvalidArgumentError(
          StrCat(what, ": ", list, " point ", i, ": value is not a finite number"));
    }
    if (i > 0 && points[i].value < points[i - 1].value) {
      return absl::InvalidArgumentError(StrCat(what, ": ", list, " point ", i, " (value ",
                                               points[i].value, ") is below point ", i - 1,
                                               " (", points[i - 1].value, "): values must ascend"));
    }
    if (!in_unit(i)) {
      return absl::InvalidArgumentError(
          StrCat(what, ": ", list, " point ", i, ": must be a number in [0, 1]"));
    }
  }
  return absl::OkStatus();
}

}  // namespace

Status ValidateRenderTransferFunction(const RenderTransferFunction& tf, std::string_view what) {
  RETURN_IF_ERROR(CheckPoints(tf.colors, what, "colour", [&](size_t i) {
    const glm::dvec3& c = tf.colors[i].rgb;
    return InUnit(c.r) && InUnit(c.g) && InUnit(c.b);
  }));
  return CheckPoints(tf.opacities, what, "opacity",
                     [&](size_t i) { return InUnit(tf.opacities[i].opacity); });
}

}  // namespace vpm
