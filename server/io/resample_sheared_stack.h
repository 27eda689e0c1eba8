// A stack of parallel image planes (slices) that need not form a box: each
// slice may be shifted within its plane (gantry tilt, a sheared stack) and
// the gaps between slices may differ. Resampled onto a regular grid.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "server/common/status.h"
#include "server/volume/volume.h"

namespace vpm {

struct StackSlice {
  // Position of pixel (0,0) in the stack's frame, mm: x = along the row
  // direction, y = along the column direction, z = along the slice normal.
  glm::dvec3 position_in_frame_mm{0.0};
  std::span<const float> values;  // columns * rows, i (along the row direction) fastest
};

struct ShearedStack {
  int64_t columns = 0;  // pixels along the row direction (i)
  int64_t rows = 0;     // pixels along the column direction (j)
  // Pixel pitch along i and along j, mm.
  glm::dvec2 pixel_spacing_mm{1.0, 1.0};
  // Columns: world (LPS) unit vectors of the row direction, the column
  // direction and the slice normal; orthonormal.
  glm::dmat3 frame{1.0};
  // Sorted by position_in_frame_mm.z, strictly increasing; at least 2.
  std::vector<StackSlice> slices;
};

// Resamples `stack` onto the regular grid whose axes are the stack's frame
// (row direction, column direction, normal), like dcm2niix's tilt-corrected
// output. In-plane spacing is the pixel spacing; the slice spacing is
// `slice_spacing_mm`, from the first slice's plane to the last (the last
// output plane may fall short of the last slice by less than one spacing).
// The box covers every slice's pixels (in-plane extents rounded up to whole
// voxels), so nothing is cut off at the edges;
// output voxels that fall outside a slice's pixels take `fill_value` (the
// caller passes the series' minimum: air, or the scanner's padding). Values:
// bilinear within each slice, then linear between the two slices that
// bracket the output plane. Output geometry is in world LPS mm.
// Errors: InvalidArgument (fewer than 2 slices, unsorted, bad spacing),
// ResourceExhausted (the output grid is over `limits`, checked before
// allocating).
Result<Volume> ResampleShearedStack(const ShearedStack& stack, double slice_spacing_mm,
                                    float fill_value, const VolumeLimits& limits);

}  // namespace vpm
