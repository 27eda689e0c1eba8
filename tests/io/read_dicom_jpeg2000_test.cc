// JPEG 2000 DICOM (1.2.840.10008.1.2.4.90 and .91): codestreams made here
// with OpenJPEG's encoder, wrapped by DCMTK as encapsulated pixel data.
#include <openjpeg.h>

#include <algorithm>
#include <cstring>
#include <string>
#include <vector>

#include <dcmtk/config/osconfig.h>  // must come first among DCMTK headers
#include <dcmtk/dcmdata/dcdeftag.h>
#include <dcmtk/dcmdata/dcfilefo.h>
#include <dcmtk/dcmdata/dcpixel.h>
#include <dcmtk/dcmdata/dcpixseq.h>
#include <dcmtk/dcmdata/dcpxitem.h>
#include <gtest/gtest.h>

#include "server/io/decode_jpeg2000.h"
#include "server/io/jpeg2000_frames.h"
#include "server/io/read_dicom_series.h"
#include "tests/io/dicom_test_util.h"
#include "tests/io/io_test_util.h"

namespace vpm {
namespace {

using ::vpm::testing::DicomSliceSpec;
using ::vpm::testing::MakeTempDir;

struct MemoryWriter {
  std::vector<uint8_t> bytes;
  size_t offset = 0;
};

OPJ_SIZE_T Write(void* buffer, OPJ_SIZE_T count, void* user) {
  auto* w = static_cast<MemoryWriter*>(user);
  if (w->bytes.size() < w->offset + count) w->bytes.resize(w->offset + count);
  std::memcpy(w->bytes.data() + w->offset, buffer, count);
  w->offset += count;
  return count;
}
OPJ_OFF_T Skip(OPJ_OFF_T count, void* user) {
  static_cast<MemoryWriter*>(user)->offset += static_cast<size_t>(count);
  return count;
}
OPJ_BOOL Seek(OPJ_OFF_T position, void* user) {
  static_cast<MemoryWriter*>(user)->offset = static_cast<size_t>(position);
  return OPJ_TRUE;
}

// A lossless (reversible 5/3 wavelet) J2K codestream of one greyscale
// component, 16-bit signed samples.
std::vector<uint8_t> EncodeJ2k(const std::vector<int32_t>& samples, int columns, int rows) {
  opj_cparameters_t parameters;
  opj_set_default_encoder_parameters(&parameters);
  parameters.tcp_numlayers = 1;
  parameters.tcp_rates[0] = 0;  // no rate target: lossless
  parameters.cp_disto_alloc = 1;
  parameters.irreversible = 0;
  parameters.numresolution = 1;  // the test images are a few pixels wide
  opj_image_cmptparm_t component{};
  component.dx = component.dy = 1;
  component.w = static_cast<OPJ_UINT32>(columns);
  component.h = static_cast<OPJ_UINT32>(rows);
  component.prec = 16;
  component.sgnd = 1;
  opj_image_t* image = opj_image_create(1, &component, OPJ_CLRSPC_GRAY);
  image->x1 = static_cast<OPJ_UINT32>(columns);
  image->y1 = static_cast<OPJ_UINT32>(rows);
  std::copy(samples.begin(), samples.end(), image->comps[0].data);
  opj_codec_t* codec = opj_create_compress(OPJ_CODEC_J2K);
  MemoryWriter writer;
  opj_stream_t* stream = opj_stream_create(1 << 16, OPJ_FALSE);
  opj_stream_set_user_data(stream, &writer, nullptr);
  opj_stream_set_write_function(stream, Write);
  opj_stream_set_skip_function(stream, Skip);
  opj_stream_set_seek_function(stream, Seek);
  const bool ok = opj_setup_encoder(codec, &parameters, image) &&
                  opj_start_compress(codec, image, stream) && opj_encode(codec, stream) &&
                  opj_end_compress(codec, stream);
  opj_stream_destroy(stream);
  opj_destroy_codec(codec);
  opj_image_destroy(image);
  EXPECT_TRUE(ok) << "OpenJPEG could not encode the test image";
  return writer.bytes;
}

// Encapsulated PixelData: item 0 the Basic Offset Table (`offset_table`,
// empty or little-endian uint32s), then one item per fragment (padded to
// an even length).
void PutEncapsulated(DcmDataset& ds, const std::vector<uint8_t>& offset_table,
                     const std::vector<std::vector<uint8_t>>& fragments, E_TransferSyntax syntax) {
  auto* sequence = new DcmPixelSequence(DCM_PixelSequenceTag);
  auto* table = new DcmPixelItem(DCM_PixelItemTag);
  if (!offset_table.empty()) {
    table->putUint8Array(offset_table.data(), static_cast<unsigned long>(offset_table.size()));
  }
  sequence->insert(table);
  for (std::vector<uint8_t> even : fragments) {
    if (even.size() % 2 != 0) even.push_back(0);  // fragments have even length
    auto* item = new DcmPixelItem(DCM_PixelItemTag);
    item->putUint8Array(even.data(), static_cast<unsigned long>(even.size()));
    sequence->insert(item);
  }
  auto* pixels = new DcmPixelData(DCM_PixelData);
  pixels->putOriginalRepresentation(syntax, nullptr, sequence);
  ds.insert(pixels, true);
}

// A CT slice whose PixelData is `codestream`, encapsulated in `syntax`.
void WriteJpeg2000Slice(const std::filesystem::path& path, DicomSliceSpec s,
                        const std::vector<uint8_t>& codestream, E_TransferSyntax syntax) {
  s.with_pixel_data = false;
  DcmFileFormat file;
  DcmDataset& ds = *file.getDataset();
  testing::FillDicomSlice(ds, s);
  PutEncapsulated(ds, {}, {codestream}, syntax);  // an empty offset table, one fragment
  ASSERT_TRUE(file.saveFile(path.c_str(), syntax).good()) << path;
}

std::vector<int32_t> Samples(int k, int count) {
  std::vector<int32_t> out;
  for (int n = 0; n < count; ++n) out.push_back(-1000 + 300 * k + 7 * n * (n % 3 == 0 ? -1 : 1));
  return out;
}

TEST(DicomJpeg2000, ReadsLosslessAndLossySyntaxesBitExact) {
  for (const E_TransferSyntax syntax : {EXS_JPEG2000LosslessOnly, EXS_JPEG2000}) {
    const auto dir = MakeTempDir() / (syntax == EXS_JPEG2000 ? "91" : "90");
    std::filesystem::create_directories(dir);
    DicomSliceSpec s;
    s.rows = 5;
    s.columns = 6;
    s.intercept = 0.0;
    for (int k = 0; k < 3; ++k) {
      s.position_mm = glm::dvec3(0, 0, 1.5 * k);
      WriteJpeg2000Slice(dir / ("j" + std::to_string(k) + ".dcm"), s,
                         EncodeJ2k(Samples(k, 30), 6, 5), syntax);
    }
    auto v = ReadDicomSeries(dir, {});
    ASSERT_TRUE(v.ok()) << v.status();
    EXPECT_EQ(v->dims(), (std::array<int64_t, 3>{6, 5, 3}));
    for (int k = 0; k < 3; ++k) {
      const std::vector<int32_t> expected = Samples(k, 30);
      for (int n = 0; n < 30; ++n) EXPECT_EQ(v->voxels()[k * 30 + n], expected[n]) << k << " " << n;
    }
  }
}

// A three-frame Enhanced CT (z = 0, 1.5, 3 mm) written twice: natively,
// and in JPEG 2000 lossless with each frame's codestream cut into
// `pieces[f]` fragments of even length, with or without a Basic Offset
// Table. Stored values: Samples(f, 30), 6 x 5 pixels.
constexpr int kFrameColumns = 6, kFrameRows = 5;

// The three frames' Enhanced CT attributes, without PixelData.
bool FillThreeFrames(DcmDataset& ds) {
  DicomSliceSpec s;
  s.rows = kFrameRows;
  s.columns = kFrameColumns;
  return testing::FillEnhancedCt(ds, s, {{{0, 0, 0.0}}, {{0, 0, 1.5}}, {{0, 0, 3.0}}}, false);
}

void WriteNativeFrames(const std::filesystem::path& path) {
  DcmFileFormat file;
  DcmDataset& ds = *file.getDataset();
  ASSERT_TRUE(FillThreeFrames(ds));
  std::vector<Uint16> pixels;
  for (int f = 0; f < 3; ++f) {
    for (int32_t v : Samples(f, kFrameColumns * kFrameRows)) pixels.push_back(static_cast<Uint16>(v));
  }
  ds.putAndInsertUint16Array(DCM_PixelData, pixels.data(), pixels.size());
  ASSERT_TRUE(file.saveFile(path.c_str(), EXS_LittleEndianExplicit).good());
}

void WriteFragmentedJ2kFrames(const std::filesystem::path& path, const std::vector<int>& pieces,
                              bool offset_table) {
  DcmFileFormat file;
  DcmDataset& ds = *file.getDataset();
  ASSERT_TRUE(FillThreeFrames(ds));
  std::vector<std::vector<uint8_t>> fragments;
  std::vector<Uint32> offsets;
  Uint32 at = 0;
  for (int f = 0; f < 3; ++f) {
    std::vector<uint8_t> stream = EncodeJ2k(Samples(f, kFrameColumns * kFrameRows), kFrameColumns,
                                            kFrameRows);
    if (stream.size() % 2 != 0) stream.push_back(0);  // fragments have even length
    offsets.push_back(at);
    const size_t piece = (stream.size() / pieces[f] + 1) & ~size_t{1};
    for (size_t from = 0; from < stream.size(); from += piece) {
      fragments.emplace_back(stream.begin() + from,
                             stream.begin() + std::min(stream.size(), from + piece));
      at += 8 + static_cast<Uint32>(fragments.back().size());
    }
  }
  ASSERT_EQ(fragments.size(), size_t(pieces[0] + pieces[1] + pieces[2]));
  std::vector<uint8_t> table;
  for (Uint32 o : offset_table ? offsets : std::vector<Uint32>{}) {
    for (int b = 0; b < 4; ++b) table.push_back(static_cast<uint8_t>(o >> (8 * b)));  // little-endian
  }
  PutEncapsulated(ds, table, fragments, EXS_JPEG2000LosslessOnly);
  ASSERT_TRUE(file.saveFile(path.c_str(), EXS_JPEG2000LosslessOnly).good()) << path;
}

TEST(DicomJpeg2000, FramesSpanningSeveralFragmentsEqualTheUncompressedFrames) {
  const auto native_dir = MakeTempDir() / "native";
  std::filesystem::create_directories(native_dir);
  WriteNativeFrames(native_dir / "frames.dcm");
  auto native = ReadDicomSeries(native_dir, {});
  ASSERT_TRUE(native.ok()) << native.status();
  ASSERT_EQ(native->dims(), (std::array<int64_t, 3>{kFrameColumns, kFrameRows, 3}));
  // 3 + 1 + 2 and 2 + 2 + 4 fragments; with and without offsets.
  for (const auto& pieces : {std::vector<int>{3, 1, 2}, std::vector<int>{2, 2, 4}}) {
    for (bool offset_table : {true, false}) {
      const auto dir = MakeTempDir() / StrCat("j2k-", pieces[0], pieces[1], pieces[2], "-",
                                              offset_table ? "bot" : "nobot");
      std::filesystem::create_directories(dir);
      WriteFragmentedJ2kFrames(dir / "frames.dcm", pieces, offset_table);
      auto v = ReadDicomSeries(dir, {});
      ASSERT_TRUE(v.ok()) << dir << ": " << v.status();
      ASSERT_EQ(v->dims(), native->dims());
      int64_t differing = 0;
      for (int64_t n = 0; n < v->geometry().voxel_count(); ++n) {
        differing += v->voxels()[n] != native->voxels()[n];
      }
      EXPECT_EQ(differing, 0) << dir;
      EXPECT_FLOAT_EQ(v->At(2, 1, 2), Samples(2, 30)[1 * kFrameColumns + 2] - 1024.0f);
    }
  }
}

TEST(DicomJpeg2000, SplitsFragmentsByOffsetsOrMarkersAndRefusesWhatDoesNotFit) {
  // Two tiny "codestreams": SOC SIZ ... EOC, split over fragments.
  const std::vector<uint8_t> a1{0xff, 0x4f, 0xff, 0x51, 1, 2}, a2{3, 4, 0xff, 0xd9};
  const std::vector<uint8_t> b1{0xff, 0x4f, 0xff, 0x51, 5, 6, 0xff, 0xd9};
  const std::vector<std::span<const uint8_t>> fragments{a1, a2, b1};
  auto by_markers = Jpeg2000FrameCodestreams({}, fragments, 2);
  ASSERT_TRUE(by_markers.ok()) << by_markers.status();
  EXPECT_EQ((*by_markers)[0].size(), 10u);
  EXPECT_EQ((*by_markers)[1], b1);
  // Offsets: frame 1 starts at item 2 = (8 + 6) + (8 + 4) = 26 bytes.
  const std::vector<uint8_t> table{0, 0, 0, 0, 26, 0, 0, 0};
  auto by_table = Jpeg2000FrameCodestreams(table, fragments, 2);
  ASSERT_TRUE(by_table.ok()) << by_table.status();
  EXPECT_EQ(*by_table, *by_markers);
  const std::vector<uint8_t> off_start{0, 0, 0, 0, 20, 0, 0, 0};
  auto bad_table = Jpeg2000FrameCodestreams(off_start, fragments, 2);
  EXPECT_EQ(bad_table.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(bad_table.status().message().find("entry 1 (20 bytes)"), absl::string_view::npos)
      << bad_table.status();
  // Four frames asked of three fragments: two codestreams found.
  auto short_count = Jpeg2000FrameCodestreams({}, fragments, 4);
  EXPECT_EQ(short_count.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(short_count.status().message().find("2 codestreams"), absl::string_view::npos)
      << short_count.status();
  // A fragment starting with SOC SIZ inside an unfinished codestream (no EOC
  // yet) belongs to it.
  const std::vector<uint8_t> c2{0xff, 0x4f, 0xff, 0x51, 0xff, 0xd9};
  const std::vector<std::span<const uint8_t>> inner{a1, c2, b1};
  auto joined = Jpeg2000FrameCodestreams({}, inner, 2);
  ASSERT_TRUE(joined.ok()) << joined.status();
  EXPECT_EQ((*joined)[0].size(), 12u);
}

TEST(DicomJpeg2000, RejectsCorruptOrMismatchedCodestreams) {
  const std::vector<uint8_t> good = EncodeJ2k(Samples(0, 30), 6, 5);
  EXPECT_TRUE(DecodeJpeg2000(good, 6, 5).ok());
  const auto mismatch = DecodeJpeg2000(good, 600, 500);  // the header is believed only if it agrees
  EXPECT_EQ(mismatch.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(mismatch.status().message().find("1 of 600x500"), absl::string_view::npos)
      << mismatch.status();
  std::vector<uint8_t> truncated(good.begin(), good.begin() + good.size() / 2);
  EXPECT_EQ(DecodeJpeg2000(truncated, 6, 5).status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(DecodeJpeg2000(std::vector<uint8_t>(40, 0xff), 6, 5).status().code(),
            absl::StatusCode::kInvalidArgument);

  const auto dir = MakeTempDir();
  DicomSliceSpec s;
  s.rows = 5;
  s.columns = 7;  // the codestream is 6 wide
  WriteJpeg2000Slice(dir / "bad.dcm", s, good, EXS_JPEG2000LosslessOnly);
  auto v = ReadDicomSeries(dir, {});
  ASSERT_FALSE(v.ok());
  EXPECT_NE(v.status().message().find("bad.dcm"), absl::string_view::npos) << v.status();
}

}  // namespace
}  // namespace vpm
