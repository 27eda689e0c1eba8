#include "server/io/read_metaimage.h"

#include <zlib.h>

#include <gtest/gtest.h>

#include "tests/io/io_test_util.h"

namespace vpm {
namespace {

using ::vpm::testing::MakeTempDir;
using ::vpm::testing::ToBytes;
using ::vpm::testing::WriteBytes;

std::vector<uint8_t> Shorts(const std::vector<int16_t>& values, bool big_endian = false) {
  std::vector<uint8_t> out;
  for (int16_t v : values) testing::AppendScalar(out, v, big_endian);
  return out;
}

std::vector<uint8_t> AttachedMetaImage(const std::string& header, const std::vector<uint8_t>& data) {
  std::vector<uint8_t> out = ToBytes(header);
  out.insert(out.end(), data.begin(), data.end());
  return out;
}

// zlib (not gzip) stream, as MetaIO writes CompressedData.
std::vector<uint8_t> Zlib(const std::vector<uint8_t>& data) {
  uLongf size = compressBound(data.size());
  std::vector<uint8_t> out(size);
  EXPECT_EQ(compress(out.data(), &size, data.data(), data.size()), Z_OK);
  out.resize(size);
  return out;
}

Result<Volume> ReadMetaImageFile(const std::string& name, const std::vector<uint8_t>& bytes) {
  const auto path = MakeTempDir() / name;
  WriteBytes(path, bytes);
  return ReadMetaImage(path, {});
}

std::string Header(const std::string& extra, const std::string& type = "MET_SHORT",
                   const std::string& dims = "2 2 1") {
  return StrCat(
      "ObjectType = Image\nNDims = 3\nBinaryData = True\n"
      "BinaryDataByteOrderMSB = False\nDimSize = ",
      dims, "\nElementType = ", type, "\n", extra, "ElementDataFile = LOCAL\n");
}

TEST(MetaImageReader, ReadsAttachedWithTransformOffsetSpacing) {
  // TransformMatrix lists axis directions one after another (as ITK reads):
  // i -> +y, j -> -x, k -> +z.
  const std::string header = Header(
      "TransformMatrix = 0 1 0 -1 0 0 0 0 1\nOffset = -5 6.5 7\nElementSpacing = 0.5 0.75 2\n"
      "AnatomicalOrientation = RAI\n");
  auto v = ReadMetaImageFile("x.mha", AttachedMetaImage(header, Shorts({-1024, 0, 50, 3000})));
  ASSERT_TRUE(v.ok()) << v.status();
  EXPECT_EQ(v->voxels()[0], -1024.0f);
  EXPECT_EQ(v->voxels()[3], 3000.0f);
  EXPECT_EQ(v->geometry().direction[0], glm::dvec3(0, 1, 0));
  EXPECT_EQ(v->geometry().direction[1], glm::dvec3(-1, 0, 0));
  EXPECT_EQ(v->geometry().origin_mm, glm::dvec3(-5, 6.5, 7));
  EXPECT_EQ(v->spacing_mm(), glm::dvec3(0.5, 0.75, 2));
}

TEST(MetaImageReader, ReadsCompressedBigEndian) {
  std::string header = Header("CompressedData = True\n");
  header.replace(header.find("BinaryDataByteOrderMSB = False"), 30,
                 "BinaryDataByteOrderMSB = True");
  auto v = ReadMetaImageFile("c.mha", AttachedMetaImage(header, Zlib(Shorts({1, 2, 3, -4}, true))));
  ASSERT_TRUE(v.ok()) << v.status();
  EXPECT_EQ(v->voxels()[3], -4.0f);
}

TEST(MetaImageReader, ReadsDetachedWithHeaderSize) {
  const auto dir = MakeTempDir();
  testing::WriteText(dir / "v.mhd",
                     "NDims = 2\nDimSize = 3 1\nElementType = MET_UCHAR\nHeaderSize = 4\n"
                     "ElementDataFile = v.raw\n");
  WriteBytes(dir / "v.raw", std::vector<uint8_t>{9, 9, 9, 9, 10, 20, 30});
  auto v = ReadMetaImage(dir / "v.mhd", {});
  ASSERT_TRUE(v.ok()) << v.status();
  EXPECT_EQ(v->dims(), (std::array<int64_t, 3>{3, 1, 1}));
  EXPECT_EQ(v->voxels()[2], 30.0f);
}

TEST(MetaImageReader, ReadsAllElementTypes) {
  struct Case {
    const char* type;
    std::vector<uint8_t> bytes;  // one voxel
    float value;
  };
  std::vector<uint8_t> u32, i32, f32, f64;
  testing::AppendScalar(u32, uint32_t{70000});
  testing::AppendScalar(i32, int32_t{-70000});
  testing::AppendScalar(f32, 2.5f);
  testing::AppendScalar(f64, -8.25);
  const Case cases[] = {{"MET_UCHAR", {200}, 200.0f},
                        {"MET_CHAR", {0xfe}, -2.0f},
                        {"MET_USHORT", {0x10, 0x27}, 10000.0f},
                        {"MET_SHORT", {0xff, 0xff}, -1.0f},
                        {"MET_UINT", u32, 70000.0f},
                        {"MET_INT", i32, -70000.0f},
                        {"MET_FLOAT", f32, 2.5f},
                        {"MET_DOUBLE", f64, -8.25f}};
  for (const Case& c : cases) {
    auto v = ReadMetaImageFile("t.mha", AttachedMetaImage(Header("", c.type, "1 1 1"), c.bytes));
    ASSERT_TRUE(v.ok()) << c.type << ": " << v.status();
    EXPECT_EQ(v->voxels()[0], c.value) << c.type;
  }
}

// ---- Bad input ----

TEST(MetaImageReader, RejectsMissingFile) {
  ExpectError(ReadMetaImage(MakeTempDir() / "none.mha", {}), absl::StatusCode::kNotFound,
              "none.mha");
}

TEST(MetaImageReader, RejectsTruncatedData) {
  ExpectError(ReadMetaImageFile("t.mha", AttachedMetaImage(Header(""), {1, 2, 3})),
              absl::StatusCode::kInvalidArgument,
              "t.mha: header says 2x2x1 int16 (8 bytes of data) but the file holds 3 bytes");
  ExpectError(ReadMetaImageFile("nohdr.mha", ToBytes("NDims = 3\nDimSize = 1 1 1\n")),
              absl::StatusCode::kInvalidArgument, "no ElementDataFile");
}

TEST(MetaImageReader, RejectsNonMetaImageText) {
  ExpectError(ReadMetaImageFile("png.mha", {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'}),
              absl::StatusCode::kInvalidArgument, "not \"Key = Value\"");
}

TEST(MetaImageReader, RejectsBadDims) {
  ExpectError(ReadMetaImageFile("z.mha", AttachedMetaImage(Header("", "MET_UCHAR", "2 0 1"), {})),
              absl::StatusCode::kInvalidArgument, "dimension y is 0");
  ExpectError(ReadMetaImageFile("n.mha", AttachedMetaImage(Header("", "MET_UCHAR", "2 2 -1"), {})),
              absl::StatusCode::kInvalidArgument, "dimension z is -1");
  ExpectError(ReadMetaImageFile("h.mha", AttachedMetaImage(Header("", "MET_UCHAR", "99999 99999 99999"), {})),
              absl::StatusCode::kResourceExhausted, "cap");
  ExpectError(ReadMetaImageFile("c.mha", AttachedMetaImage(Header("", "MET_UCHAR", "2 2"), {})),
              absl::StatusCode::kInvalidArgument, "DimSize lists 2");
}

TEST(MetaImageReader, RejectsBadSpacing) {
  for (const char* spacing : {"1 0 1", "1 -1 1", "1 nan 1"}) {
    ExpectError(ReadMetaImageFile("s.mha", AttachedMetaImage(Header(StrCat("ElementSpacing = ", spacing, "\n"),
                                                  "MET_UCHAR", "1 1 1"),
                                           {0})),
                absl::StatusCode::kInvalidArgument, "spacing y");
  }
}

TEST(MetaImageReader, RejectsNonOrthonormalTransform) {
  ExpectError(
      ReadMetaImageFile(
          "o.mha",
          AttachedMetaImage(Header("TransformMatrix = 1 0 0 1 1 0 0 0 1\n", "MET_UCHAR", "1 1 1"), {0})),
      absl::StatusCode::kInvalidArgument, "not orthonormal");
}

TEST(MetaImageReader, RejectsUnknownAndUnsupportedTypes) {
  ExpectError(ReadMetaImageFile("u.mha", AttachedMetaImage(Header("", "FLOAT", "1 1 1"), {0, 0, 0, 0})),
              absl::StatusCode::kInvalidArgument, "unknown ElementType");
  ExpectError(ReadMetaImageFile("a.mha", AttachedMetaImage(Header("", "MET_FLOAT_ARRAY", "1 1 1"), {0, 0, 0, 0})),
              absl::StatusCode::kUnimplemented, "MET_FLOAT_ARRAY");
  ExpectError(ReadMetaImageFile("ch.mha", AttachedMetaImage(Header("ElementNumberOfChannels = 3\n"), {})),
              absl::StatusCode::kUnimplemented, "ElementNumberOfChannels");
  ExpectError(ReadMetaImageFile("l.mha", ToBytes("NDims = 3\nDimSize = 1 1 1\nElementType = MET_UCHAR\n"
                                        "ElementDataFile = LIST\n")),
              absl::StatusCode::kUnimplemented, "LIST");
}

TEST(MetaImageReader, RejectsCompressedDataPastDeclaredSize) {
  const std::string header = Header("CompressedData = True\n", "MET_UCHAR", "2 2 2");
  ExpectError(ReadMetaImageFile("bomb.mha", AttachedMetaImage(header, Zlib(std::vector<uint8_t>(50000, 1)))),
              absl::StatusCode::kInvalidArgument, "zlib data inflates past the declared size");
  ExpectError(ReadMetaImageFile("corrupt.mha", AttachedMetaImage(header, {1, 2, 3, 4, 5})),
              absl::StatusCode::kInvalidArgument, "corrupt");
}

}  // namespace
}  // namespace vpm
