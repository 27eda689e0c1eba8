#include "server/raycast/brick_occupancy_cpu.h"

#include <algorithm>

#include "server/raycast/raycast_cpu.h"

namespace vpm {

using glm::ivec3;
using glm::vec3;

std::vector<glm::vec2> BrickMinMaxCpu(const Volume& volume, glm::ivec3 brick_voxels) {
  const glm::i64vec3 w(brick_voxels);
  const auto nb = BrickGridDims(volume.dims(), brick_voxels);
  const auto& n = volume.dims();
  std::vector<glm::vec2> out(static_cast<size_t>(nb[0]) * nb[1] * nb[2]);
  for (int bz = 0; bz < nb[2]; ++bz)
    for (int by = 0; by < nb[1]; ++by)
      for (int bx = 0; bx < nb[0]; ++bx) {
        float lo = 3.0e38f, hi = -3.0e38f;
        const int64_t z1 = std::min<int64_t>(bz * w.z + w.z, n[2] - 1);
        const int64_t y1 = std::min<int64_t>(by * w.y + w.y, n[1] - 1);
        const int64_t x1 = std::min<int64_t>(bx * w.x + w.x, n[0] - 1);
        for (int64_t z = bz * w.z; z <= z1; ++z)
          for (int64_t y = by * w.y; y <= y1; ++y)
            for (int64_t x = bx * w.x; x <= x1; ++x) {
              const float v = volume.At(x, y, z);
              lo = std::min(lo, v);
              hi = std::max(hi, v);
            }
        out[bx + nb[0] * (by + size_t(nb[1]) * bz)] = glm::vec2(lo, hi);
      }
  return out;
}

std::vector<float> BrickOccupancyCpu(std::span<const glm::vec2> minmax,
                                     const VolumeGeometry& geometry, glm::ivec3 brick_voxels,
                                     RenderMode mode, const RenderLut& lut,
                                     const HostBackwardMap* map) {
  const ivec3 w = brick_voxels;
  const auto nba = BrickGridDims(geometry.dims, brick_voxels);
  const ivec3 nb(nba[0], nba[1], nba[2]);
  const ivec3 n(int(geometry.dims[0]), int(geometry.dims[1]), int(geometry.dims[2]));
  const vec3 s(geometry.spacing_mm);
  std::vector<float> out(size_t(nb.x) * nb.y * nb.z);
  for (int index = 0; index < int(out.size()); ++index) {
    const ivec3 b(index % nb.x, (index / nb.x) % nb.y, index / (nb.x * nb.y));
    const vec3 lo_mm = vec3(b * w) * s;
    const vec3 hi_mm = vec3(glm::min((b + 1) * w, n - 1)) * s;
    vec3 dmin(0.0f), dmax(0.0f);
    if (map != nullptr) {
      const ivec3 m(map->dims[0], map->dims[1], map->dims[2]);
      const vec3 to_grid = vec3(m - 1) / (vec3(n - 1) * s);
      const ivec3 g_lo = glm::clamp(ivec3(glm::floor(lo_mm * to_grid)), ivec3(0), m - 1);
      const ivec3 g_hi = glm::clamp(ivec3(glm::floor(hi_mm * to_grid)) + 1, ivec3(0), m - 1);
      dmin = vec3(3.0e38f);
      dmax = vec3(-3.0e38f);
      for (int z = g_lo.z; z <= g_hi.z; ++z)
        for (int y = g_lo.y; y <= g_hi.y; ++y)
          for (int x = g_lo.x; x <= g_hi.x; ++x) {
            const vec3 d(map->texels[x + m.x * (y + size_t(m.y) * z)]);
            dmin = glm::min(dmin, d);
            dmax = glm::max(dmax, d);
          }
    }
    // Source bricks covering voxels floor(u_lo) .. ceil(u_hi), as
    // brick_occupancy.comp.
    const vec3 u_lo = glm::clamp(vec3(b * w) + dmin / s, vec3(0.0f), vec3(n - 1));
    const vec3 u_hi =
        glm::clamp(vec3(glm::min((b + 1) * w, n - 1)) + dmax / s, vec3(0.0f), vec3(n - 1));
    const ivec3 s_lo = glm::clamp(ivec3(glm::floor(u_lo / vec3(w))), ivec3(0), nb - 1);
    const ivec3 s_hi = glm::clamp(ivec3(glm::ceil(u_hi / vec3(w))) - 1, s_lo, nb - 1);
    float vmin = 3.0e38f, vmax = -3.0e38f;
    for (int z = s_lo.z; z <= s_hi.z; ++z)
      for (int y = s_lo.y; y <= s_hi.y; ++y)
        for (int x = s_lo.x; x <= s_hi.x; ++x) {
          const glm::vec2 r = minmax[x + nb.x * (y + size_t(nb.y) * z)];
          vmin = std::min(vmin, r.x);
          vmax = std::max(vmax, r.y);
        }
    if (mode == RenderMode::kMip) {
      out[index] = vmax;
    } else {
      const auto [e_lo, e_hi] = LutEntryRange(lut, vmin, vmax);
      out[index] = lut.nonzero_prefix[e_hi + 1] - lut.nonzero_prefix[e_lo] > 0 ? 1.0f : 0.0f;
    }
  }
  return out;
}

}  // namespace vpm
