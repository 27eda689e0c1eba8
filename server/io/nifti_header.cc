#include "server/io/nifti_header.h"

#include <cmath>
#include <cstring>
#include <optional>
#include <string_view>

namespace vpm {
namespace {

// NIFTI_TYPE_* codes (nifti1.h), and those we do not decode.
std::optional<VoxelType> NiftiVoxelType(int datatype) {
  switch (datatype) {
    case 2:
      return VoxelType::kUint8;
    case 4:
      return VoxelType::kInt16;
    case 8:
      return VoxelType::kInt32;
    case 16:
      return VoxelType::kFloat32;
    case 64:
      return VoxelType::kFloat64;
    case 256:
      return VoxelType::kInt8;
    case 512:
      return VoxelType::kUint16;
    case 768:
      return VoxelType::kUint32;
    case 1024:
      return VoxelType::kInt64;
    case 1280:
      return VoxelType::kUint64;
    default:
      return std::nullopt;
  }
}

bool IsKnownUnsupportedType(int datatype) {
  // complex64, RGB24, complex128, float128, complex256, RGBA32, binary.
  return datatype == 32 || datatype == 128 || datatype == 1792 || datatype == 1536 ||
         datatype == 2048 || datatype == 2304 || datatype == 1;
}

// Reads fields at the offsets of one header version.
class FieldReader {
 public:
  FieldReader(std::span<const uint8_t> bytes, Endian endian) : bytes_(bytes), endian_(endian) {}
  template <typename T>
  T Get(int64_t offset) const {
    return LoadScalar<T>(bytes_.data() + offset, endian_);
  }

 private:
  std::span<const uint8_t> bytes_;
  Endian endian_;
};

Status CheckMagic(std::span<const uint8_t> bytes, int version) {
  const char* got = reinterpret_cast<const char*>(bytes.data() + (version == 1 ? 344 : 4));
  const int length = version == 1 ? 4 : 8;
  const std::string_view magic(got, length);
  const std::string_view single =
      version == 1 ? std::string_view("n+1\0", 4) : std::string_view("n+2\0\r\n\032\n", 8);
  const std::string_view pair =
      version == 1 ? std::string_view("ni1\0", 4) : std::string_view("ni2\0\r\n\032\n", 8);
  if (magic == single) return absl::OkStatus();
  if (magic == pair) {
    return absl::UnimplementedError(
        "magic says a two-file .hdr/.img pair; only single-file .nii is supported");
  }
  return absl::InvalidArgumentError(
      StrCat("wrong magic for NIfTI-", version, " (expected \"n+", version, "\")"));
}

void ReadFields1(const FieldReader& f, NiftiHeader& h) {
  for (int n = 0; n < 8; ++n) h.dim[n] = f.Get<int16_t>(40 + 2 * n);
  h.datatype = f.Get<int16_t>(70);
  for (int n = 0; n < 8; ++n) h.pixdim[n] = f.Get<float>(76 + 4 * n);
  h.scl_slope = f.Get<float>(112);
  h.scl_inter = f.Get<float>(116);
  h.qform_code = f.Get<int16_t>(252);
  h.sform_code = f.Get<int16_t>(254);
  for (int n = 0; n < 3; ++n) h.quatern[n] = f.Get<float>(256 + 4 * n);
  for (int n = 0; n < 3; ++n) h.qoffset[n] = f.Get<float>(268 + 4 * n);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) h.srow[r][c] = f.Get<float>(280 + 16 * r + 4 * c);
  }
}

void ReadFields2(const FieldReader& f, NiftiHeader& h) {
  h.datatype = f.Get<int16_t>(12);
  for (int n = 0; n < 8; ++n) h.dim[n] = f.Get<int64_t>(16 + 8 * n);
  for (int n = 0; n < 8; ++n) h.pixdim[n] = f.Get<double>(104 + 8 * n);
  h.scl_slope = f.Get<double>(176);
  h.scl_inter = f.Get<double>(184);
  h.qform_code = f.Get<int32_t>(344);
  h.sform_code = f.Get<int32_t>(348);
  for (int n = 0; n < 3; ++n) h.quatern[n] = f.Get<double>(352 + 8 * n);
  for (int n = 0; n < 3; ++n) h.qoffset[n] = f.Get<double>(376 + 8 * n);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) h.srow[r][c] = f.Get<double>(400 + 32 * r + 8 * c);
  }
}

Status CheckDims(const NiftiHeader& h) {
  if (h.dim[0] < 1 || h.dim[0] > 7) {
    return absl::InvalidArgumentError(
        StrCat("dim[0] (the rank) is ", h.dim[0], "; it must be 1..7"));
  }
  for (int n = 1; n <= h.dim[0]; ++n) {
    if (h.dim[n] <= 0) {
      return absl::InvalidArgumentError(
          StrCat("dim[", n, "] is ", h.dim[n], "; it must be positive"));
    }
    if (n >= 4 && h.dim[n] != 1) {
      return absl::UnimplementedError(
          StrCat("dim[", n, "] is ", h.dim[n],
                       "; only 3D scalar volumes are supported (no time series "
                       "or vector components)"));
    }
  }
  return absl::OkStatus();
}

Status CheckDatatype(NiftiHeader& h, int bitpix) {
  const std::optional<VoxelType> type = NiftiVoxelType(h.datatype);
  if (!type.has_value()) {
    if (IsKnownUnsupportedType(h.datatype)) {
      return absl::UnimplementedError(StrCat(
          "datatype ", h.datatype, " (complex, RGB, binary or float128) is not supported"));
    }
    return absl::InvalidArgumentError(StrCat("unknown datatype ", h.datatype));
  }
  h.voxel_type = *type;
  if (bitpix != VoxelTypeSize(*type) * 8) {
    return absl::InvalidArgumentError(StrCat("bitpix is ", bitpix, " but datatype ",
                                                   h.datatype, " (", VoxelTypeName(*type), ") has ",
                                                   VoxelTypeSize(*type) * 8, " bits"));
  }
  return absl::OkStatus();
}

Status ReadVoxOffset(const FieldReader& f, NiftiHeader& h) {
  double offset = 0.0;
  if (h.version == 1) {
    offset = f.Get<float>(108);
  } else {
    const int64_t offset2 = f.Get<int64_t>(168);
    if (offset2 < 0 || offset2 > (int64_t{1} << 50)) {
      return absl::InvalidArgumentError(StrCat("vox_offset ", offset2, " is absurd"));
    }
    offset = static_cast<double>(offset2);
  }
  if (!std::isfinite(offset) || offset < 0.0 || offset != std::floor(offset) || offset > 1e15) {
    return absl::InvalidArgumentError(
        StrCat("vox_offset ", offset, " is not a valid byte offset"));
  }
  h.vox_offset = static_cast<int64_t>(offset);
  if (h.vox_offset < h.header_bytes) {
    return absl::InvalidArgumentError(StrCat(
        "vox_offset ", h.vox_offset, " points inside the ", h.header_bytes, "-byte header"));
  }
  return absl::OkStatus();
}

}  // namespace

Result<NiftiHeader> ParseNiftiHeader(std::span<const uint8_t> bytes) {
  if (static_cast<int64_t>(bytes.size()) < kNifti1HeaderBytes) {
    return absl::InvalidArgumentError(
        StrCat("holds ", bytes.size(),
                     " bytes, less than a 348-byte NIfTI header (truncated or not NIfTI)"));
  }
  NiftiHeader h;
  const int32_t sizeof_le = LoadScalar<int32_t>(bytes.data(), Endian::kLittle);
  const int32_t sizeof_be = LoadScalar<int32_t>(bytes.data(), Endian::kBig);
  if (sizeof_le == 348 || sizeof_be == 348) {
    h.version = 1;
    h.endian = sizeof_le == 348 ? Endian::kLittle : Endian::kBig;
  } else if (sizeof_le == 540 || sizeof_be == 540) {
    h.version = 2;
    h.endian = sizeof_le == 540 ? Endian::kLittle : Endian::kBig;
  } else {
    return absl::InvalidArgumentError(StrCat("not a NIfTI file: sizeof_hdr is ", sizeof_le,
                                                   " (NIfTI-1 has 348, NIfTI-2 540)"));
  }
  h.header_bytes = h.version == 1 ? kNifti1HeaderBytes : kNifti2HeaderBytes;
  if (static_cast<int64_t>(bytes.size()) < h.header_bytes) {
    return absl::InvalidArgumentError(StrCat(
        "holds ", bytes.size(), " bytes, less than the 540-byte NIfTI-2 header (truncated)"));
  }
  RETURN_IF_ERROR(CheckMagic(bytes, h.version));
  const FieldReader f(bytes, h.endian);
  int bitpix = 0;
  if (h.version == 1) {
    ReadFields1(f, h);
    bitpix = f.Get<int16_t>(72);
  } else {
    ReadFields2(f, h);
    bitpix = f.Get<int16_t>(14);
  }
  RETURN_IF_ERROR(CheckDims(h));
  for (int n = static_cast<int>(h.dim[0]) + 1; n < 8; ++n) h.dim[n] = 1;
  RETURN_IF_ERROR(CheckDatatype(h, bitpix));
  RETURN_IF_ERROR(ReadVoxOffset(f, h));
  return h;
}

std::array<double, 2> NiftiScaling(const NiftiHeader& header) {
  if (header.scl_slope == 0.0 || !std::isfinite(header.scl_slope)) return {1.0, 0.0};
  const double intercept = std::isfinite(header.scl_inter) ? header.scl_inter : 0.0;
  return {header.scl_slope, intercept};
}

}  // namespace vpm
