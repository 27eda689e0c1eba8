#include "server/io/check_dicom_structure.h"

#include <gtest/gtest.h>

#include "server/io/read_dicom_slice.h"
#include "server/io/read_file_bytes.h"
#include "tests/io/dicom_test_util.h"
#include "tests/io/io_test_util.h"

namespace vpm {
namespace {

using ::vpm::testing::AppendScalar;
using ::vpm::testing::DicomSliceSpec;

std::vector<uint8_t> SliceBytes(const DicomSliceSpec& spec) {
  const auto path = ::vpm::testing::MakeTempDir() / "slice.dcm";
  EXPECT_TRUE(::vpm::testing::WriteDicomSlice(path, spec));
  auto bytes = ReadFileBytes(path, {});
  EXPECT_TRUE(bytes.ok());
  return *bytes;
}

// Explicit VR little endian element header with a 4-byte length.
void AppendLongHeader(std::vector<uint8_t>& out, uint16_t group, uint16_t element, const char* vr,
                      uint32_t length) {
  AppendScalar(out, group);
  AppendScalar(out, element);
  out.push_back(static_cast<uint8_t>(vr[0]));
  out.push_back(static_cast<uint8_t>(vr[1]));
  AppendScalar(out, uint16_t{0});
  AppendScalar(out, length);
}

void ExpectStatus(const Status& status, absl::StatusCode code, const std::string& fragment) {
  EXPECT_EQ(status.code(), code) << status;
  EXPECT_NE(status.message().find(fragment), absl::string_view::npos) << status;
}

TEST(DicomStructure, AcceptsWrittenFilesAndReportsSyntax) {
  auto uid = CheckDicomStructure(SliceBytes({}));
  ASSERT_TRUE(uid.ok()) << uid.status();
  EXPECT_EQ(*uid, "1.2.840.10008.1.2.1");
  DicomSliceSpec rle;
  rle.transfer_syntax = EXS_RLELossless;
  EXPECT_TRUE(CheckDicomStructure(SliceBytes(rle)).ok());
}

TEST(DicomStructure, RejectsElementLongerThanTheFile) {
  // Before this check, DCMTK allocated the claimed gigabyte first.
  std::vector<uint8_t> bytes = SliceBytes({});
  AppendLongHeader(bytes, 0x7FE1, 0x0010, "OB", 0x40000000u);
  bytes.resize(bytes.size() + 16, 0);
  ExpectStatus(CheckDicomStructure(bytes).status(), absl::StatusCode::kInvalidArgument,
               "claims 1073741824 bytes but only 16 follow");
  ExpectStatus(ParseDicomFrames(bytes, {}).status(), absl::StatusCode::kInvalidArgument, "claims");
}

TEST(DicomStructure, RejectsDeepNesting) {
  std::vector<uint8_t> bytes = SliceBytes({});
  for (int n = 0; n < kMaxDicomNesting + 2; ++n) {
    AppendLongHeader(bytes, 0x0009, 0x1010, "SQ", 0xFFFFFFFFu);  // undefined length
    AppendScalar(bytes, uint16_t{0xFFFE});
    AppendScalar(bytes, uint16_t{0xE000});
    AppendScalar(bytes, 0xFFFFFFFFu);
  }
  ExpectStatus(CheckDicomStructure(bytes).status(), absl::StatusCode::kInvalidArgument,
               "nest deeper");
}

TEST(DicomStructure, RejectsInvalidVrAndUnknownSyntax) {
  std::vector<uint8_t> bytes = SliceBytes({});
  AppendLongHeader(bytes, 0x0009, 0x0010, "zz", 0);
  ExpectStatus(CheckDicomStructure(bytes).status(), absl::StatusCode::kInvalidArgument,
               "invalid VR");
  bytes = SliceBytes({});
  const std::string syntax = "1.2.840.10008.1.2.1";
  auto at = std::search(bytes.begin(), bytes.end(), syntax.begin(), syntax.end());
  ASSERT_NE(at, bytes.end());
  *(at + 2) = '9';  // 1.9.840...: no such syntax
  ExpectStatus(CheckDicomStructure(bytes).status(), absl::StatusCode::kInvalidArgument,
               "unknown transfer syntax");
}

TEST(DicomStructure, RejectsMetaGroupLengthThatDisagrees) {
  // DCMTK trusts (0002,0000) where the walk follows the group number; a
  // fuzzer input where they differed made DCMTK misparse and allocate 1.3 GB.
  std::vector<uint8_t> bytes = SliceBytes({});
  ASSERT_EQ(bytes[132], 0x02);  // (0002,0000) UL, value at byte 140
  ASSERT_EQ(bytes[133], 0x00);
  bytes[140] = static_cast<uint8_t>(bytes[140] - 3);
  ExpectStatus(CheckDicomStructure(bytes).status(), absl::StatusCode::kInvalidArgument,
               "group length");
}

TEST(DicomStructure, RejectsDeflatedSyntaxAsUnimplemented) {
  DicomSliceSpec spec;
  spec.transfer_syntax = EXS_DeflatedLittleEndianExplicit;
  ExpectStatus(CheckDicomStructure(SliceBytes(spec)).status(), absl::StatusCode::kUnimplemented,
               "Deflated");
}

TEST(DicomSlice, RejectsJpegThatWouldHangDcmtk) {
  DicomSliceSpec spec;
  spec.transfer_syntax = EXS_JPEGProcess14SV1;
  spec.is_signed = false;
  spec.bits_stored = 12;
  std::vector<uint8_t> bytes = SliceBytes(spec);
  const uint8_t soi[] = {0xff, 0xd8, 0xff};
  auto at = std::search(bytes.begin(), bytes.end(), std::begin(soi), std::end(soi));
  ASSERT_NE(at, bytes.end());
  *(at + 3) = 0x01;  // the marker after SOI becomes TEM (FF01)
  ExpectStatus(ParseDicomFrames(bytes, {}).status(), absl::StatusCode::kInvalidArgument,
               "TEM marker");
}

}  // namespace
}  // namespace vpm
