// What one slice frame of a deformable scene asks for, and what comes back
// (DeformableScene::RenderSlice).
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "server/raycast/slice_grid.h"
#include "server/raycast/slice_image.h"

namespace vpm {

struct SliceView {
  SlicePlane plane;
  double pixel_mm = 0.0;               // 0: the smallest voxel spacing
  std::optional<MipWindow> window;     // default: DefaultSliceWindow(volume)
  // Outline the deformed tets the plane cuts (yellow) and mark the grabbed
  // tissue (the grab point moved by the drag, red) when it lies within one
  // lattice step h of the plane.
  bool overlay = false;
};

struct SliceFrame {
  std::vector<uint8_t> rgba;  // grid.width * grid.height * 4, row 0 at the top
  SliceGrid grid;
  MipWindow window;
  int64_t cut_tets = -1;      // overlay: tets the plane cuts
  double gpu_ms = 0.0;        // the slice kernel
};

}  // namespace vpm
