#include "server/raycast/render_preset_from_tf.h"

#include <algorithm>

#include "server/raycast/volume_mip_window.h"

namespace vpm {
namespace {

constexpr double kCtShadingGradient = 30.0;  // HU/mm, as vpm's CT presets

// The limits from the left and from the right at `x` of the piecewise-linear
// function through `points` (sorted by value; clamped outside): equal unless
// x is a step (several points at x: the first gives the left limit, the last
// the right).
template <typename Point, typename Get>
auto LeftRight(const std::vector<Point>& points, double x, Get get) {
  const auto by_value = [](const Point& p, double v) { return p.value < v; };
  const auto lo = std::lower_bound(points.begin(), points.end(), x, by_value);
  auto hi = lo;
  while (hi != points.end() && hi->value == x) ++hi;
  using T = decltype(get(points.front()));
  if (lo != hi) return std::pair<T, T>{get(*lo), get(*(hi - 1))};
  if (lo == points.begin()) return std::pair<T, T>{get(points.front()), get(points.front())};
  if (lo == points.end()) return std::pair<T, T>{get(points.back()), get(points.back())};
  const Point& a = *(lo - 1);
  const Point& b = *lo;
  const double t = (x - a.value) / (b.value - a.value);
  const T v = get(a) + (get(b) - get(a)) * t;
  return std::pair<T, T>{v, v};
}

}  // namespace

Result<RenderPreset> RenderPresetFromTf(const RenderTransferFunction& tf, const Volume& volume) {
  RETURN_IF_ERROR(ValidateRenderTransferFunction(tf, tf.name.empty() ? "transfer function" : tf.name));
  std::vector<double> values;
  for (const TfColorPoint& c : tf.colors) values.push_back(c.value);
  for (const TfOpacityPoint& o : tf.opacities) values.push_back(o.value);
  std::sort(values.begin(), values.end());
  values.erase(std::unique(values.begin(), values.end()), values.end());
  RenderPreset preset;
  preset.name = tf.name.empty() ? "custom" : tf.name;
  for (double x : values) {
    const auto [c_left, c_right] =
        LeftRight(tf.colors, x, [](const TfColorPoint& p) { return p.rgb; });
    const auto [a_left, a_right] =
        LeftRight(tf.opacities, x, [](const TfOpacityPoint& p) { return p.opacity; });
    preset.points.push_back({x, glm::dvec4(c_left, a_left)});
    if (c_left != c_right || a_left != a_right) {
      preset.points.push_back({x, glm::dvec4(c_right, a_right)});
    }
  }
  if (preset.points.size() == 1) preset.points.push_back(preset.points.front());
  preset.mip_window = VolumeMipWindow(volume);
  preset.shading_gradient =
      IsCtInHu(volume) ? kCtShadingGradient : std::max(1e-6, preset.mip_window.width / 50.0);
  preset.lighting = tf.lighting;
  return preset;
}

}  // namespace vpm
