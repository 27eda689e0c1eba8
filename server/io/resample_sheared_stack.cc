#include "server/io/resample_sheared_stack.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <thread>

#include "server/common/huge_pages.h"
#include "server/common/parallel_chunks.h"

namespace vpm {
namespace {

// Fractions this close to a whole pixel or slice are snapped to it, so that
// an unsheared, evenly spaced stack comes out bit for bit as stored.
constexpr double kSnap = 1e-6;
// Grid extents within this fraction of a voxel of a whole count are taken as
// that count (no extra plane for rounding noise).
constexpr double kExtentSlack = 1e-3;

double Snap(double x) {
  const double r = std::round(x);
  return std::abs(x - r) < kSnap ? r : x;
}

// Bilinear sample of one slice at continuous pixel (x, y); `fill` outside
// [0, columns-1] x [0, rows-1].
float SampleSlice(const StackSlice& s, int64_t columns, int64_t rows, double x, double y,
                  float fill) {
  x = Snap(x);
  y = Snap(y);
  if (!(x >= 0.0 && y >= 0.0 && x <= columns - 1 && y <= rows - 1)) return fill;
  const int64_t i0 = std::min<int64_t>(static_cast<int64_t>(x), columns - 1);
  const int64_t j0 = std::min<int64_t>(static_cast<int64_t>(y), rows - 1);
  const int64_t i1 = std::min(i0 + 1, columns - 1);
  const int64_t j1 = std::min(j0 + 1, rows - 1);
  const double fx = x - i0, fy = y - j0;
  const auto at = [&](int64_t i, int64_t j) { return double{s.values[i + columns * j]}; };
  const double top = at(i0, j0) + fx * (at(i1, j0) - at(i0, j0));
  const double bottom = at(i0, j1) + fx * (at(i1, j1) - at(i0, j1));
  return static_cast<float>(top + fy * (bottom - top));
}

Status CheckStack(const ShearedStack& stack, double slice_spacing_mm) {
  if (stack.slices.size() < 2) {
    return absl::InvalidArgumentError("a stack to resample needs at least 2 slices");
  }
  if (stack.columns < 1 || stack.rows < 1) {
    return absl::InvalidArgumentError("stack slices have no pixels");
  }
  if (!(stack.pixel_spacing_mm.x > 0.0) || !(stack.pixel_spacing_mm.y > 0.0) ||
      !std::isfinite(stack.pixel_spacing_mm.x) || !std::isfinite(stack.pixel_spacing_mm.y)) {
    return absl::InvalidArgumentError("pixel spacing must be finite and > 0");
  }
  if (!(slice_spacing_mm > 0.0) || !std::isfinite(slice_spacing_mm)) {
    return absl::InvalidArgumentError(
        StrCat("slice spacing ", slice_spacing_mm, " mm must be finite and > 0"));
  }
  const size_t pixels = static_cast<size_t>(stack.columns * stack.rows);
  for (size_t k = 0; k < stack.slices.size(); ++k) {
    if (stack.slices[k].values.size() != pixels) {
      return absl::InvalidArgumentError(
          StrCat("slice ", k, " holds ", stack.slices[k].values.size(), " values, not ", pixels));
    }
    if (k > 0 &&
        !(stack.slices[k].position_in_frame_mm.z > stack.slices[k - 1].position_in_frame_mm.z)) {
      return absl::InvalidArgumentError("stack slices are not sorted along the normal");
    }
  }
  return absl::OkStatus();
}

// Voxel count along an in-plane axis whose grid covers `extent_mm` at
// `spacing_mm`: rounded up, so that no pixel of any slice is cut off.
int64_t CountCovering(double extent_mm, double spacing_mm) {
  return static_cast<int64_t>(std::ceil(extent_mm / spacing_mm - kExtentSlack)) + 1;
}

// Planes along the normal from the first slice, none beyond the last (there
// is nothing there to interpolate).
int64_t CountWithin(double extent_mm, double spacing_mm) {
  return static_cast<int64_t>(std::floor(extent_mm / spacing_mm + kExtentSlack)) + 1;
}

// The output slice at z (mm, along the frame's normal): nx x ny pixels
// from `low` (mm, in the frame) at the stack's pitch, linear between the
// stack's slices below and above z, into out.
void ResampleSlice(const ShearedStack& stack, glm::dvec2 low, double z, float fill_value,
                   int64_t nx, int64_t ny, float* out) {
  const glm::dvec2 pitch = stack.pixel_spacing_mm;
  // The slices below and above the output plane, and the weight of the upper one.
  const auto above = std::upper_bound(
      stack.slices.begin(), stack.slices.end(), z,
      [](double zz, const StackSlice& s) { return zz < s.position_in_frame_mm.z; });
  const size_t upper = std::clamp<size_t>(above - stack.slices.begin(), 1, stack.slices.size() - 1);
  const StackSlice& a = stack.slices[upper - 1];
  const StackSlice& b = stack.slices[upper];
  const double t = std::clamp(
      Snap((z - a.position_in_frame_mm.z) / (b.position_in_frame_mm.z - a.position_in_frame_mm.z)),
      0.0, 1.0);
  for (int64_t j = 0; j < ny; ++j) {
    const double y = low.y + j * pitch.y;
    for (int64_t i = 0; i < nx; ++i) {
      const double x = low.x + i * pitch.x;
      const auto sample = [&](const StackSlice& s) {
        return SampleSlice(s, stack.columns, stack.rows, (x - s.position_in_frame_mm.x) / pitch.x,
                           (y - s.position_in_frame_mm.y) / pitch.y, fill_value);
      };
      float v = 0.0f;
      if (t == 0.0) {
        v = sample(a);
      } else if (t == 1.0) {
        v = sample(b);
      } else {
        v = static_cast<float>((1.0 - t) * sample(a) + t * sample(b));
      }
      out[i + nx * j] = v;
    }
  }
}

}  // namespace

Result<Volume> ResampleShearedStack(const ShearedStack& stack, double slice_spacing_mm,
                                    float fill_value, const VolumeLimits& limits) {
  RETURN_IF_ERROR(CheckStack(stack, slice_spacing_mm));
  const glm::dvec2 pitch = stack.pixel_spacing_mm;
  // The in-plane box covering every slice, in the frame (mm).
  glm::dvec2 low(std::numeric_limits<double>::max());
  glm::dvec2 high(std::numeric_limits<double>::lowest());
  for (const StackSlice& s : stack.slices) {
    const glm::dvec2 p(s.position_in_frame_mm);
    low = glm::min(low, p);
    high = glm::max(high, p + glm::dvec2(stack.columns - 1, stack.rows - 1) * pitch);
  }
  const double z_first = stack.slices.front().position_in_frame_mm.z;
  const double z_last = stack.slices.back().position_in_frame_mm.z;
  VolumeGeometry g;
  g.dims = {CountCovering(high.x - low.x, pitch.x), CountCovering(high.y - low.y, pitch.y),
            CountWithin(z_last - z_first, slice_spacing_mm)};
  g.spacing_mm = {pitch.x, pitch.y, slice_spacing_mm};
  g.direction = stack.frame;
  g.origin_mm = stack.frame * glm::dvec3(low.x, low.y, z_first);
  // The budget, before allocating: float, since resampled values are not
  // integers (the volume's notes say so).
  RETURN_IF_ERROR(ValidateGeometry(g, limits, VoxelEncoding::kFloat32));
  std::vector<float> values = HugePageVector<float>(static_cast<size_t>(g.voxel_count()));

  const int64_t nx = g.dims[0], ny = g.dims[1];
  const int threads = static_cast<int>(std::clamp(std::thread::hardware_concurrency(), 1u, 8u));
  // A cancelled load skips the slices not yet begun, and returns the token's status below.
  ParallelSlices(g.dims[2], threads, [&](int64_t k) {
    if (!limits.cancel.Check().ok()) return;
    ResampleSlice(stack, low, z_first + k * slice_spacing_mm, fill_value, nx, ny,
                  values.data() + k * nx * ny);
  });
  RETURN_IF_ERROR(limits.cancel.Check());
  ASSIGN_OR_RETURN(Volume volume, Volume::Create(g, std::move(values), limits));
  volume.add_note("stored as float32: resampled values are not integers");
  return volume;
}

}  // namespace vpm
