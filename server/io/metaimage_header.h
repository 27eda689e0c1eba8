// The MetaImage header (ITK's .mha / .mhd, "Key = Value" lines), parsed from
// text. Written here rather than with ITK's MetaIO, which is not packaged
// apart from ITK and, like teem, allocates what the header claims.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "server/common/status.h"
#include "server/io/byte_order.h"
#include "server/io/voxel_type.h"

namespace vpm {

struct MetaImageHeader {
  int ndims = 0;
  std::vector<int64_t> dim_size;       // DimSize, fastest first
  VoxelType type = VoxelType::kUint8;  // ElementType
  Endian endian = Endian::kLittle;     // ElementByteOrderMSB / BinaryDataByteOrderMSB
  std::vector<double> spacing;         // ElementSpacing (else ElementSize); empty: 1
  std::vector<double> offset;          // Offset / Origin / Position; empty: 0
  std::vector<double> transform;       // TransformMatrix / Rotation / Orientation
  bool compressed = false;             // CompressedData (zlib or gzip)
  int64_t compressed_size = -1;        // CompressedDataSize; -1: unknown
  int64_t header_size = 0;             // HeaderSize (detached data); -1: data ends the file
  std::string data_file;               // ElementDataFile: "LOCAL" or a file name
  int64_t data_offset = 0;             // LOCAL: first byte after the header
};

// Parses the header at the start of `bytes`; it ends with the ElementDataFile
// line. InvalidArgument for malformed headers; Unimplemented for valid
// features we do not read (ASCII data, several channels, LIST data files,
// array element types).
Result<MetaImageHeader> ParseMetaImageHeader(std::span<const uint8_t> bytes);

}  // namespace vpm
