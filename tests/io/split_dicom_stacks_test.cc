// Several stacks in one DICOM series (planes, or echoes at the same
// positions): the split (SplitDicomStacks) and what the series reader makes
// of it.
#include "server/io/split_dicom_stacks.h"

#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "server/io/list_dicom_series.h"
#include "server/io/parse_dicom_source.h"
#include "server/io/read_dicom_series.h"
#include "tests/io/dicom_test_util.h"
#include "tests/io/io_test_util.h"

namespace vpm {
namespace {

using ::vpm::testing::DicomSliceSpec;
using ::vpm::testing::MakeTempDir;
using ::vpm::testing::WriteDicomSlice;

// Axial images at z = 0, 2, 4, ... mm, each with the attributes `a`.
std::vector<StackImage> AxialFiles(int count, const DicomStackAttributes& a) {
  std::vector<StackImage> files;
  for (int k = 0; k < count; ++k) {
    files.push_back({.attributes = a, .position_mm = glm::dvec3(0.0, 0.0, 2.0 * k)});
  }
  return files;
}

std::vector<std::string> Labels(const std::vector<DicomStack>& stacks) {
  std::vector<std::string> out;
  for (const DicomStack& s : stacks) out.push_back(s.label);
  return out;
}

TEST(SplitDicomStacks, DistinctPositionsAreOneStackWhateverTheAttributesSay) {
  // A sequential CT numbers each rotation's images as an acquisition of its
  // own: nothing repeats, so nothing is split.
  std::vector<StackImage> files = AxialFiles(6, {});
  for (size_t f = 0; f < files.size(); ++f) {
    files[f].attributes.acquisition_number = std::to_string(f / 2 + 1);
  }
  const std::vector<DicomStack> stacks = SplitDicomStacks(files);
  ASSERT_EQ(stacks.size(), 1u);
  EXPECT_EQ(stacks[0].label, "");
  EXPECT_EQ(stacks[0].images, (std::vector<size_t>{0, 1, 2, 3, 4, 5}));
}

TEST(SplitDicomStacks, TwoEchoesAtTheSamePositionsAreTwoStacksInEchoOrder) {
  // Echo 2 listed first, and with EchoNumbers as text ("10" sorts before
  // "2"): the order is numeric.
  std::vector<StackImage> files = AxialFiles(3, {.echo_numbers = "10", .echo_time = "4.6"});
  for (StackImage f : AxialFiles(3, {.echo_numbers = "2", .echo_time = "2.3"})) files.push_back(f);
  const std::vector<DicomStack> stacks = SplitDicomStacks(files);
  EXPECT_EQ(Labels(stacks), (std::vector<std::string>{"EchoNumbers 2", "EchoNumbers 10"}));
  ASSERT_EQ(stacks.size(), 2u);
  EXPECT_EQ(stacks[0].images, (std::vector<size_t>{3, 4, 5}));
  EXPECT_EQ(stacks[1].images, (std::vector<size_t>{0, 1, 2}));
}

TEST(SplitDicomStacks, ImagesInSeveralPlanesAreOneStackPerPlaneTheLargestFirst) {
  // A three-plane localizer, interleaved: 3 axial (one of them written with
  // the normal flipped), 2 coronal, 4 sagittal, and one plane tilted 30
  // degrees from axial about x.
  std::vector<StackImage> images;
  const auto add = [&](glm::dvec3 normal, int k) {
    images.push_back({.normal_lps = normal, .position_mm = normal * (2.0 * k)});
  };
  const glm::dvec3 oblique(0.0, -0.5, 0.8660254);
  for (int k = 0; k < 4; ++k) {
    if (k < 3) add(glm::dvec3(0, 0, k == 1 ? -1 : 1), k);
    if (k < 2) add(glm::dvec3(0, 1, 0), k);
    add(glm::dvec3(1, 0, 0), k);
    if (k < 2) add(oblique, k);
  }
  const std::vector<DicomStack> stacks = SplitDicomStacks(images);
  EXPECT_EQ(Labels(stacks),
            (std::vector<std::string>{"sagittal", "axial", "coronal", "oblique axial"}));
  ASSERT_EQ(stacks.size(), 4u);
  EXPECT_EQ(stacks[0].images, (std::vector<size_t>{2, 6, 9, 10}));
  EXPECT_EQ(stacks[1].images, (std::vector<size_t>{0, 4, 8}));
  EXPECT_EQ(stacks[2].images, (std::vector<size_t>{1, 5}));
  EXPECT_EQ(stacks[3].images, (std::vector<size_t>{3, 7}));
}

TEST(SplitDicomStacks, APlaneThatRepeatsItsPositionsIsSplitWithinThePlane) {
  // Two echoes of an axial stack, a coronal one beside them, and a second
  // coronal plane 15 degrees off the first.
  std::vector<StackImage> images = AxialFiles(3, {.echo_numbers = "1"});
  for (StackImage f : AxialFiles(3, {.echo_numbers = "2"})) images.push_back(f);
  const glm::dvec3 tilted(0.0, 0.9659258, 0.2588190);
  for (int k = 0; k < 2; ++k) {
    images.push_back({.normal_lps = glm::dvec3(0, 1, 0), .position_mm = glm::dvec3(0, 2.0 * k, 0)});
    images.push_back({.normal_lps = tilted, .position_mm = tilted * (2.0 * k)});
  }
  const std::vector<DicomStack> stacks = SplitDicomStacks(images);
  EXPECT_EQ(Labels(stacks),
            (std::vector<std::string>{"axial, EchoNumbers 1", "axial, EchoNumbers 2", "coronal",
                                      "coronal 2"}));
  ASSERT_EQ(stacks.size(), 4u);
  EXPECT_EQ(stacks[1].images, (std::vector<size_t>{3, 4, 5}));
  EXPECT_EQ(stacks[2].images, (std::vector<size_t>{6, 8}));
  EXPECT_EQ(stacks[3].images, (std::vector<size_t>{7, 9}));
}

TEST(SplitDicomStacks, APlaneOfOneImageLeavesTheSeriesWhole) {
  // Radial slices, 20 degrees apart about the y axis: no plane of two.
  std::vector<StackImage> images;
  for (int k = 0; k < 6; ++k) {
    const double a = glm::radians(20.0 * k);
    images.push_back({.normal_lps = glm::dvec3(std::sin(a), 0.0, std::cos(a))});
  }
  std::vector<DicomStack> stacks = SplitDicomStacks(images);
  ASSERT_EQ(stacks.size(), 1u);
  EXPECT_EQ(stacks[0].label, "");
  EXPECT_EQ(stacks[0].images.size(), 6u);
  // Four axial slices and one stray sagittal image: whole too.
  images = AxialFiles(4, {});
  images.push_back({.normal_lps = glm::dvec3(1, 0, 0)});
  stacks = SplitDicomStacks(images);
  ASSERT_EQ(stacks.size(), 1u);
  EXPECT_EQ(stacks[0].images.size(), 5u);
}

TEST(SplitDicomStacks, TheFirstAttributeThatSeparatesThePositionsSplits) {
  // Three phases of a dynamic series, every image of echo 1 and of one
  // ImageType: EchoNumbers and ImageType cannot split it, the phase can.
  std::vector<StackImage> files;
  for (const char* phase : {"3", "1", "2"}) {
    for (StackImage f : AxialFiles(4, {.echo_numbers = "1",
                                      .temporal_position = phase,
                                      .image_type = "ORIGINAL\\PRIMARY\\M"})) {
      files.push_back(f);
    }
  }
  EXPECT_EQ(
      Labels(SplitDicomStacks(files)),
      (std::vector<std::string>{"TemporalPositionIdentifier 1", "TemporalPositionIdentifier 2",
                                "TemporalPositionIdentifier 3"}));
  // Dixon: water and fat told apart by ImageType alone, in text order.
  files = AxialFiles(2, {.image_type = "DERIVED\\PRIMARY\\DIXON\\WATER"});
  for (StackImage f : AxialFiles(2, {.image_type = "DERIVED\\PRIMARY\\DIXON\\FAT"})) {
    files.push_back(f);
  }
  EXPECT_EQ(Labels(SplitDicomStacks(files)),
            (std::vector<std::string>{"ImageType DERIVED\\PRIMARY\\DIXON\\FAT",
                                      "ImageType DERIVED\\PRIMARY\\DIXON\\WATER"}));
}

TEST(SplitDicomStacks, NoSplitThatLeavesARepeatOrALoneImage) {
  // A repeated file: same attributes, one position twice.
  std::vector<StackImage> files = AxialFiles(4, {.echo_numbers = "1"});
  files.push_back(files[2]);
  ASSERT_EQ(SplitDicomStacks(files).size(), 1u);
  // The repeat differs only in AcquisitionNumber: a stack of one image is
  // not a stack.
  files.back().attributes.acquisition_number = "2";
  ASSERT_EQ(SplitDicomStacks(files).size(), 1u);
  // Echoes that still repeat a position within one echo.
  files = AxialFiles(3, {.echo_numbers = "1"});
  for (StackImage f : AxialFiles(3, {.echo_numbers = "2"})) files.push_back(f);
  files.push_back(files[0]);
  EXPECT_EQ(SplitDicomStacks(files).size(), 1u);
  // A NaN position repeats nothing and splits nothing, without a crash.
  files = AxialFiles(3, {});
  files[1].position_mm.z = std::nan("");
  EXPECT_EQ(SplitDicomStacks(files).size(), 1u);
  EXPECT_EQ(SplitDicomStacks({}).size(), 1u);
}

TEST(SplitDicomStacks, PositionsAreComparedAlongTheSliceNormal) {
  // Sagittal slices (normal along x) at x = 0, 2, 4, all at the same z, of
  // one echo: distinct positions, one stack; two echoes: two.
  std::vector<StackImage> files;
  for (const char* echo : {"1", "2"}) {
    for (int k = 0; k < 3; ++k) {
      files.push_back({.attributes = {.echo_numbers = echo},
                       .normal_lps = glm::dvec3(1.0, 0.0, 0.0),
                       .position_mm = glm::dvec3(2.0 * k, 5.0, 7.0)});
    }
  }
  EXPECT_EQ(SplitDicomStacks(std::span(files).first(3)).size(), 1u);
  EXPECT_EQ(Labels(SplitDicomStacks(files)),
            (std::vector<std::string>{"EchoNumbers 1", "EchoNumbers 2"}));
}

// ---- Through the series reader ----

// An MR series of two echoes at four positions in one folder; echo e's
// voxels hold 1000 * e + 10 * k + n (slice k, pixel n).
std::filesystem::path WriteTwoEchoes() {
  const auto dir = MakeTempDir();
  DicomSliceSpec s;
  s.sop_class_uid = UID_MRImageStorage;
  s.modality = "MR";
  s.intercept = 0.0;
  s.series_description = "T1 in/opp";
  for (int echo = 1; echo <= 2; ++echo) {
    for (int k = 0; k < 4; ++k) {
      s.position_mm = glm::dvec3(0.0, 0.0, 3.0 * k);
      s.more = {{DCM_EchoNumbers, std::to_string(echo)}, {DCM_EchoTime, echo == 1 ? "2.3" : "4.6"}};
      s.stored.clear();
      for (int n = 0; n < s.rows * s.columns; ++n) s.stored.push_back(1000 * echo + 10 * k + n);
      EXPECT_TRUE(WriteDicomSlice(dir / ("im" + std::to_string(10 * (3 - echo) + k) + ".dcm"),
                                  s));  // echo 2 first
    }
  }
  return dir;
}

bool HasNote(const Volume& v, const std::string& fragment) {
  for (const std::string& note : v.notes()) {
    if (note.find(fragment) != std::string::npos) return true;
  }
  return false;
}

TEST(DicomSeriesReader, ReadsTheFirstEchoOfATwoEchoSeriesAndTheOtherOnRequest) {
  const auto dir = WriteTwoEchoes();
  const auto listed = ListDicomSeries(dir, {});
  ASSERT_TRUE(listed.ok()) << listed.status();
  ASSERT_EQ(listed->size(), 2u);
  EXPECT_EQ((*listed)[0].stack, "EchoNumbers 1");
  EXPECT_EQ((*listed)[1].stack, "EchoNumbers 2");
  EXPECT_EQ((*listed)[0].images, 4);
  EXPECT_EQ((*listed)[0].uid, (*listed)[1].uid);

  const auto first = ReadDicomSeries(dir, {});
  ASSERT_TRUE(first.ok()) << first.status();
  EXPECT_EQ(first->dims(), (std::array<int64_t, 3>{4, 3, 4}));
  EXPECT_NEAR(first->spacing_mm().z, 3.0, 1e-9);
  EXPECT_FLOAT_EQ(first->At(0, 0, 0), 1000.0f);
  EXPECT_FLOAT_EQ(first->At(1, 0, 3), 1031.0f);
  std::string notes;
  for (const std::string& n : first->notes()) notes += n + "\n";
  EXPECT_TRUE(HasNote(*first,
                      "holds 2 stacks (1 = EchoNumbers 1, 2 = "
                      "EchoNumbers 2); read stack 1 (EchoNumbers 1, 4 slices); stack=N in the "
                      "source picks another"))
      << notes;
  EXPECT_EQ(first->stacks(), (std::vector<std::string>{"EchoNumbers 1", "EchoNumbers 2"}));
  EXPECT_EQ(first->stack(), 1);
  EXPECT_FALSE(HasNote(*first, "the folder holds")) << notes;  // one series

  const auto second = ReadDicomSeries(dir, {}, {.series = "2"});
  ASSERT_TRUE(second.ok()) << second.status();
  EXPECT_FLOAT_EQ(second->At(0, 0, 0), 2000.0f);
  EXPECT_FLOAT_EQ(second->At(1, 0, 3), 2031.0f);
  EXPECT_EQ(second->stack(), 2);
  // The UID names the series: its first stack.
  const auto by_uid = ReadDicomSeries(dir, {}, {.series = (*listed)[0].uid});
  ASSERT_TRUE(by_uid.ok()) << by_uid.status();
  EXPECT_FLOAT_EQ(by_uid->At(0, 0, 0), 1000.0f);
}

// stack=N picks a stack within the series, whichever way the series is
// named (the default, its UID or its first entry), as a PACS source does.
TEST(DicomSeriesReader, StackNPicksAStackOfTheSeries) {
  const auto dir = WriteTwoEchoes();
  const auto listed = ListDicomSeries(dir, {});
  ASSERT_TRUE(listed.ok()) << listed.status();
  for (const std::string& series : {std::string(), (*listed)[0].uid, std::string("1")}) {
    const auto v = ReadDicomSeries(dir, {}, {.series = series, .stack = 2});
    ASSERT_TRUE(v.ok()) << series << ": " << v.status();
    EXPECT_FLOAT_EQ(v->At(0, 0, 0), 2000.0f) << series;
    EXPECT_EQ(v->stack(), 2) << series;
    EXPECT_TRUE(HasNote(*v, "read stack 2 (EchoNumbers 2, 4 slices)")) << series;
  }
  const auto third = ReadDicomSeries(dir, {}, {.stack = 3});
  EXPECT_TRUE(absl::IsInvalidArgument(third.status()));
  EXPECT_NE(std::string(third.status().message())
                .find("no stack 3: series " + (*listed)[0].uid +
                      " holds 2 stacks (1 = EchoNumbers 1, 2 = EchoNumbers 2)"),
            std::string::npos)
      << third.status();

  // Through the folder's source syntax.
  const auto source = ParseDicomSource(dir.string() + "?stack=2");
  ASSERT_TRUE(source.ok() && source->has_value()) << source.status();
  EXPECT_EQ((*source)->options.stack, 2);
  for (const char* bad : {"?stack=0", "?stack=x", "?stack=", "?stack=-1", "?stack=100001"}) {
    EXPECT_TRUE(absl::IsInvalidArgument(ParseDicomSource(dir.string() + bad).status())) << bad;
  }
}

TEST(DicomSeriesReader, AStackBeyondOneOnASeriesOfOneStackIsRefused) {
  const auto dir = MakeTempDir();
  DicomSliceSpec s;
  for (int k = 0; k < 3; ++k) {
    s.position_mm = glm::dvec3(0.0, 0.0, 2.0 * k);
    ASSERT_TRUE(WriteDicomSlice(dir / ("im" + std::to_string(k) + ".dcm"), s));
  }
  const auto one = ReadDicomSeries(dir, {}, {.stack = 1});
  ASSERT_TRUE(one.ok()) << one.status();
  EXPECT_TRUE(one->stacks().empty());
  EXPECT_EQ(one->stack(), 0);
  const auto two = ReadDicomSeries(dir, {}, {.stack = 2});
  EXPECT_TRUE(absl::IsInvalidArgument(two.status()));
  EXPECT_NE(std::string(two.status().message()).find("no stack 2: series "), std::string::npos);
  EXPECT_NE(std::string(two.status().message()).find(" holds one stack"), std::string::npos);
}

// A series of 4 axial slices and 3 coronal ones (a workstation's
// reformats under one UID): one stack per plane, the axial one by default.
TEST(DicomSeriesReader, ASeriesInTwoPlanesReadsEitherPlane) {
  const auto dir = MakeTempDir();
  DicomSliceSpec s;
  for (int k = 0; k < 4; ++k) {
    s.position_mm = glm::dvec3(0.0, 0.0, 2.0 * k);
    ASSERT_TRUE(WriteDicomSlice(dir / ("ax" + std::to_string(k) + ".dcm"), s));
  }
  s.orientation = {1, 0, 0, 0, 0, -1};  // rows along x, columns down: normal +y
  s.rows = 5;
  for (int k = 0; k < 3; ++k) {
    s.position_mm = glm::dvec3(0.0, 1.5 * k, 10.0);
    ASSERT_TRUE(WriteDicomSlice(dir / ("co" + std::to_string(k) + ".dcm"), s));
  }
  const auto listed = ListDicomSeries(dir, {});
  ASSERT_TRUE(listed.ok()) << listed.status();
  ASSERT_EQ(listed->size(), 2u);
  EXPECT_EQ((*listed)[0].stack, "axial");
  EXPECT_EQ((*listed)[0].images, 4);
  EXPECT_EQ((*listed)[1].stack, "coronal");
  EXPECT_EQ((*listed)[1].images, 3);

  const auto axial = ReadDicomSeries(dir, {});
  ASSERT_TRUE(axial.ok()) << axial.status();
  EXPECT_EQ(axial->dims(), (std::array<int64_t, 3>{4, 3, 4}));
  EXPECT_EQ(axial->stacks(), (std::vector<std::string>{"axial", "coronal"}));
  EXPECT_TRUE(HasNote(*axial, "holds 2 stacks (1 = axial, 2 = coronal); read stack 1"));
  const auto coronal = ReadDicomSeries(dir, {}, {.stack = 2});
  ASSERT_TRUE(coronal.ok()) << coronal.status();
  EXPECT_EQ(coronal->dims(), (std::array<int64_t, 3>{4, 5, 3}));
  EXPECT_NEAR(coronal->spacing_mm().z, 1.5, 1e-9);
  EXPECT_NEAR(coronal->geometry().direction[2].y, 1.0, 1e-9);  // the slice axis is +y
  EXPECT_EQ(coronal->stack(), 2);
}

TEST(DicomSeriesReader, ARepeatNoAttributeExplainsIsStillRefusedWithAReason) {
  const auto dir = WriteTwoEchoes();
  DicomSliceSpec s;
  s.sop_class_uid = UID_MRImageStorage;
  s.modality = "MR";
  s.position_mm = glm::dvec3(0.0, 0.0, 3.0);
  s.more = {{DCM_EchoNumbers, "1"}, {DCM_EchoTime, "2.3"}};
  ASSERT_TRUE(WriteDicomSlice(dir / "again.dcm", s));
  const auto v = ReadDicomSeries(dir, {});
  ASSERT_FALSE(v.ok());
  EXPECT_EQ(v.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(v.status().message().find("duplicate slice position"), std::string::npos) << v.status();
  EXPECT_NE(v.status().message().find("no echo, phase, b-value"), std::string::npos) << v.status();
}

// One Enhanced file of two echoes at z = 0 and 2 mm: frames 0 and 1 of
// EffectiveEchoTime 4.6 ms, frames 2 and 3 of 2.3 ms, in per-frame
// MREchoSequence items; pixel n of frame f stores 100 f + n.
std::filesystem::path WriteEnhancedTwoEchoes() {
  const auto dir = MakeTempDir();
  DicomSliceSpec s;
  DcmFileFormat file;
  DcmDataset& ds = *file.getDataset();
  const std::vector<testing::EnhancedFrame> frames = {
      {{0, 0, 0.0}}, {{0, 0, 2.0}}, {{0, 0, 0.0}}, {{0, 0, 2.0}}};
  EXPECT_TRUE(testing::FillEnhancedCt(ds, s, frames, false));
  for (int f = 0; f < 4; ++f) {
    DcmItem *group = nullptr, *echo = nullptr;
    EXPECT_TRUE(ds.findAndGetSequenceItem(DCM_PerFrameFunctionalGroupsSequence, group, f).good());
    EXPECT_TRUE(group->findOrCreateSequenceItem(DCM_MREchoSequence, echo, -2).good());
    echo->putAndInsertFloat64(DCM_EffectiveEchoTime, f < 2 ? 4.6 : 2.3);
  }
  std::vector<Uint16> pixels;
  for (int f = 0; f < 4; ++f) {
    for (int n = 0; n < s.rows * s.columns; ++n) pixels.push_back(static_cast<Uint16>(100 * f + n));
  }
  ds.putAndInsertUint16Array(DCM_PixelData, pixels.data(), pixels.size());
  EXPECT_TRUE(file.saveFile((dir / "enhanced.dcm").c_str(), EXS_LittleEndianExplicit).good());
  return dir;
}

TEST(DicomSeriesReader, SplitsTheFramesOfOneEnhancedFileByTheirEchoTime) {
  const auto dir = WriteEnhancedTwoEchoes();
  const auto listed = ListDicomSeries(dir, {});
  ASSERT_TRUE(listed.ok()) << listed.status();
  ASSERT_EQ(listed->size(), 2u);
  EXPECT_EQ((*listed)[0].stack, "EchoTime 2.3");
  EXPECT_EQ((*listed)[0].frames, (std::vector<std::vector<int64_t>>{{2, 3}}));
  EXPECT_EQ((*listed)[1].frames, (std::vector<std::vector<int64_t>>{{0, 1}}));

  const auto first = ReadDicomSeries(dir, {});
  ASSERT_TRUE(first.ok()) << first.status();
  EXPECT_EQ(first->dims(), (std::array<int64_t, 3>{4, 3, 2}));
  EXPECT_FLOAT_EQ(first->At(0, 0, 0), 200.0f - 1024.0f);  // frame 2
  EXPECT_FLOAT_EQ(first->At(1, 0, 1), 301.0f - 1024.0f);  // frame 3
  const auto second = ReadDicomSeries(dir, {}, {.series = "2"});
  ASSERT_TRUE(second.ok()) << second.status();
  EXPECT_FLOAT_EQ(second->At(0, 0, 0), 0.0f - 1024.0f);
  EXPECT_FLOAT_EQ(second->At(1, 0, 1), 101.0f - 1024.0f);
}

}  // namespace
}  // namespace vpm
