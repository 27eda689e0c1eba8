#include "server/io/read_raw.h"

#include <gtest/gtest.h>

#include "server/io/parse_raw_source.h"
#include "tests/io/io_test_util.h"

namespace vpm {
namespace {

using ::vpm::testing::MakeTempDir;
using ::vpm::testing::WriteBytes;

void ExpectError(const Result<Volume>& v, absl::StatusCode code, const std::string& fragment) {
  ASSERT_FALSE(v.ok());
  EXPECT_EQ(v.status().code(), code) << v.status();
  EXPECT_NE(v.status().message().find(fragment), absl::string_view::npos) << v.status();
}

RawOptions Int16Options() {
  RawOptions o;
  o.dims = {2, 1, 2};
  o.type = VoxelType::kInt16;
  o.spacing_mm = {0.5, 1.0, 2.0};
  return o;
}

TEST(RawReader, ReadsLittleAndBigEndianAfterOffset) {
  const auto dir = MakeTempDir();
  std::vector<uint8_t> little = {0xAA, 0xBB, 0xCC};  // 3 header bytes
  std::vector<uint8_t> big = little;
  for (int16_t v : {1, -2, 300, -32768}) {
    testing::AppendScalar(little, v);
    testing::AppendScalar(big, v, true);
  }
  WriteBytes(dir / "l.raw", little);
  WriteBytes(dir / "b.raw", big);
  RawOptions o = Int16Options();
  o.header_offset_bytes = 3;
  auto l = ReadRaw(dir / "l.raw", o, {});
  ASSERT_TRUE(l.ok()) << l.status();
  o.endian = Endian::kBig;
  auto b = ReadRaw(dir / "b.raw", o, {});
  ASSERT_TRUE(b.ok()) << b.status();
  for (auto* v : {&*l, &*b}) {
    EXPECT_EQ(v->voxels()[1], -2.0f);
    EXPECT_EQ(v->voxels()[3], -32768.0f);
    EXPECT_EQ(v->spacing_mm(), glm::dvec3(0.5, 1.0, 2.0));
    EXPECT_EQ(v->geometry().direction, glm::dmat3(1.0));
  }
}

TEST(RawReader, RejectsTruncatedAndOversizedFiles) {
  const auto dir = MakeTempDir();
  WriteBytes(dir / "short.raw", std::vector<uint8_t>(7, 0));
  ExpectError(ReadRaw(dir / "short.raw", Int16Options(), {}), absl::StatusCode::kInvalidArgument,
              "expected 2x1x2 int16 (8 bytes of data) after 0 header bytes but the file holds 7 "
              "bytes (truncated)");
  WriteBytes(dir / "long.raw", std::vector<uint8_t>(10, 0));
  ExpectError(ReadRaw(dir / "long.raw", Int16Options(), {}), absl::StatusCode::kInvalidArgument,
              "wrong dims");
}

TEST(RawReader, RejectsBadDimsAndSpacing) {
  const auto dir = MakeTempDir();
  WriteBytes(dir / "x.raw", std::vector<uint8_t>(8, 0));
  RawOptions o = Int16Options();
  o.dims = {2, 0, 2};
  ExpectError(ReadRaw(dir / "x.raw", o, {}), absl::StatusCode::kInvalidArgument,
              "dimension y is 0");
  o = Int16Options();
  o.dims = {1 << 20, 1 << 20, 1 << 20};
  ExpectError(ReadRaw(dir / "x.raw", o, {}), absl::StatusCode::kResourceExhausted, "cap");
  o = Int16Options();
  o.spacing_mm.z = std::nan("");
  ExpectError(ReadRaw(dir / "x.raw", o, {}), absl::StatusCode::kInvalidArgument, "spacing z");
  o = Int16Options();
  o.spacing_mm.x = -1;
  ExpectError(ReadRaw(dir / "x.raw", o, {}), absl::StatusCode::kInvalidArgument, "spacing x");
  ExpectError(ReadRaw(dir / "missing.raw", Int16Options(), {}), absl::StatusCode::kNotFound,
              "missing.raw");
}

TEST(RawSource, ParsesAllParameters) {
  auto s = ParseRawSource(
      "raw:/data/ct?v1.bin?dims=4,5,6&type=uint16&spacing=0.5,0.5,1.25"
      "&endian=big&offset=128");
  ASSERT_TRUE(s.ok()) << s.status();
  EXPECT_EQ(s->path, "/data/ct?v1.bin");
  EXPECT_EQ(s->options.dims, (std::array<int64_t, 3>{4, 5, 6}));
  EXPECT_EQ(s->options.type, VoxelType::kUint16);
  EXPECT_EQ(s->options.spacing_mm, glm::dvec3(0.5, 0.5, 1.25));
  EXPECT_EQ(s->options.endian, Endian::kBig);
  EXPECT_EQ(s->options.header_offset_bytes, 128);
  auto d = ParseRawSource("raw:a.raw?type=float&spacing=1,1,1&dims=1,1,1");
  ASSERT_TRUE(d.ok()) << d.status();
  EXPECT_EQ(d->options.type, VoxelType::kFloat32);
  EXPECT_EQ(d->options.endian, Endian::kLittle);
  EXPECT_EQ(d->options.header_offset_bytes, 0);
}

TEST(RawSource, RejectsMalformedSpecs) {
  for (const char* bad :
       {"raw:a.raw", "raw:?dims=1,1,1&type=int8&spacing=1,1,1",
        "raw:a.raw?dims=1,1&type=int8&spacing=1,1,1",
        "raw:a.raw?dims=1,1,1&type=int12&spacing=1,1,1", "raw:a.raw?dims=1,1,1&type=int8",
        "raw:a.raw?dims=1,1,1&type=int8&spacing=1,1,1&colour=red",
        "raw:a.raw?dims=1,1,1&dims=2,2,2&type=int8&spacing=1,1,1",
        "raw:a.raw?dims=1,1,1&type=int8&spacing=1,1,1&endian=middle",
        "raw:a.raw?dims=1,1,1&type=int8&spacing=1,1,1&offset=-4",
        "raw:a.raw?dims=a,b,c&type=int8&spacing=1,1,1", "notraw:x"}) {
    auto s = ParseRawSource(bad);
    EXPECT_FALSE(s.ok()) << bad;
    EXPECT_EQ(s.status().code(), absl::StatusCode::kInvalidArgument) << bad;
  }
}

}  // namespace
}  // namespace vpm
