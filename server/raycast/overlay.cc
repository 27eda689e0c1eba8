#include "server/raycast/overlay.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace vpm {
namespace {

struct Canvas {
  int width;
  int height;
  std::span<uint8_t> rgba;

  // Blends `rgb` over the pixel with coverage `a` in [0, 1].
  void Blend(int x, int y, const uint8_t* rgb, double a) {
    if (x < 0 || y < 0 || x >= width || y >= height || a <= 0.0) return;
    uint8_t* p = &rgba[(size_t(y) * width + x) * 4];
    a = std::min(a, 1.0);
    for (int c = 0; c < 3; ++c) {
      p[c] = static_cast<uint8_t>(std::lround(p[c] + (rgb[c] - p[c]) * a));
    }
    p[3] = 255;
  }

  // A disc of radius r centred at (cx, cy) (continuous pixel coordinates),
  // with an outline ring of `ring` px in ring_rgb; edges antialiased by
  // distance.
  void Disc(double cx, double cy, double r, const uint8_t* fill, double ring,
            const uint8_t* ring_rgb) {
    const int x0 = int(std::floor(cx - r - 1)), x1 = int(std::ceil(cx + r + 1));
    const int y0 = int(std::floor(cy - r - 1)), y1 = int(std::ceil(cy + r + 1));
    for (int y = std::max(y0, 0); y <= std::min(y1, height - 1); ++y) {
      for (int x = std::max(x0, 0); x <= std::min(x1, width - 1); ++x) {
        const double d = std::hypot(x + 0.5 - cx, y + 0.5 - cy);
        const double outer = std::clamp(r + 0.5 - d, 0.0, 1.0);
        if (outer <= 0.0) continue;
        const double inner = ring > 0.0 ? std::clamp(r - ring + 0.5 - d, 0.0, 1.0) : 1.0;
        if (ring > 0.0) Blend(x, y, ring_rgb, outer);
        Blend(x, y, fill, ring > 0.0 ? inner : outer);
      }
    }
  }

  // A segment of half-width hw from a to b.
  void Segment(glm::dvec2 a, glm::dvec2 b, double hw, const uint8_t* rgb) {
    const glm::dvec2 lo = glm::min(a, b) - hw - 1.0, hi = glm::max(a, b) + hw + 1.0;
    const glm::dvec2 ab = b - a;
    const double len2 = std::max(glm::dot(ab, ab), 1e-12);
    for (int y = std::max(int(lo.y), 0); y <= std::min(int(hi.y), height - 1); ++y) {
      for (int x = std::max(int(lo.x), 0); x <= std::min(int(hi.x), width - 1); ++x) {
        const glm::dvec2 p(x + 0.5, y + 0.5);
        const double t = std::clamp(glm::dot(p - a, ab) / len2, 0.0, 1.0);
        const double d = glm::length(p - (a + t * ab));
        Blend(x, y, rgb, std::clamp(hw + 0.5 - d, 0.0, 1.0));
      }
    }
  }
};

constexpr uint8_t kWhite[3] = {255, 255, 255};
constexpr uint8_t kDark[3] = {20, 20, 20};

void DrawArrow(Canvas& canvas, glm::dvec2 from, glm::dvec2 to, double r) {
  const double hw = std::max(1.0, 0.4 * r);
  canvas.Disc(from.x, from.y, r, kDragRgb, 1.0, kDark);
  canvas.Segment(from, to, hw, kDragRgb);
  const glm::dvec2 d = to - from;
  const double len = glm::length(d);
  if (len < 1e-6) return;
  const glm::dvec2 u = d / len, n(-u.y, u.x);
  const double head = std::min(4.0 * r, 0.5 * len + 2.0 * r);
  canvas.Segment(to, to - head * u + 0.6 * head * n, hw, kDragRgb);
  canvas.Segment(to, to - head * u - 0.6 * head * n, hw, kDragRgb);
}

}  // namespace

OverlayData MakeMeshOverlay(const ProxyMesh& mesh, std::span<const glm::dvec3> positions_mm,
                            std::span<const int32_t> handle_vertices) {
  OverlayData overlay;
  overlay.points.reserve(mesh.vertices.size());
  const bool deformed = positions_mm.size() == mesh.vertices.size();
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    const MeshVertex& v = mesh.vertices[i];
    overlay.points.push_back(
        {deformed ? positions_mm[i] : v.position_mm, v.hard, v.kind, false});
  }
  for (int32_t h : handle_vertices) {
    if (h >= 0 && size_t(h) < overlay.points.size()) overlay.points[h].handle = true;
  }
  return overlay;
}

void DrawOverlay(const OverlayData& overlay, const Camera& camera, int width, int height,
                 std::span<uint8_t> rgba) {
  if (overlay.empty() || width <= 0 || height <= 0 ||
      rgba.size() < size_t(width) * size_t(height) * 4) {
    return;
  }
  Canvas canvas{width, height, rgba};
  const double r = overlay.point_radius_px > 0.0
                       ? overlay.point_radius_px
                       : std::max(2.0, std::min(width, height) / 170.0);
  struct Projected {
    glm::dvec3 xyz;  // pixel x, y, depth (mm)
    const OverlayPoint* point;
  };
  std::vector<Projected> projected;
  projected.reserve(overlay.points.size());
  for (const OverlayPoint& p : overlay.points) {
    if (auto xyz = camera.Project(p.position_mm, width, height)) projected.push_back({*xyz, &p});
  }
  // Far to near; handles last so that they are never hidden.
  std::stable_sort(projected.begin(), projected.end(), [](const Projected& a, const Projected& b) {
    if (a.point->handle != b.point->handle) return b.point->handle;
    return a.xyz.z > b.xyz.z;
  });
  for (const Projected& p : projected) {
    const OverlayPoint& v = *p.point;
    if (v.handle) {
      canvas.Disc(p.xyz.x, p.xyz.y, 1.8 * r, kHandleRgb, 1.5, kWhite);
    } else {
      const uint8_t* fill = v.hard ? kHardRgb : kDeformableRgb;
      const bool refined = v.kind == VertexKind::kRefined;
      canvas.Disc(p.xyz.x, p.xyz.y, r, fill, refined ? 1.0 : 0.0, kDark);
    }
  }
  if (overlay.drag) {
    auto from = camera.Project(overlay.drag->from_mm, width, height);
    auto to = camera.Project(overlay.drag->to_mm, width, height);
    if (from && to) DrawArrow(canvas, glm::dvec2(*from), glm::dvec2(*to), r);
  }
}

}  // namespace vpm
