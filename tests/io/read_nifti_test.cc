#include "server/io/read_nifti.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include <gtest/gtest.h>

#include "server/io/gzip_stream.h"
#include "server/io/nifti_c_api.h"
#include "tests/io/io_test_util.h"

namespace vpm {
namespace {

using ::vpm::testing::MakeTempDir;
using ::vpm::testing::WriteBytes;

// A NIfTI-1 header built with nifti_clib's own struct (an independent check
// of the byte offsets the reader uses): no transform, unit spacing.
nifti_1_header Header1(int nx, int ny, int nz, short datatype, short bitpix) {
  nifti_1_header h;
  std::memset(&h, 0, sizeof(h));
  h.sizeof_hdr = 348;
  h.dim[0] = 3;
  h.dim[1] = static_cast<short>(nx);
  h.dim[2] = static_cast<short>(ny);
  h.dim[3] = static_cast<short>(nz);
  for (int n = 4; n < 8; ++n) h.dim[n] = 1;
  h.datatype = datatype;
  h.bitpix = bitpix;
  for (int n = 0; n < 8; ++n) h.pixdim[n] = 1.0f;
  h.vox_offset = 352.0f;
  std::memcpy(h.magic, "n+1\0", 4);
  return h;
}

std::vector<uint8_t> File1(const nifti_1_header& h, const std::vector<uint8_t>& data) {
  // Sized once: GCC 12 at -O2 misreads an insert after 352 bytes as an
  // out-of-bounds copy (-Warray-bounds).
  std::vector<uint8_t> out(352 + data.size(), 0);
  std::memcpy(out.data(), &h, sizeof(h));
  std::copy(data.begin(), data.end(), out.begin() + 352);
  return out;
}

std::vector<uint8_t> Int16Data(const std::vector<int16_t>& values) {
  std::vector<uint8_t> out;
  for (int16_t v : values) testing::AppendScalar(out, v);
  return out;
}

Result<Volume> ReadBytes(const std::vector<uint8_t>& bytes, const std::string& name,
                         const VolumeLimits& limits = {}) {
  const auto path = MakeTempDir() / name;
  WriteBytes(path, bytes);
  return ReadNifti(path, limits);
}

// The world (LPS) geometry nifti_clib derives from a file, for comparison.
VolumeGeometry LibraryGeometry(const std::filesystem::path& path) {
  nifti_image* image = nifti_image_read(path.c_str(), 0);
  EXPECT_NE(image, nullptr);
  VolumeGeometry g;
  if (image == nullptr) return g;
  const nifti_dmat44& m = image->sform_code > 0 ? image->sto_xyz : image->qto_xyz;
  g.dims = {image->nx, image->ny, image->nz};
  for (int c = 0; c < 3; ++c) {
    glm::dvec3 column(m.m[0][c], m.m[1][c], m.m[2][c]);
    g.spacing_mm[c] = glm::length(column);
    column /= g.spacing_mm[c];
    g.direction[c] = glm::dvec3(-column.x, -column.y, column.z);
  }
  g.origin_mm = glm::dvec3(-m.m[0][3], -m.m[1][3], m.m[2][3]);
  nifti_image_free(image);
  return g;
}

TEST(NiftiReader, AppliesSlopeAndIntercept) {
  nifti_1_header h = Header1(2, 2, 1, DT_INT16, 16);
  h.scl_slope = 2.0f;
  h.scl_inter = -1024.0f;
  auto v = ReadBytes(File1(h, Int16Data({0, 1, 512, -3})), "ct.nii");
  ASSERT_TRUE(v.ok()) << v.status();
  ASSERT_EQ(v->voxels().size(), 4);
  EXPECT_EQ(v->voxels()[0], -1024.0f);
  EXPECT_EQ(v->voxels()[1], -1022.0f);
  EXPECT_EQ(v->voxels()[2], 0.0f);
  EXPECT_EQ(v->voxels()[3], -1030.0f);
}

TEST(NiftiReader, IgnoresZeroSlope) {
  nifti_1_header h = Header1(2, 1, 1, DT_INT16, 16);
  h.scl_slope = 0.0f;
  h.scl_inter = 100.0f;
  auto v = ReadBytes(File1(h, Int16Data({7, -7})), "raw_values.nii");
  ASSERT_TRUE(v.ok()) << v.status();
  EXPECT_EQ(v->voxels()[0], 7.0f);
  EXPECT_EQ(v->voxels()[1], -7.0f);
}

TEST(NiftiReader, NoTransformUsesPixdimInRas) {
  nifti_1_header h = Header1(2, 1, 1, DT_UINT8, 8);
  h.pixdim[1] = 0.5f;
  h.pixdim[2] = 0.75f;
  h.pixdim[3] = 3.0f;
  auto v = ReadBytes(File1(h, {1, 2}), "plain.nii");
  ASSERT_TRUE(v.ok()) << v.status();
  EXPECT_DOUBLE_EQ(v->spacing_mm().x, 0.5);
  EXPECT_DOUBLE_EQ(v->spacing_mm().z, 3.0);
  // RAS axes seen in LPS: x and y flip.
  EXPECT_EQ(v->geometry().direction[0], glm::dvec3(-1, 0, 0));
  EXPECT_EQ(v->geometry().direction[1], glm::dvec3(0, -1, 0));
  EXPECT_EQ(v->geometry().direction[2], glm::dvec3(0, 0, 1));
}

TEST(NiftiReader, QformOnlyFileMatchesNiftiClib) {
  nifti_1_header h = Header1(3, 2, 2, DT_INT16, 16);
  h.qform_code = 1;
  h.sform_code = 0;
  h.quatern_d = static_cast<float>(std::sqrt(0.5));  // 90 degrees about z
  h.qoffset_x = 10.0f;
  h.qoffset_y = 20.0f;
  h.qoffset_z = 30.0f;
  h.pixdim[0] = -1.0f;  // qfac: k axis reversed
  h.pixdim[1] = 0.8f;
  h.pixdim[2] = 0.9f;
  h.pixdim[3] = 2.0f;
  const auto dir = MakeTempDir();
  WriteBytes(dir / "q.nii", File1(h, Int16Data(std::vector<int16_t>(12, 5))));
  auto v = ReadNifti(dir / "q.nii", {});
  ASSERT_TRUE(v.ok()) << v.status();
  const VolumeGeometry& g = v->geometry();
  // RAS: i -> +y, j -> -x, k -> -z; in LPS: i -> -y, j -> +x, k -> -z.
  EXPECT_NEAR(glm::distance(g.direction[0], glm::dvec3(0, -1, 0)), 0.0, 1e-6);
  EXPECT_NEAR(glm::distance(g.direction[1], glm::dvec3(1, 0, 0)), 0.0, 1e-6);
  EXPECT_NEAR(glm::distance(g.direction[2], glm::dvec3(0, 0, -1)), 0.0, 1e-6);
  EXPECT_NEAR(glm::distance(g.origin_mm, glm::dvec3(-10, -20, 30)), 0.0, 1e-6);
  EXPECT_NEAR(g.spacing_mm.y, 0.9, 1e-6);
  testing::ExpectGeometryNear(g, LibraryGeometry(dir / "q.nii"), 1e-5);
}

TEST(NiftiReader, SformTakesPrecedenceOverQform) {
  nifti_1_header h = Header1(2, 2, 2, DT_UINT8, 8);
  h.qform_code = 1;
  h.quatern_d = 1.0f;  // 180 degrees about z: would flip x and y
  h.sform_code = 2;
  const float srow[3][4] = {{0, 0, 3, -5}, {2, 0, 0, 6}, {0, 1.5f, 0, 7}};
  std::memcpy(h.srow_x, srow[0], sizeof(h.srow_x));
  std::memcpy(h.srow_y, srow[1], sizeof(h.srow_y));
  std::memcpy(h.srow_z, srow[2], sizeof(h.srow_z));
  const auto dir = MakeTempDir();
  WriteBytes(dir / "s.nii", File1(h, std::vector<uint8_t>(8, 1)));
  auto v = ReadNifti(dir / "s.nii", {});
  ASSERT_TRUE(v.ok()) << v.status();
  const VolumeGeometry& g = v->geometry();
  EXPECT_DOUBLE_EQ(g.spacing_mm.x, 2.0);
  EXPECT_DOUBLE_EQ(g.spacing_mm.y, 1.5);
  EXPECT_DOUBLE_EQ(g.spacing_mm.z, 3.0);
  EXPECT_EQ(g.direction[0], glm::dvec3(0, -1, 0));  // RAS +y -> LPS -y
  EXPECT_EQ(g.direction[1], glm::dvec3(0, 0, 1));
  EXPECT_EQ(g.direction[2], glm::dvec3(-1, 0, 0));
  EXPECT_EQ(g.origin_mm, glm::dvec3(5, -6, 7));
  testing::ExpectGeometryNear(g, LibraryGeometry(dir / "s.nii"), 1e-6);
}

TEST(NiftiReader, OrthonormalisesShearedSform) {
  nifti_1_header h = Header1(2, 2, 2, DT_UINT8, 8);
  h.sform_code = 1;
  const float srow[3][4] = {{1, 0.1f, 0, 0}, {0, 1, 0, 0}, {0, 0, 2, 0}};
  std::memcpy(h.srow_x, srow[0], sizeof(h.srow_x));
  std::memcpy(h.srow_y, srow[1], sizeof(h.srow_y));
  std::memcpy(h.srow_z, srow[2], sizeof(h.srow_z));
  auto v = ReadBytes(File1(h, std::vector<uint8_t>(8, 1)), "shear.nii");
  ASSERT_TRUE(v.ok()) << v.status();
  const VolumeGeometry& g = v->geometry();
  EXPECT_NEAR(g.spacing_mm.y, std::sqrt(1.0 + 0.01), 1e-6);  // the column norm
  EXPECT_NEAR(g.spacing_mm.z, 2.0, 1e-12);
  const glm::dmat3 gram = glm::transpose(g.direction) * g.direction;
  for (int c = 0; c < 3; ++c) {
    for (int r = 0; r < 3; ++r) EXPECT_NEAR(gram[c][r], r == c ? 1.0 : 0.0, 1e-9);
  }
}

TEST(NiftiReader, ReadsNifti2) {
  nifti_2_header h;
  std::memset(&h, 0, sizeof(h));
  h.sizeof_hdr = 540;
  std::memcpy(h.magic, "n+2\0\r\n\032\n", 8);
  h.datatype = DT_FLOAT32;
  h.bitpix = 32;
  h.dim[0] = 3;
  h.dim[1] = 2;
  h.dim[2] = 1;
  h.dim[3] = 2;
  for (int n = 4; n < 8; ++n) h.dim[n] = 1;
  for (int n = 0; n < 8; ++n) h.pixdim[n] = 1.0;
  h.vox_offset = 544;
  h.scl_slope = 0.5;
  h.sform_code = 1;
  h.srow_x[0] = -0.25;  // RAS -x = LPS +x
  h.srow_y[1] = -0.5;
  h.srow_z[2] = 4.0;
  h.srow_z[3] = -100.0;
  std::vector<uint8_t> bytes(544, 0);
  std::memcpy(bytes.data(), &h, sizeof(h));
  for (float f : {1.0f, 2.0f, 3.0f, -4.0f}) testing::AppendScalar(bytes, f);
  const auto dir = MakeTempDir();
  WriteBytes(dir / "two.nii", bytes);
  auto v = ReadNifti(dir / "two.nii", {});
  ASSERT_TRUE(v.ok()) << v.status();
  EXPECT_EQ(v->dims(), (std::array<int64_t, 3>{2, 1, 2}));
  EXPECT_EQ(v->voxels()[3], -2.0f);
  EXPECT_EQ(v->geometry().direction, glm::dmat3(1.0));
  EXPECT_EQ(v->spacing_mm(), glm::dvec3(0.25, 0.5, 4.0));
  EXPECT_EQ(v->geometry().origin_mm, glm::dvec3(0, 0, -100));
  testing::ExpectGeometryNear(v->geometry(), LibraryGeometry(dir / "two.nii"), 1e-12);
}

TEST(NiftiReader, ReadsBigEndianFile) {
  // A big-endian header and data, written field by field.
  std::vector<uint8_t> bytes(352, 0);
  auto put16 = [&](int offset, int16_t v) {
    std::vector<uint8_t> b;
    testing::AppendScalar(b, v, true);
    std::memcpy(bytes.data() + offset, b.data(), 2);
  };
  auto put32 = [&](int offset, auto v) {
    std::vector<uint8_t> b;
    testing::AppendScalar(b, v, true);
    std::memcpy(bytes.data() + offset, b.data(), 4);
  };
  put32(0, int32_t{348});
  const int16_t dims[8] = {3, 2, 1, 1, 1, 1, 1, 1};
  for (int n = 0; n < 8; ++n) put16(40 + 2 * n, dims[n]);
  put16(70, DT_INT16);
  put16(72, 16);
  for (int n = 0; n < 8; ++n) put32(76 + 4 * n, 1.0f);
  put32(108, 352.0f);
  std::memcpy(bytes.data() + 344, "n+1\0", 4);
  testing::AppendScalar(bytes, int16_t{300}, true);
  testing::AppendScalar(bytes, int16_t{-2}, true);
  auto v = ReadBytes(bytes, "be.nii");
  ASSERT_TRUE(v.ok()) << v.status();
  EXPECT_EQ(v->voxels()[0], 300.0f);
  EXPECT_EQ(v->voxels()[1], -2.0f);
}

TEST(NiftiReader, ReadsGzippedFile) {
  nifti_1_header h = Header1(2, 2, 1, DT_INT16, 16);
  auto gz = GzipCompress(File1(h, Int16Data({1, 2, 3, 4})));
  ASSERT_TRUE(gz.ok());
  auto v = ReadBytes(*gz, "small.nii.gz");
  ASSERT_TRUE(v.ok()) << v.status();
  EXPECT_EQ(v->voxels()[3], 4.0f);
}

TEST(NiftiReader, ReplacesNonFiniteVoxelsByMinimum) {
  nifti_1_header h = Header1(3, 1, 1, DT_FLOAT32, 32);
  std::vector<uint8_t> data;
  for (float f : {5.0f, std::numeric_limits<float>::quiet_NaN(), -2.0f}) {
    testing::AppendScalar(data, f);
  }
  auto v = ReadBytes(File1(h, data), "nan.nii");
  ASSERT_TRUE(v.ok()) << v.status();
  EXPECT_EQ(v->non_finite_count(), 1);
  EXPECT_EQ(v->voxels()[1], -2.0f);
}

// ---- Bad input ----

TEST(NiftiReader, RejectsMissingFile) {
  ExpectError(ReadNifti(MakeTempDir() / "absent.nii", {}), absl::StatusCode::kNotFound,
              "absent.nii");
}

TEST(NiftiReader, RejectsTruncatedFile) {
  nifti_1_header h = Header1(256, 256, 200, DT_INT16, 16);
  ExpectError(ReadBytes(File1(h, std::vector<uint8_t>(1000, 0)), "brain.nii"),
              absl::StatusCode::kInvalidArgument,
              "brain.nii: header says 256x256x200 int16 (26214400 bytes of data) at offset 352 "
              "but the file holds 1352 bytes (truncated)");
}

TEST(NiftiReader, RejectsTruncatedHeader) {
  nifti_1_header h = Header1(2, 2, 2, DT_UINT8, 8);
  std::vector<uint8_t> bytes = File1(h, {});
  bytes.resize(200);
  ExpectError(ReadBytes(bytes, "short.nii"), absl::StatusCode::kInvalidArgument, "truncated");
}

TEST(NiftiReader, RejectsWrongMagic) {
  nifti_1_header h = Header1(2, 1, 1, DT_UINT8, 8);
  std::memcpy(h.magic, "abc\0", 4);
  ExpectError(ReadBytes(File1(h, {0, 0}), "magic.nii"), absl::StatusCode::kInvalidArgument,
              "wrong magic");
}

TEST(NiftiReader, RejectsWrongHeaderSize) {
  nifti_1_header h = Header1(2, 1, 1, DT_UINT8, 8);
  h.sizeof_hdr = 1234;
  ExpectError(ReadBytes(File1(h, {0, 0}), "size.nii"), absl::StatusCode::kInvalidArgument,
              "sizeof_hdr is 1234");
}

TEST(NiftiReader, RejectsHeaderPairMagicAsUnimplemented) {
  nifti_1_header h = Header1(2, 1, 1, DT_UINT8, 8);
  std::memcpy(h.magic, "ni1\0", 4);
  ExpectError(ReadBytes(File1(h, {0, 0}), "pair.nii"), absl::StatusCode::kUnimplemented,
              ".hdr/.img");
}

TEST(NiftiReader, RejectsZeroAndNegativeDims) {
  nifti_1_header h = Header1(2, 0, 1, DT_UINT8, 8);
  ExpectError(ReadBytes(File1(h, {}), "zero.nii"), absl::StatusCode::kInvalidArgument,
              "dim[2] is 0");
  h = Header1(2, 2, -4, DT_UINT8, 8);
  ExpectError(ReadBytes(File1(h, {}), "neg.nii"), absl::StatusCode::kInvalidArgument,
              "dim[3] is -4");
  h = Header1(2, 2, 2, DT_UINT8, 8);
  h.dim[0] = 9;
  ExpectError(ReadBytes(File1(h, {}), "rank.nii"), absl::StatusCode::kInvalidArgument, "dim[0]");
}

TEST(NiftiReader, RejectsAbsurdDimsBeforeAllocating) {
  nifti_1_header h = Header1(32767, 32767, 32767, DT_FLOAT64, 64);
  ExpectError(ReadBytes(File1(h, {1, 2, 3}), "huge.nii"), absl::StatusCode::kResourceExhausted,
              "over the cap");
  h = Header1(600, 600, 600, DT_UINT8, 8);
  VolumeLimits small;
  small.max_volume_bytes = 1000 * 2;  // 1000 int16 voxels
  ExpectError(ReadBytes(File1(h, {1}), "capped.nii", small), absl::StatusCode::kResourceExhausted,
              "cap");
}

TEST(NiftiReader, Rejects4DAsUnimplemented) {
  nifti_1_header h = Header1(2, 2, 2, DT_UINT8, 8);
  h.dim[0] = 4;
  h.dim[4] = 5;
  ExpectError(ReadBytes(File1(h, std::vector<uint8_t>(40, 0)), "fmri.nii"),
              absl::StatusCode::kUnimplemented, "dim[4] is 5");
}

TEST(NiftiReader, RejectsBadSpacing) {
  for (float bad : {0.0f, -1.0f, std::numeric_limits<float>::quiet_NaN()}) {
    nifti_1_header h = Header1(2, 1, 1, DT_UINT8, 8);
    h.pixdim[2] = bad;
    ExpectError(ReadBytes(File1(h, {0, 0}), "spacing.nii"), absl::StatusCode::kInvalidArgument,
                "pixdim[2]");
  }
}

TEST(NiftiReader, RejectsUnknownAndUnsupportedDatatypes) {
  nifti_1_header h = Header1(2, 1, 1, 3, 8);
  ExpectError(ReadBytes(File1(h, {0, 0}), "type.nii"), absl::StatusCode::kInvalidArgument,
              "unknown datatype 3");
  h = Header1(2, 1, 1, DT_COMPLEX64, 64);
  ExpectError(ReadBytes(File1(h, std::vector<uint8_t>(16, 0)), "complex.nii"),
              absl::StatusCode::kUnimplemented, "datatype 32");
  h = Header1(2, 1, 1, DT_INT16, 8);
  ExpectError(ReadBytes(File1(h, {0, 0, 0, 0}), "bitpix.nii"), absl::StatusCode::kInvalidArgument,
              "bitpix is 8");
}

TEST(NiftiReader, RejectsDegenerateSform) {
  nifti_1_header h = Header1(2, 2, 2, DT_UINT8, 8);
  h.sform_code = 1;
  h.srow_x[0] = 1.0f;
  h.srow_y[1] = 1.0f;  // third column all zero
  ExpectError(ReadBytes(File1(h, std::vector<uint8_t>(8, 0)), "flat.nii"),
              absl::StatusCode::kInvalidArgument, "sform column 2");
  h.srow_z[2] = 0.0f;
  h.srow_x[2] = 1.0f;  // third column parallel to the first
  h.srow_y[2] = 0.01f;
  ExpectError(ReadBytes(File1(h, std::vector<uint8_t>(8, 0)), "parallel.nii"),
              absl::StatusCode::kInvalidArgument, "too sheared");
}

TEST(NiftiReader, RejectsNegativeOrHugeVoxOffset) {
  // Found by fuzz_nifti: converting -2.7e21 to int64 was undefined behaviour.
  for (float offset : {-2.7e21f, -352.0f, 1e30f, 352.5f}) {
    nifti_1_header h = Header1(2, 1, 1, DT_UINT8, 8);
    h.vox_offset = offset;
    ExpectError(ReadBytes(File1(h, {0, 0}), "offset.nii"), absl::StatusCode::kInvalidArgument,
                "vox_offset");
  }
}

TEST(NiftiReader, RejectsVoxOffsetInsideHeader) {
  nifti_1_header h = Header1(2, 1, 1, DT_UINT8, 8);
  h.vox_offset = 100.0f;
  ExpectError(ReadBytes(File1(h, {0, 0}), "offset.nii"), absl::StatusCode::kInvalidArgument,
              "vox_offset 100");
}

TEST(NiftiReader, RejectsGzipInflatingPastDeclaredSize) {
  nifti_1_header h = Header1(2, 2, 1, DT_INT16, 16);
  std::vector<uint8_t> bytes = File1(h, Int16Data({1, 2, 3, 4}));
  bytes.resize(bytes.size() + 100000, 0);  // far more than the header declares
  auto gz = GzipCompress(bytes);
  ASSERT_TRUE(gz.ok());
  ExpectError(ReadBytes(*gz, "bomb.nii.gz"), absl::StatusCode::kInvalidArgument,
              "gzip inflates past the declared size");
}

TEST(NiftiReader, RejectsTruncatedGzip) {
  nifti_1_header h = Header1(64, 64, 4, DT_INT16, 16);
  auto gz = GzipCompress(File1(h, std::vector<uint8_t>(64 * 64 * 4 * 2, 7)));
  ASSERT_TRUE(gz.ok());
  gz->resize(gz->size() / 2);
  ExpectError(ReadBytes(*gz, "cut.nii.gz"), absl::StatusCode::kInvalidArgument, "truncated");
}

TEST(NiftiReader, RejectsFileOverByteCap) {
  nifti_1_header h = Header1(16, 16, 16, DT_UINT8, 8);
  VolumeLimits limits;
  limits.max_bytes = 1000;
  ExpectError(ReadBytes(File1(h, std::vector<uint8_t>(4096, 0)), "big.nii", limits),
              absl::StatusCode::kResourceExhausted, "cap of 1000 bytes");
}

}  // namespace
}  // namespace vpm

namespace vpm {
namespace {

std::vector<uint8_t> Uint16Data(const std::vector<uint16_t>& values) {
  std::vector<uint8_t> out;
  for (uint16_t v : values) testing::AppendScalar(out, v);
  return out;
}

TEST(NiftiReader, KeepsIntegerSourcesAsInt16) {
  nifti_1_header h = Header1(2, 2, 1, DT_INT16, 16);
  h.scl_slope = 1.0f;
  h.scl_inter = -1024.0f;
  auto v = ReadBytes(File1(h, Int16Data({0, 1, 4095, -3})), "ct.nii");
  ASSERT_TRUE(v.ok()) << v.status();
  EXPECT_EQ(v->encoding(), VoxelEncoding::kInt16);
  EXPECT_EQ(v->value_bytes(), 4 * 2);
  EXPECT_EQ(v->voxels().ToFloats(), (std::vector<float>{-1024, -1023, 3071, -1027}));
  // Through the general conversion (a slope of 2): int16 too.
  h.scl_slope = 2.0f;
  v = ReadBytes(File1(h, Int16Data({0, 1, 4095, -3})), "ct2.nii");
  ASSERT_TRUE(v.ok()) << v.status();
  EXPECT_EQ(v->encoding(), VoxelEncoding::kInt16);
  EXPECT_EQ(v->voxels().ToFloats(), (std::vector<float>{-1024, -1022, 7166, -1030}));
  EXPECT_TRUE(v->notes().empty());
}

TEST(NiftiReader, KeepsFullRangeUint16AsInt16WithOffset) {
  nifti_1_header h = Header1(3, 1, 1, DT_UINT16, 16);
  auto v = ReadBytes(File1(h, Uint16Data({0, 65535, 40000})), "mri.nii");
  ASSERT_TRUE(v.ok()) << v.status();
  EXPECT_EQ(v->encoding(), VoxelEncoding::kInt16);
  EXPECT_EQ(v->voxels().int16_offset(), 32768);
  EXPECT_EQ(v->voxels().ToFloats(), (std::vector<float>{0, 65535, 40000}));
}

TEST(NiftiReader, KeepsFloatWhenRescaledValuesAreNotIntegersAndSaysSo) {
  nifti_1_header h = Header1(2, 1, 1, DT_INT16, 16);
  h.scl_slope = 0.5f;
  auto v = ReadBytes(File1(h, Int16Data({3, 4})), "scaled.nii");
  ASSERT_TRUE(v.ok()) << v.status();
  EXPECT_EQ(v->encoding(), VoxelEncoding::kFloat32);
  EXPECT_EQ(v->voxels().ToFloats(), (std::vector<float>{1.5f, 2.0f}));
  ASSERT_EQ(v->notes().size(), 1u);
  EXPECT_NE(v->notes()[0].find("float32"), std::string::npos) << v->notes()[0];
  // Float sources stay float without a note.
  h = Header1(2, 1, 1, DT_FLOAT32, 32);
  std::vector<uint8_t> data;
  testing::AppendScalar(data, 1.0f);
  testing::AppendScalar(data, 2.0f);
  v = ReadBytes(File1(h, data), "float.nii");
  ASSERT_TRUE(v.ok()) << v.status();
  EXPECT_EQ(v->encoding(), VoxelEncoding::kFloat32);
  EXPECT_TRUE(v->notes().empty());
}

TEST(NiftiReader, BudgetCountsTwoBytesPerInt16Voxel) {
  nifti_1_header h = Header1(10, 10, 10, DT_INT16, 16);
  VolumeLimits limits;
  limits.max_volume_bytes = 2000;  // exactly 1000 int16 voxels
  EXPECT_TRUE(ReadBytes(File1(h, std::vector<uint8_t>(2000, 0)), "fits.nii", limits).ok());
  h = Header1(10, 10, 10, DT_FLOAT32, 32);
  const Result<Volume> floats =
      ReadBytes(File1(h, std::vector<uint8_t>(4000, 0)), "float.nii", limits);
  EXPECT_EQ(floats.status().code(), absl::StatusCode::kResourceExhausted);
  EXPECT_NE(floats.status().message().find("--max-volume-bytes"), std::string_view::npos)
      << floats.status();
}

}  // namespace
}  // namespace vpm

namespace vpm {
namespace {

// An uncompressed int16 file is read straight into the volume's storage
// (ReadNifti's in-place path); the volume equals the one decoded from the
// file's bytes in memory: values, offset, geometry, source. A file cut short
// inside its voxels still fails as truncated (the in-place path leaves it to
// the decoder).
TEST(NiftiReader, Int16FileReadInPlaceEqualsDecodedFromMemory) {
  nifti_1_header h = Header1(3, 2, 2, DT_INT16, 16);
  h.scl_slope = 1.0f;
  h.scl_inter = -1024.0f;
  h.pixdim[1] = 0.75f;
  h.pixdim[3] = 2.5f;
  const std::vector<uint8_t> bytes =
      File1(h, Int16Data({0, 1, 4095, -3, 7, 8, 9, 10, 11, 12, -32768, 32767}));
  const auto path = testing::MakeTempDir() / "inplace.nii";
  testing::WriteBytes(path, bytes);
  auto file = ReadNifti(path, {});
  auto memory = ReadNiftiFromMemory(bytes, path.string(), {});
  ASSERT_TRUE(file.ok()) << file.status();
  ASSERT_TRUE(memory.ok()) << memory.status();
  EXPECT_EQ(file->encoding(), VoxelEncoding::kInt16);
  EXPECT_EQ(file->voxels().int16_offset(), -1024);
  EXPECT_EQ(file->voxels().ToFloats(), memory->voxels().ToFloats());
  EXPECT_EQ(file->geometry().dims, memory->geometry().dims);
  EXPECT_EQ(file->geometry().spacing_mm, memory->geometry().spacing_mm);
  EXPECT_EQ(file->geometry().origin_mm, memory->geometry().origin_mm);
  EXPECT_EQ(file->geometry().direction, memory->geometry().direction);
  EXPECT_EQ(file->min_value(), -32768.0f - 1024.0f);
  EXPECT_EQ(file->max_value(), 32767.0f - 1024.0f);
  EXPECT_EQ(file->source(), memory->source());
  testing::WriteBytes(path, std::vector<uint8_t>(bytes.begin(), bytes.end() - 3));
  const Result<Volume> cut = ReadNifti(path, {});
  EXPECT_EQ(cut.status().code(), absl::StatusCode::kInvalidArgument) << cut.status();
  EXPECT_NE(cut.status().message().find("truncated"), std::string_view::npos) << cut.status();
}

}  // namespace
}  // namespace vpm
