// Overlays drawn on a rendered frame on the CPU: the proxy mesh's vertices
// as discs (deformable YELLOW, hard / non-deformable BLUE, as in the paper's
// figures), the grabbed handle vertices highlighted (RED, larger, white
// ring), and the drag as an arrow from the grab point to the dragged point.
//
// No depth test: every vertex is drawn, as in the paper's figures, which
// show the whole mesh over the rendering. Discs are drawn far to near, so
// nearer vertices cover farther ones. Refined vertices (step 4) follow the
// same colour rule with a dark outline, to tell them from lattice survivors;
// anchors (box corners) follow the plain rule.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "server/mesh/proxy_mesh.h"
#include "server/raycast/camera.h"

namespace vpm {

struct OverlayPoint {
  glm::dvec3 position_mm{0.0};  // physical voxel space, deformed position
  bool hard = false;
  VertexKind kind = VertexKind::kLattice;
  bool handle = false;          // one of the grabbed vertices
};

struct DragArrow {
  glm::dvec3 from_mm{0.0};  // grab point (rest)
  glm::dvec3 to_mm{0.0};    // where it is dragged to
};

struct OverlayData {
  std::vector<OverlayPoint> points;
  std::optional<DragArrow> drag;
  double point_radius_px = 0.0;  // 0: max(2, shorter image side / 170)

  bool empty() const { return points.empty() && !drag; }
};

// Overlay points for `mesh`: positions from `positions_mm` (#V, deformed
// positions, mm) when given, else the rest positions; `handle_vertices`
// (indices into mesh.vertices) are marked as handles. Indices out of range
// are ignored.
OverlayData MakeMeshOverlay(const ProxyMesh& mesh, std::span<const glm::dvec3> positions_mm = {},
                            std::span<const int32_t> handle_vertices = {});

// Draws `overlay` into `rgba` (width * height * 4 bytes, row 0 at the top),
// projected with `camera` for a width x height image. Points behind the eye
// are skipped.
void DrawOverlay(const OverlayData& overlay, const Camera& camera, int width, int height,
                 std::span<uint8_t> rgba);

// The colours, for tests and docs.
inline constexpr uint8_t kDeformableRgb[3] = {255, 215, 0};
inline constexpr uint8_t kHardRgb[3] = {40, 110, 255};
inline constexpr uint8_t kHandleRgb[3] = {255, 40, 40};
inline constexpr uint8_t kDragRgb[3] = {0, 255, 140};

}  // namespace vpm
