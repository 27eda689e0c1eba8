// Headerless raw volumes: the caller says what the bytes are.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string_view>

#include <glm/glm.hpp>

#include "server/common/status.h"
#include "server/io/byte_order.h"
#include "server/volume/volume.h"
#include "server/io/voxel_type.h"

namespace vpm {

struct RawOptions {
  std::array<int64_t, 3> dims{0, 0, 0};  // voxels, x fastest
  VoxelType type = VoxelType::kInt16;
  glm::dvec3 spacing_mm{1.0, 1.0, 1.0};
  Endian endian = Endian::kLittle;
  int64_t header_offset_bytes = 0;  // bytes to skip before the voxels
};

// Reads dims[0] * dims[1] * dims[2] voxels of `options.type` after
// header_offset_bytes. Geometry: the given spacing, identity direction,
// origin 0. The file must hold exactly offset + data bytes: a shorter file
// is truncated, a longer one almost always means wrong dims or type; both
// are InvalidArgument with the sizes in the message. ResourceExhausted over
// `limits` (checked before allocating), NotFound for a missing file.
Result<Volume> ReadRaw(const std::filesystem::path& path, const RawOptions& options,
                       const VolumeLimits& limits);

// The same on bytes; `name` is used in messages and as source.
Result<Volume> ReadRawFromMemory(std::span<const uint8_t> bytes, std::string_view name,
                                 const RawOptions& options, const VolumeLimits& limits);

}  // namespace vpm
