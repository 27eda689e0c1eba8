#include "server/volume/volume.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace vpm {

std::string DescribeVolumeSize(const VolumeGeometry& g, VoxelEncoding encoding) {
  const double mib = double(g.dims[0]) * double(g.dims[1]) * double(g.dims[2]) *
                     double(VoxelEncodingBytes(encoding)) / (1 << 20);
  char size[32];
  std::snprintf(size, sizeof(size), "%.1f", mib);
  return StrCat(g.dims[0], "x", g.dims[1], "x", g.dims[2], " ", VoxelEncodingName(encoding),
                " voxels (", size, " MiB)");
}

Status ValidateGeometry(const VolumeGeometry& g, const VolumeLimits& limits,
                        VoxelEncoding encoding) {
  static constexpr const char* kAxis[3] = {"x", "y", "z"};
  const int64_t bytes_per_voxel = VoxelEncodingBytes(encoding);
  const int64_t max_voxels = std::max<int64_t>(limits.max_volume_bytes / bytes_per_voxel, 0);
  for (int a = 0; a < 3; ++a) {
    if (g.dims[a] <= 0) {
      return absl::InvalidArgumentError(
          StrCat("dimension ", kAxis[a], " is ", g.dims[a], "; it must be positive"));
    }
    if (g.dims[a] > max_voxels) {
      return absl::ResourceExhaustedError(
          StrCat("dimension ", kAxis[a], " is ", g.dims[a], " voxels: over the cap of ",
                 limits.max_volume_bytes, " bytes on one volume (--max-volume-bytes)"));
    }
    const double s = g.spacing_mm[a];
    if (!std::isfinite(s) || s <= 0.0) {
      return absl::InvalidArgumentError(StrCat(
          "spacing ", kAxis[a], " is ", s, " mm; it must be a positive finite number"));
    }
    if (!std::isfinite(g.origin_mm[a])) {
      return absl::InvalidArgumentError(StrCat("origin ", kAxis[a], " is not finite"));
    }
  }
  // Overflow-safe product check against the budget.
  if (g.dims[0] > max_voxels / g.dims[1] || g.dims[0] * g.dims[1] > max_voxels / g.dims[2]) {
    const bool fits_int64 = g.dims[0] <= (int64_t{1} << 62) / g.dims[1] &&
                            g.dims[0] * g.dims[1] <= (int64_t{1} << 62) / g.dims[2];
    return absl::ResourceExhaustedError(StrCat(
        "volume of ", DescribeVolumeSize(g, encoding), " needs ",
        fits_int64 ? StrCat(g.voxel_count() * bytes_per_voxel) : std::string("over 2^62"),
        " bytes, over the cap of ", limits.max_volume_bytes,
        " bytes on one volume (--max-volume-bytes)"));
  }
  // Direction: columns must be unit length and mutually orthogonal (1e-3
  // tolerance absorbs the rounding of headers that store 6 decimals).
  const glm::dmat3 gram = glm::transpose(g.direction) * g.direction;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      const double expected = r == c ? 1.0 : 0.0;
      if (!std::isfinite(gram[c][r]) || std::abs(gram[c][r] - expected) > 1e-3) {
        return absl::InvalidArgumentError(
            "direction matrix is not orthonormal (axes must be unit and perpendicular)");
      }
    }
  }
  return absl::OkStatus();
}

Volume::Volume(VolumeGeometry geometry, VoxelValues values)
    : geometry_(geometry), values_(std::move(values)) {}

Result<Volume> Volume::Create(VolumeGeometry geometry, std::vector<float> values,
                              const VolumeLimits& limits) {
  return Create(geometry, VoxelValues::Float(std::move(values)), limits);
}

Result<Volume> Volume::Create(VolumeGeometry geometry, VoxelValues values,
                              const VolumeLimits& limits) {
  RETURN_IF_ERROR(ValidateGeometry(geometry, limits, values.encoding()));
  if (values.size() != geometry.voxel_count()) {
    return absl::InvalidArgumentError(
        StrCat("volume has ", values.size(), " values, expected ", geometry.voxel_count()));
  }
  Volume volume(geometry, std::move(values));
  if (volume.values_.is_int16()) {
    const auto stored = volume.values_.int16s();
    // A plain loop, not std::minmax_element: it vectorizes (perf showed
    // minmax_element at 12% of `vpm mesh` on a 512 x 512 x 900 CT).
    int16_t lo = stored[0], hi = stored[0];
    for (const int16_t s : stored) {
      lo = std::min(lo, s);
      hi = std::max(hi, s);
    }
    const int32_t offset = volume.values_.int16_offset();
    volume.min_value_ = static_cast<float>(int32_t{lo} + offset);
    volume.max_value_ = static_cast<float>(int32_t{hi} + offset);
    return volume;
  }
  float lo = std::numeric_limits<float>::infinity();
  float hi = -std::numeric_limits<float>::infinity();
  int64_t non_finite = 0;
  for (float v : volume.values_.floats()) {
    if (!std::isfinite(v)) {
      ++non_finite;
      continue;
    }
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  if (non_finite == volume.values_.size()) lo = hi = 0.0f;
  // NaN or infinite voxels would poison every mean and gradient downstream;
  // they become the smallest finite value (the background) and are counted.
  if (non_finite > 0) {
    for (float& v : volume.values_.mutable_floats()) {
      if (!std::isfinite(v)) v = lo;
    }
  }
  volume.min_value_ = lo;
  volume.max_value_ = hi;
  volume.non_finite_count_ = non_finite;
  return volume;
}

float Volume::AtClamped(int64_t i, int64_t j, int64_t k) const {
  i = std::clamp<int64_t>(i, 0, geometry_.dims[0] - 1);
  j = std::clamp<int64_t>(j, 0, geometry_.dims[1] - 1);
  k = std::clamp<int64_t>(k, 0, geometry_.dims[2] - 1);
  return values_[LinearIndex(i, j, k)];
}

}  // namespace vpm
