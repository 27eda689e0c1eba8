#include "server/raycast/upscale_cpu.h"

#include <algorithm>

#include <glm/glm.hpp>

namespace vpm {
namespace {

using glm::vec4;

// RGBA in [0, 1] of a packed RGBA8 word (r in the low byte).
vec4 Unpack(uint32_t w) {
  return vec4(float(w & 255u), float((w >> 8) & 255u), float((w >> 16) & 255u),
              float(w >> 24)) / 255.0f;
}

// Catmull-Rom weights of the texels at -1, 0, 1, 2 for a fraction t.
vec4 CatmullRom(float t) {
  const float t2 = t * t;
  const float t3 = t2 * t;
  return vec4(-0.5f * t3 + t2 - 0.5f * t, 1.5f * t3 - 2.5f * t2 + 1.0f,
              -1.5f * t3 + 2.0f * t2 + 0.5f * t, 0.5f * t3 - 0.5f * t2);
}

}  // namespace

std::vector<uint32_t> UpscaleCpu(std::span<const uint32_t> source, int sw, int sh, int tw,
                                 int th, int filter) {
  std::vector<uint32_t> out(size_t(tw) * th);
  const glm::vec2 scale = glm::vec2(sw, sh) / glm::vec2(tw, th);
  auto at = [&](int qx, int qy) { return Unpack(source[size_t(qy) * sw + qx]); };
  for (int y = 0; y < th; ++y) {
    for (int x = 0; x < tw; ++x) {
      const glm::vec2 s = glm::clamp((glm::vec2(x, y) + 0.5f) * scale - 0.5f, glm::vec2(0.0f),
                                     glm::vec2(sw - 1, sh - 1));
      const glm::ivec2 i0 = glm::ivec2(glm::floor(s));
      const glm::vec2 f = s - glm::vec2(i0);
      vec4 c(0.0f);
      if (filter == gpu::kUpscaleCatmullRom) {
        const vec4 wx = CatmullRom(f.x);
        const vec4 wy = CatmullRom(f.y);
        const glm::ivec4 xs = glm::clamp(i0.x + glm::ivec4(-1, 0, 1, 2), 0, sw - 1);
        for (int r = 0; r < 4; ++r) {
          const int qy = std::clamp(i0.y - 1 + r, 0, sh - 1);
          const vec4 row = at(xs.x, qy) * wx.x + at(xs.y, qy) * wx.y + at(xs.z, qy) * wx.z +
                           at(xs.w, qy) * wx.w;
          c += row * wy[r];
        }
      } else {
        const glm::ivec2 i1 = glm::min(i0 + 1, glm::ivec2(sw - 1, sh - 1));
        const vec4 top = at(i0.x, i0.y) + (at(i1.x, i0.y) - at(i0.x, i0.y)) * f.x;
        const vec4 bottom = at(i0.x, i1.y) + (at(i1.x, i1.y) - at(i0.x, i1.y)) * f.x;
        c = top + (bottom - top) * f.y;
      }
      c = glm::clamp(c, 0.0f, 1.0f) * 255.0f + 0.5f;
      out[size_t(y) * tw + x] = uint32_t(c.r) | (uint32_t(c.g) << 8) | (uint32_t(c.b) << 16) |
                                (uint32_t(c.a) << 24);
    }
  }
  return out;
}

}  // namespace vpm
