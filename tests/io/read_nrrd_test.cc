#include "server/io/read_nrrd.h"

#include <gtest/gtest.h>

#include "server/io/gzip_stream.h"
#include "tests/io/io_test_util.h"

namespace vpm {
namespace {

using ::vpm::testing::MakeTempDir;
using ::vpm::testing::ToBytes;
using ::vpm::testing::WriteBytes;

std::vector<uint8_t> Int16Le(const std::vector<int16_t>& values, bool big_endian = false) {
  std::vector<uint8_t> out;
  for (int16_t v : values) testing::AppendScalar(out, v, big_endian);
  return out;
}

std::vector<uint8_t> AttachedNrrd(const std::string& header, const std::vector<uint8_t>& data) {
  std::vector<uint8_t> out = ToBytes(header + "\n");
  out.insert(out.end(), data.begin(), data.end());
  return out;
}

Result<Volume> ReadNrrdFile(const std::string& name, const std::vector<uint8_t>& bytes,
                        const VolumeLimits& limits = {}) {
  const auto path = MakeTempDir() / name;
  WriteBytes(path, bytes);
  return ReadNrrd(path, limits);
}

const char kRasHeader[] =
    "NRRD0004\n"
    "# a comment\n"
    "type: short\n"
    "dimension: 3\n"
    "space: right-anterior-superior\n"
    "sizes: 2 2 1\n"
    "space directions: (0,0.5,0) (-2,0,0) (0,0,3)\n"
    "space origin: (10,20,30)\n"
    "kinds: domain domain domain\n"
    "endian: little\n"
    "encoding: raw\n"
    "meta key:=ignored value\n";

TEST(NrrdReader, ReadsAttachedRawAndConvertsRasToLps) {
  auto v = ReadNrrdFile("ras.nrrd", AttachedNrrd(kRasHeader, Int16Le({1, -2, 3, 400})));
  ASSERT_TRUE(v.ok()) << v.status();
  EXPECT_EQ(v->dims(), (std::array<int64_t, 3>{2, 2, 1}));
  EXPECT_EQ(v->voxels()[1], -2.0f);
  EXPECT_EQ(v->voxels()[3], 400.0f);
  EXPECT_EQ(v->spacing_mm(), glm::dvec3(0.5, 2.0, 3.0));
  EXPECT_EQ(v->geometry().direction[0], glm::dvec3(0, -1, 0));  // RAS +y = LPS -y
  EXPECT_EQ(v->geometry().direction[1], glm::dvec3(1, 0, 0));   // RAS -x = LPS +x
  EXPECT_EQ(v->geometry().direction[2], glm::dvec3(0, 0, 1));
  EXPECT_EQ(v->geometry().origin_mm, glm::dvec3(-10, -20, 30));
}

TEST(NrrdReader, ReadsGzipBigEndianWithLps) {
  const std::string header =
      "NRRD0005\ntype: int16\ndimension: 3\nspace: left-posterior-superior\nsizes: 3 1 1\n"
      "space directions: (1.5,0,0) (0,1.5,0) (0,0,2)\nspace origin: (-1,-2,-3)\n"
      "endian: big\nencoding: gzip\n";
  auto gz = GzipCompress(Int16Le({-1000, 0, 1000}, true));
  ASSERT_TRUE(gz.ok());
  auto v = ReadNrrdFile("lps.nrrd", AttachedNrrd(header, *gz));
  ASSERT_TRUE(v.ok()) << v.status();
  EXPECT_EQ(v->voxels()[0], -1000.0f);
  EXPECT_EQ(v->voxels()[2], 1000.0f);
  EXPECT_EQ(v->geometry().origin_mm, glm::dvec3(-1, -2, -3));
  EXPECT_EQ(v->geometry().direction, glm::dmat3(1.0));
}

TEST(NrrdReader, ReadsDetachedHeaderWithSpacingsAndSkips) {
  const auto dir = MakeTempDir();
  testing::WriteText(dir / "vol.nhdr",
                     "NRRD0004\ntype: float\ndimension: 2\nsizes: 2 2\nspacings: 0.25 4\n"
                     "endian: little\nencoding: raw\ndata file: vol.raw\nline skip: 1\n"
                     "byte skip: 2\n");
  std::vector<uint8_t> data = ToBytes("junk line\nXX");
  for (float f : {1.5f, 2.5f, -3.5f, 4.5f}) testing::AppendScalar(data, f);
  WriteBytes(dir / "vol.raw", data);
  auto v = ReadNrrd(dir / "vol.nhdr", {});
  ASSERT_TRUE(v.ok()) << v.status();
  EXPECT_EQ(v->dims(), (std::array<int64_t, 3>{2, 2, 1}));
  EXPECT_EQ(v->spacing_mm(), glm::dvec3(0.25, 4.0, 1.0));
  EXPECT_EQ(v->voxels()[2], -3.5f);
}

TEST(NrrdReader, ReadsAllIntegerTypesAndAscii) {
  struct Case {
    const char* type;
    std::vector<uint8_t> data;
    float last;
  };
  std::vector<uint8_t> u32, i32, f64;
  testing::AppendScalar(u32, uint32_t{7});
  testing::AppendScalar(u32, uint32_t{4000000000u});
  testing::AppendScalar(i32, int32_t{-7});
  testing::AppendScalar(i32, int32_t{-100000});
  testing::AppendScalar(f64, 0.5);
  testing::AppendScalar(f64, -0.25);
  const Case cases[] = {{"uchar", {1, 255}, 255.0f},
                        {"signed char", {1, 0xff}, -1.0f},
                        {"ushort", {0, 0, 0xff, 0xff}, 65535.0f},
                        {"uint", u32, 4e9f},
                        {"int32", i32, -100000.0f},
                        {"double", f64, -0.25f}};
  for (const Case& c : cases) {
    const std::string header = StrCat("NRRD0004\ntype: ", c.type,
                                            "\ndimension: 2\nsizes: 2 1\nendian: little\n"
                                            "encoding: raw\n");
    auto v = ReadNrrdFile("t.nrrd", AttachedNrrd(header, c.data));
    ASSERT_TRUE(v.ok()) << c.type << ": " << v.status();
    EXPECT_EQ(v->voxels()[1], c.last) << c.type;
  }
  auto v = ReadNrrdFile("a.nrrd", AttachedNrrd("NRRD0004\ntype: float\ndimension: 2\nsizes: 3 1\n"
                                       "encoding: ascii\n",
                                       ToBytes("1.5 -2\n 3e2\n")));
  ASSERT_TRUE(v.ok()) << v.status();
  EXPECT_EQ(v->voxels()[2], 300.0f);
}

// ---- Bad input ----

TEST(NrrdReader, RejectsMissingFile) {
  ExpectError(ReadNrrd(MakeTempDir() / "gone.nrrd", {}), absl::StatusCode::kNotFound, "gone.nrrd");
}

TEST(NrrdReader, RejectsWrongMagic) {
  ExpectError(ReadNrrdFile("m.nrrd", ToBytes("NRRD9999\ntype: short\n\n")),
              absl::StatusCode::kInvalidArgument, "wrong magic");
}

TEST(NrrdReader, RejectsTruncatedData) {
  ExpectError(ReadNrrdFile("short.nrrd", AttachedNrrd(kRasHeader, {1, 2, 3})),
              absl::StatusCode::kInvalidArgument,
              "short.nrrd: header says 2x2x1 int16 (8 bytes of data)");
  ExpectError(ReadNrrdFile("short.nrrd", AttachedNrrd(kRasHeader, {1, 2, 3})),
              absl::StatusCode::kInvalidArgument, "(truncated)");
}

TEST(NrrdReader, RejectsTruncatedHeader) {
  ExpectError(ReadNrrdFile("h.nrrd", ToBytes("NRRD0004\ntype: short\ndimension: 3\n")),
              absl::StatusCode::kInvalidArgument, "blank line");
}

TEST(NrrdReader, RejectsBadDims) {
  std::string h = kRasHeader;
  h.replace(h.find("sizes: 2 2 1"), 12, "sizes: 2 0 1");
  ExpectError(ReadNrrdFile("zero.nrrd", AttachedNrrd(h, {})), absl::StatusCode::kInvalidArgument,
              "dimension y is 0");
  h = kRasHeader;
  h.replace(h.find("sizes: 2 2 1"), 12, "sizes: 2 -5 1");
  ExpectError(ReadNrrdFile("neg.nrrd", AttachedNrrd(h, {})), absl::StatusCode::kInvalidArgument,
              "dimension y is -5");
  h = kRasHeader;
  h.replace(h.find("sizes: 2 2 1"), 12, "sizes: 100000 100000 100000");
  ExpectError(ReadNrrdFile("huge.nrrd", AttachedNrrd(h, {})), absl::StatusCode::kResourceExhausted, "cap");
  h = kRasHeader;
  h.replace(h.find("sizes: 2 2 1"), 12, "sizes: 2 2");
  ExpectError(ReadNrrdFile("count.nrrd", AttachedNrrd(h, {})), absl::StatusCode::kInvalidArgument,
              "sizes lists 2 axes");
}

TEST(NrrdReader, RejectsBadSpacing) {
  for (const char* spacings : {"1 0 1", "1 -2 1", "1 nan 1"}) {
    const std::string header =
        StrCat("NRRD0004\ntype: uchar\ndimension: 3\nsizes: 1 1 1\nspacings: ", spacings,
                     "\nencoding: raw\n");
    ExpectError(ReadNrrdFile("s.nrrd", AttachedNrrd(header, {0})), absl::StatusCode::kInvalidArgument,
                "spacing y");
  }
  std::string h = kRasHeader;
  h.replace(h.find("(-2,0,0)"), 8, "(0,0,0)");
  ExpectError(ReadNrrdFile("d.nrrd", AttachedNrrd(h, Int16Le({1, 2, 3, 4}))),
              absl::StatusCode::kInvalidArgument, "length 0");
}

TEST(NrrdReader, RejectsNonOrthonormalDirections) {
  std::string h = kRasHeader;
  h.replace(h.find("(-2,0,0)"), 8, "(-2,1,0)");
  ExpectError(ReadNrrdFile("skew.nrrd", AttachedNrrd(h, Int16Le({1, 2, 3, 4}))),
              absl::StatusCode::kInvalidArgument, "not orthonormal");
}

TEST(NrrdReader, RejectsUnknownAndUnsupportedTypes) {
  ExpectError(ReadNrrdFile("t.nrrd", AttachedNrrd("NRRD0004\ntype: quaternion\ndimension: 2\nsizes: 1 1\n"
                                          "encoding: raw\n",
                                          {0})),
              absl::StatusCode::kInvalidArgument, "unknown type");
  ExpectError(ReadNrrdFile("b.nrrd", AttachedNrrd("NRRD0004\ntype: block\ndimension: 2\nsizes: 1 1\n"
                                          "encoding: raw\n",
                                          {0})),
              absl::StatusCode::kUnimplemented, "block");
  ExpectError(ReadNrrdFile("z.nrrd", AttachedNrrd("NRRD0004\ntype: uchar\ndimension: 2\nsizes: 1 1\n"
                                          "encoding: bzip2\n",
                                          {0})),
              absl::StatusCode::kUnimplemented, "bzip2");
  ExpectError(ReadNrrdFile("e.nrrd", AttachedNrrd("NRRD0004\ntype: short\ndimension: 2\nsizes: 1 1\n"
                                          "encoding: raw\n",
                                          {0, 0})),
              absl::StatusCode::kInvalidArgument, "endian is missing");
}

TEST(NrrdReader, RejectsVectorAnd4DDataAsUnimplemented) {
  ExpectError(ReadNrrdFile("4d.nrrd", AttachedNrrd("NRRD0004\ntype: uchar\ndimension: 4\nsizes: 1 1 1 2\n"
                                           "encoding: raw\n",
                                           {0, 0})),
              absl::StatusCode::kUnimplemented, "dimension is 4");
  ExpectError(ReadNrrdFile("rgb.nrrd", AttachedNrrd("NRRD0004\ntype: uchar\ndimension: 3\nsizes: 3 1 1\n"
                                            "kinds: RGB-color domain domain\nencoding: raw\n",
                                            {0, 0, 0})),
              absl::StatusCode::kUnimplemented, "RGB-color");
  ExpectError(ReadNrrdFile("sp.nrrd", AttachedNrrd("NRRD0004\ntype: uchar\ndimension: 2\nsizes: 1 1\n"
                                           "space: scanner-xyz\nencoding: raw\n",
                                           {0})),
              absl::StatusCode::kUnimplemented, "scanner-xyz");
}

TEST(NrrdReader, RejectsGzipInflatingPastDeclaredSize) {
  auto gz = GzipCompress(std::vector<uint8_t>(100000, 0));
  ASSERT_TRUE(gz.ok());
  const std::string header = "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: gzip\n";
  ExpectError(ReadNrrdFile("bomb.nrrd", AttachedNrrd(header, *gz)), absl::StatusCode::kInvalidArgument,
              "gzip inflates past the declared size");
}

TEST(NrrdReader, RejectsDetachedFileOutsideFolder) {
  const auto dir = MakeTempDir();
  testing::WriteText(dir / "evil.nhdr",
                     "NRRD0004\ntype: uchar\ndimension: 2\nsizes: 1 1\nencoding: raw\n"
                     "data file: ../secret.raw\n");
  ExpectError(ReadNrrd(dir / "evil.nhdr", {}), absl::StatusCode::kInvalidArgument,
              "must not leave");
  testing::WriteText(dir / "abs.nhdr",
                     "NRRD0004\ntype: uchar\ndimension: 2\nsizes: 1 1\nencoding: raw\n"
                     "data file: /etc/passwd\n");
  ExpectError(ReadNrrd(dir / "abs.nhdr", {}), absl::StatusCode::kInvalidArgument, "relative");
  testing::WriteText(dir / "missing.nhdr",
                     "NRRD0004\ntype: uchar\ndimension: 2\nsizes: 1 1\nencoding: raw\n"
                     "data file: nothing.raw\n");
  ExpectError(ReadNrrd(dir / "missing.nhdr", {}), absl::StatusCode::kNotFound, "nothing.raw");
}

TEST(NrrdReader, RejectsDuplicateAndMalformedFields) {
  ExpectError(ReadNrrdFile("dup.nrrd", AttachedNrrd("NRRD0004\ntype: uchar\ntype: short\n", {})),
              absl::StatusCode::kInvalidArgument, "appears twice");
  ExpectError(ReadNrrdFile("bad.nrrd", AttachedNrrd("NRRD0004\nsizes: 2 x\n", {})),
              absl::StatusCode::kInvalidArgument, "not an integer");
  ExpectError(ReadNrrdFile("vec.nrrd", AttachedNrrd("NRRD0004\nspace origin: (1,2\n", {})),
              absl::StatusCode::kInvalidArgument, "space origin");
}

}  // namespace
}  // namespace vpm
