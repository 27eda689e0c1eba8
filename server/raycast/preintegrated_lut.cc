#include "server/raycast/preintegrated_lut.h"

#include <algorithm>
#include <cmath>

#include "server/gpu/shader_interface.h"

namespace vpm {
namespace {

// The preset's colour and opacity per mm at ascending values.
std::vector<glm::dvec4> EvaluateAscending(const RenderPreset& preset,
                                          const std::vector<double>& values) {
  const auto& pts = preset.points;
  std::vector<glm::dvec4> out(values.size());
  size_t seg = 0;
  for (size_t i = 0; i < values.size(); ++i) {
    const double v = values[i];
    while (seg + 2 < pts.size() && v >= pts[seg + 1].value) ++seg;
    const ColorPoint& a = pts[seg];
    const ColorPoint& b = pts[seg + 1];
    const double width = b.value - a.value;
    const double t = width > 0.0 ? std::clamp((v - a.value) / width, 0.0, 1.0)
                                 : (v >= b.value ? 1.0 : 0.0);
    out[i] = a.rgba + (b.rgba - a.rgba) * t;
  }
  return out;
}

}  // namespace

std::vector<glm::vec4> BakePreintegratedLut(const RenderPreset& preset, double step_mm) {
  const int n = gpu::kPreintegratedEntries;
  const double lo = preset.points.front().value;
  const double hi = std::max(preset.points.back().value, lo + 1e-3);
  // Half-entry grid: q even is entry q / 2, q odd the midpoint of two entries.
  const int halves = 2 * n - 1;
  std::vector<double> values(halves);
  for (int q = 0; q < halves; ++q) values[q] = lo + (hi - lo) * q / (2.0 * (n - 1));
  const std::vector<glm::dvec4> tf = EvaluateAscending(preset, values);
  // Extinction per mm: 1 - a = exp(-tau * 1 mm); a = 1 stays finite.
  std::vector<double> tau(halves);
  for (int q = 0; q < halves; ++q) {
    tau[q] = -std::log(std::max(1.0 - tf[q].a, 1e-12)) / kOpacityReferenceMm;
  }
  std::vector<glm::vec4> table(size_t(n) * n);
  std::vector<double> alpha(halves);  // opacity of a sub-segment of length step / span
  for (int span = 0; span < n; ++span) {
    const double length = span == 0 ? step_mm : step_mm / span;
    for (int q = 0; q < halves; ++q) alpha[q] = 1.0 - std::exp(-tau[q] * length);
    for (int front = 0; front < n; ++front) {
      for (int side = 0; side < (span == 0 ? 1 : 2); ++side) {
        const int back = side == 0 ? front + span : front - span;
        if (back < 0 || back >= n) continue;
        glm::dvec3 colour(0.0);
        double transmitted = 1.0;
        if (span == 0) {
          const int q = 2 * front;
          colour = glm::dvec3(tf[q]) * alpha[q];
          transmitted = 1.0 - alpha[q];
        } else {
          const int dir = back > front ? 1 : -1;
          for (int m = 0; m < span; ++m) {
            const int q = 2 * front + dir * (2 * m + 1);
            colour += transmitted * alpha[q] * glm::dvec3(tf[q]);
            transmitted *= 1.0 - alpha[q];
          }
        }
        table[front + size_t(n) * back] = glm::vec4(glm::vec3(colour), float(1.0 - transmitted));
      }
    }
  }
  return table;
}

glm::vec4 PartialPreintegratedStep(glm::vec4 step, float fraction) {
  const float f = std::clamp(fraction, 0.0f, 1.0f);
  const float a = 1.0f - std::exp2(f * std::log2(std::max(1.0f - step.a, 1e-30f)));
  return glm::vec4(glm::vec3(step) * (step.a > 1e-6f ? a / step.a : f), a);
}

glm::vec4 SamplePreintegratedLut(const std::vector<glm::vec4>& table, const RenderLut& lut,
                                 float front, float back) {
  const int n = gpu::kPreintegratedEntries;
  const float scale = lut.entries_per_value * float(n - 1) / float(lut.entries.size() - 1);
  const float ff = std::clamp((front - lut.value_lo) * scale, 0.0f, float(n - 1));
  const float fb = std::clamp((back - lut.value_lo) * scale, 0.0f, float(n - 1));
  const int i = std::min(int(ff), n - 2), j = std::min(int(fb), n - 2);
  const float s = ff - float(i), t = fb - float(j);
  const size_t base = size_t(i) + size_t(n) * j;
  const glm::vec4 ab = table[base] + (table[base + 1] - table[base]) * s;
  const glm::vec4 cd = table[base + n] + (table[base + n + 1] - table[base + n]) * s;
  return ab + (cd - ab) * t;
}

}  // namespace vpm
