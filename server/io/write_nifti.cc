#include "server/io/write_nifti.h"

#include <cstring>
#include <string>

#include "server/common/write_file.h"
#include "server/io/byte_order.h"
#include "server/io/gzip_stream.h"
#include "server/io/nifti_geometry.h"
#include "server/io/nifti_header.h"

namespace vpm {
namespace {

constexpr int64_t kVoxOffset = 352;  // 348-byte header + 4-byte extension flag
constexpr int16_t kDatatypeInt16 = 4;
constexpr int16_t kDatatypeFloat32 = 16;
constexpr int16_t kXformScannerAnat = 1;
constexpr uint8_t kUnitsMm = 2;

template <typename T>
void Put(std::vector<uint8_t>& out, int64_t offset, T value) {
  StoreScalar<T>(value, out.data() + offset, Endian::kLittle);
}

void PutOrientation(std::vector<uint8_t>& out, const NiftiOrientation& o) {
  for (int n = 0; n < 4; ++n) Put<float>(out, 76 + 4 * n, static_cast<float>(o.pixdim[n]));
  Put<int16_t>(out, 252, kXformScannerAnat);
  Put<int16_t>(out, 254, kXformScannerAnat);
  for (int n = 0; n < 3; ++n) Put<float>(out, 256 + 4 * n, static_cast<float>(o.quatern[n]));
  for (int n = 0; n < 3; ++n) Put<float>(out, 268 + 4 * n, static_cast<float>(o.qoffset[n]));
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) {
      Put<float>(out, 280 + 16 * r + 4 * c, static_cast<float>(o.srow[r][c]));
    }
  }
}

}  // namespace

Result<std::vector<uint8_t>> EncodeNifti(const Volume& volume) {
  const VolumeGeometry& g = volume.geometry();
  for (int a = 0; a < 3; ++a) {
    if (g.dims[a] > 32767) {
      return absl::InvalidArgumentError(StrCat("dimension ", a, " is ", g.dims[a],
                                                     "; NIfTI-1 holds at most 32767 per axis"));
    }
  }
  const int64_t voxels = g.voxel_count();
  const VoxelValues& values = volume.voxels();
  const int64_t bytes_per_voxel = values.bytes_per_voxel();
  std::vector<uint8_t> out(static_cast<size_t>(kVoxOffset + bytes_per_voxel * voxels), 0);
  Put<int32_t>(out, 0, static_cast<int32_t>(kNifti1HeaderBytes));
  out[38] = 'r';  // "regular", as nifti_clib writes
  const int16_t dim[8] = {3,
                          static_cast<int16_t>(g.dims[0]),
                          static_cast<int16_t>(g.dims[1]),
                          static_cast<int16_t>(g.dims[2]),
                          1,
                          1,
                          1,
                          1};
  for (int n = 0; n < 8; ++n) Put<int16_t>(out, 40 + 2 * n, dim[n]);
  Put<int16_t>(out, 70, values.is_int16() ? kDatatypeInt16 : kDatatypeFloat32);
  Put<int16_t>(out, 72, static_cast<int16_t>(8 * bytes_per_voxel));
  Put<float>(out, 108, static_cast<float>(kVoxOffset));
  // scl_slope 1, scl_inter the int16 offset (an integer under 2^24: exact
  // in the header's float), so readers see the values exactly.
  Put<float>(out, 112, 1.0f);
  Put<float>(out, 116, static_cast<float>(values.int16_offset()));
  out[123] = kUnitsMm;
  Put<float>(out, 124, volume.max_value());  // cal_max / cal_min: display window
  Put<float>(out, 128, volume.min_value());
  constexpr char kDescription[] = "vpm";
  std::memcpy(out.data() + 148, kDescription, sizeof(kDescription));
  PutOrientation(out, GeometryToNiftiOrientation(g));
  std::memcpy(out.data() + 344, "n+1\0", 4);
  if (values.is_int16()) {
    const std::span<const int16_t> stored = values.int16s();
    for (int64_t n = 0; n < voxels; ++n) Put<int16_t>(out, kVoxOffset + 2 * n, stored[n]);
  } else {
    const std::span<const float> floats = values.floats();
    for (int64_t n = 0; n < voxels; ++n) Put<float>(out, kVoxOffset + 4 * n, floats[n]);
  }
  return out;
}

Status WriteNifti(const Volume& volume, const std::filesystem::path& path) {
  const std::string name = path.string();
  Result<std::vector<uint8_t>> bytes = EncodeNifti(volume);
  if (!bytes.ok())
    return Status(bytes.status().code(), StrCat(name, ": ", bytes.status().message()));
  if (name.size() >= 3 && name.compare(name.size() - 3, 3, ".gz") == 0) {
    ASSIGN_OR_RETURN(bytes, GzipCompress(*bytes));
  }
  return WriteFile(
      path, std::string_view(reinterpret_cast<const char*>(bytes->data()), bytes->size()));
}

}  // namespace vpm
