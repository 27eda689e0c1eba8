// The NIfTI-1 / NIfTI-2 header, parsed and checked from raw bytes.
//
// Why not nifti_image_read (nifti_clib)? It is the reference reader, but on a
// hostile header it allocates whatever dims * bitpix says before looking at
// the file size, prints to stderr, and on some paths calls exit(). Making it
// safe means parsing and checking the header first: once that is done, the
// data is a plain array at vox_offset, and handing it to the library again
// would only add a second read of the file (which may have changed since) and
// no in-memory entry point for the fuzzer. So the header is parsed here from
// explicit byte offsets of the standard; the library is kept for its
// reference geometry math (quaternions, polar decomposition) and, in tests,
// as an independent reader of what WriteNifti writes.
#pragma once

#include <array>
#include <cstdint>
#include <span>

#include "server/common/status.h"
#include "server/io/byte_order.h"
#include "server/io/voxel_type.h"

namespace vpm {

inline constexpr int64_t kNifti1HeaderBytes = 348;
inline constexpr int64_t kNifti2HeaderBytes = 540;

struct NiftiHeader {
  int version = 1;                  // 1 or 2
  Endian endian = Endian::kLittle;  // of the header and the data
  int64_t header_bytes = kNifti1HeaderBytes;
  std::array<int64_t, 8> dim{};    // dim[0] = rank (1..7); dim[1..3] > 0
  std::array<double, 8> pixdim{};  // pixdim[0] = qfac; pixdim[1..3] in mm
  int64_t vox_offset = 0;          // byte offset of the data in the .nii
  int datatype = 0;                // NIFTI_TYPE_* code
  VoxelType voxel_type = VoxelType::kUint8;
  double scl_slope = 0.0;
  double scl_inter = 0.0;
  int qform_code = 0;
  int sform_code = 0;
  std::array<double, 3> quatern{};              // b, c, d
  std::array<double, 3> qoffset{};              // x, y, z (RAS, mm)
  std::array<std::array<double, 4>, 3> srow{};  // RAS affine rows (mm)
};

// Parses the header at the start of `bytes` (the first 348 bytes for NIfTI-1,
// 540 for NIfTI-2; more is fine). Checks sizeof_hdr (either byte order), the
// magic, rank and dims (positive; dims 4..7 must be 1), datatype vs bitpix,
// and vox_offset. Errors: InvalidArgument for malformed headers, Unimplemented
// for valid but unsupported ones (two-file .hdr/.img, 4D, complex or RGB).
Result<NiftiHeader> ParseNiftiHeader(std::span<const uint8_t> bytes);

// Linear scaling to apply to stored values: (slope, intercept), or (1, 0)
// where scl_slope is 0 or not finite, as the standard says.
std::array<double, 2> NiftiScaling(const NiftiHeader& header);

}  // namespace vpm
