// Voxels as a file stores them -> the storage a Volume holds (int16 + offset
// or float, server/volume/voxel_values.h).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <span>
#include <string>

#include "server/common/status.h"
#include "server/io/byte_order.h"
#include "server/io/voxel_type.h"
#include "server/volume/volume.h"

namespace vpm {

// Converts geometry.voxel_count() voxels stored back to back in `bytes`
// (type `type`, byte order `endian`; value = stored * slope + intercept, as
// ConvertVoxelsToFloat) into the storage the volume will hold: int16 +
// offset when `type` is an integer type and every value is an integer, all
// of them within 65,536 consecutive integers and +-2^24 (CT in HU, 8- and
// 16-bit MRI: the values exactly); float otherwise, and then, for an
// integer type, `*float_note` (when given) says why ("stored as float32:
// ..."), for the volume's notes. Checks the geometry against
// limits.max_volume_bytes for the chosen encoding before allocating it.
// Fails like ConvertVoxelsToFloat when `bytes` is short.
Result<VoxelValues> ConvertVoxels(std::span<const uint8_t> bytes, VoxelType type, Endian endian,
                                  const VolumeGeometry& geometry, const VolumeLimits& limits,
                                  double slope = 1.0, double intercept = 0.0,
                                  std::string* float_note = nullptr);

// Whether ConvertVoxels keeps voxels of this type, byte order and scaling
// as the file stores them (int16 in the machine's byte order, slope 1, an
// integer intercept within +-32768, which becomes the int16 offset): then a
// reader may read them straight into the volume's int16 storage.
bool StoredAsInt16AsIs(VoxelType type, Endian endian, double slope, double intercept);

// A volume of `geometry` from voxels as a file stores them (ConvertVoxels),
// with its source set to `name` and the float note, if any, among its notes.
Result<Volume> VolumeFromStoredVoxels(std::span<const uint8_t> bytes, VoxelType type,
                                      Endian endian, const VolumeGeometry& geometry,
                                      const VolumeLimits& limits, std::string_view name,
                                      double slope = 1.0, double intercept = 0.0);

// Whether float values seen one by one (Add) are int16 material: all
// integers within 65,536 consecutive integers and +-2^24 (Offset), and if
// not, why (WhyFloat, for the notes).
class IntegerRangeOfFloats {
 public:
  void Add(float v) {
    lo_ = std::min<double>(lo_, v);
    hi_ = std::max<double>(hi_, v);
    integers_ = integers_ && v == std::floor(v);  // NaN and infinities fail here
  }
  std::optional<int32_t> Offset() const;
  std::string WhyFloat() const;

 private:
  bool integers_ = true;
  double lo_ = INFINITY, hi_ = -INFINITY;
};

// Float values (a decoded DICOM stack) as int16 + offset when every one is
// an integer within 65,536 consecutive integers and +-2^24, else as they
// are, with `*float_note` saying why. Checks the budget like ConvertVoxels.
Result<VoxelValues> FloatsToVoxels(std::vector<float> values, const VolumeGeometry& geometry,
                                   const VolumeLimits& limits, std::string* float_note = nullptr);

}  // namespace vpm
