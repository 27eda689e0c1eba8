#include "server/raycast/slice_image.h"

#include <algorithm>
#include <cmath>

#include "server/raycast/volume_mip_window.h"
#include "server/volume/ct_in_hu.h"

namespace vpm {
namespace {

// The plane's unit normal in physical space.
glm::dvec3 PhysicalNormal(const SliceGrid& grid) {
  return glm::normalize(glm::cross(grid.step_u_mm, grid.step_v_mm));
}

// Continuous pixel position (pixel (i, j) covers [i, i+1) x [j, j+1)) and
// signed distance from the plane (mm) of physical point p; `normal`:
// PhysicalNormal(grid).
glm::dvec3 ToSlice(const SliceGrid& grid, const glm::dvec3& normal, const glm::dvec3& p) {
  const glm::dvec3 d = p - grid.origin_mm;
  const double pixel2 = grid.pixel_mm * grid.pixel_mm;
  return glm::dvec3(glm::dot(d, grid.step_u_mm) / pixel2, glm::dot(d, grid.step_v_mm) / pixel2,
                    glm::dot(d, normal));
}

void Plot(const SliceGrid& grid, int x, int y, const uint8_t rgb[3], std::span<uint8_t> rgba) {
  if (x < 0 || y < 0 || x >= grid.width || y >= grid.height) return;
  uint8_t* px = &rgba[(size_t(y) * grid.width + x) * 4];
  px[0] = rgb[0];
  px[1] = rgb[1];
  px[2] = rgb[2];
  px[3] = 255;
}

// Samples the segment at half-pixel steps (pixel coordinates).
void DrawSegment(const SliceGrid& grid, glm::dvec2 a, glm::dvec2 b, const uint8_t rgb[3],
                 std::span<uint8_t> rgba) {
  const double length = glm::length(b - a);
  const int steps = std::max(1, int(std::ceil(2.0 * length)));
  if (steps > 4 * (grid.width + grid.height)) return;  // far outside: not worth drawing
  for (int s = 0; s <= steps; ++s) {
    const glm::dvec2 p = a + (b - a) * (double(s) / steps);
    Plot(grid, int(std::floor(p.x)), int(std::floor(p.y)), rgb, rgba);
  }
}

}  // namespace

MipWindow DefaultSliceWindow(const Volume& volume) {
  if (IsCtInHu(volume)) return MipWindow{40.0, 400.0};
  std::vector<float> sample = SampleVolumeValues(volume, -INFINITY);
  const std::vector<double> p = Percentiles(sample, {1.0, 99.0});
  return MipWindow{0.5 * (p[0] + p[1]), std::max(p[1] - p[0], 1e-6)};
}

std::vector<uint8_t> SliceToRgba(std::span<const float> values, int width, int height,
                                 const MipWindow& window) {
  std::vector<uint8_t> rgba(size_t(width) * height * 4, 0);
  const double black = window.level - 0.5 * window.width;
  for (size_t i = 0; i < size_t(width) * height && i < values.size(); ++i) {
    const float v = values[i];
    const uint8_t grey =
        std::isnan(v) ? 0 : uint8_t(std::clamp((v - black) / window.width, 0.0, 1.0) * 255.0 + 0.5);
    rgba[4 * i] = rgba[4 * i + 1] = rgba[4 * i + 2] = grey;
    rgba[4 * i + 3] = 255;
  }
  return rgba;
}

int64_t DrawCutTets(const SliceGrid& grid, std::span<const glm::dvec3> positions_mm,
                    std::span<const std::array<int32_t, 4>> tets, const uint8_t rgb[3],
                    std::span<uint8_t> rgba) {
  static constexpr int kFaces[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
  int64_t cut = 0;
  const int64_t n = int64_t(positions_mm.size());
  const glm::dvec3 normal = PhysicalNormal(grid);
  for (const auto& tet : tets) {
    glm::dvec3 p[4];
    bool valid = true;
    for (int c = 0; c < 4; ++c) {
      if (tet[c] < 0 || tet[c] >= n) valid = false;
      if (valid) p[c] = ToSlice(grid, normal, positions_mm[tet[c]]);
    }
    if (!valid) continue;
    const double lo = std::min({p[0].z, p[1].z, p[2].z, p[3].z});
    const double hi = std::max({p[0].z, p[1].z, p[2].z, p[3].z});
    if (!(lo < 0.0 && hi > 0.0)) continue;
    ++cut;
    for (const auto& face : kFaces) {
      // The two points where the face's edges cross the plane.
      glm::dvec2 ends[2];
      int found = 0;
      for (int e = 0; e < 3 && found < 2; ++e) {
        const glm::dvec3& a = p[face[e]];
        const glm::dvec3& b = p[face[(e + 1) % 3]];
        if ((a.z < 0.0) == (b.z < 0.0)) continue;
        const double t = a.z / (a.z - b.z);
        ends[found++] = glm::dvec2(a) + t * (glm::dvec2(b) - glm::dvec2(a));
      }
      if (found == 2) DrawSegment(grid, ends[0], ends[1], rgb, rgba);
    }
  }
  return cut;
}

bool DrawSliceMarker(const SliceGrid& grid, const glm::dvec3& point_mm, double within_mm,
                     const uint8_t rgb[3], std::span<uint8_t> rgba) {
  const glm::dvec3 s = ToSlice(grid, PhysicalNormal(grid), point_mm);
  if (std::abs(s.z) > within_mm) return false;
  const int arm = std::max(4, std::min(grid.width, grid.height) / 40);
  const int x = int(std::floor(s.x)), y = int(std::floor(s.y));
  for (int d = -arm; d <= arm; ++d) {
    Plot(grid, x + d, y, rgb, rgba);
    Plot(grid, x, y + d, rgb, rgba);
  }
  return true;
}

}  // namespace vpm
