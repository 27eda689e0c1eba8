#include "server/io/read_volume.h"

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "server/io/write_nifti.h"
#include "tests/io/io_test_util.h"

namespace vpm {
namespace {

using ::vpm::testing::MakeTempDir;

Volume SmallVolume() {
  auto v = Volume::Create(testing::RotatedGeometry({3, 2, 2}), testing::RampValues(12));
  EXPECT_TRUE(v.ok());
  return *std::move(v);
}

TEST(ReadVolume, DispatchesNiftiByExtensionAndSetsSource) {
  const auto dir = MakeTempDir();
  for (const char* name : {"a.nii", "b.nii.gz", "C.NII"}) {
    ASSERT_TRUE(WriteNifti(SmallVolume(), dir / name).ok());
    const std::string source = (dir / name).string();
    auto v = ReadVolume(source, {});
    ASSERT_TRUE(v.ok()) << name << ": " << v.status();
    EXPECT_EQ(v->source(), source);
    EXPECT_EQ(v->voxels()[5], SmallVolume().voxels()[5]);
  }
}

TEST(ReadVolume, DispatchesNrrdMetaImageAndRaw) {
  const auto dir = MakeTempDir();
  testing::WriteText(dir / "v.nrrd",
                     "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 1 1 2\nencoding: raw\n\nAB");
  testing::WriteText(dir / "v.mha",
                     "NDims = 3\nDimSize = 2 1 1\nElementType = MET_UCHAR\n"
                     "ElementDataFile = LOCAL\nCD");
  testing::WriteText(dir / "v.bin", "EF");
  auto nrrd = ReadVolume((dir / "v.nrrd").string(), {});
  ASSERT_TRUE(nrrd.ok()) << nrrd.status();
  EXPECT_EQ(nrrd->voxels()[1], static_cast<float>('B'));
  auto mha = ReadVolume((dir / "v.mha").string(), {});
  ASSERT_TRUE(mha.ok()) << mha.status();
  EXPECT_EQ(mha->voxels()[0], static_cast<float>('C'));
  const std::string raw =
      "raw:" + (dir / "v.bin").string() + "?dims=2,1,1&type=uint8&spacing=1,1,1";
  auto r = ReadVolume(raw, {});
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_EQ(r->voxels()[1], static_cast<float>('F'));
  EXPECT_EQ(r->source(), raw);
}

TEST(ReadVolume, DispatchesPhantom) {
  auto v = ReadVolume("phantom:abdomen?size=16&noise=0", {});
  ASSERT_TRUE(v.ok()) << v.status();
  EXPECT_EQ(v->dims(), (std::array<int64_t, 3>{16, 16, 16}));
  EXPECT_EQ(v->source(), "phantom:abdomen?size=16&noise=0");
  VolumeLimits tiny;
  tiny.max_volume_bytes = 100 * 2;
  EXPECT_EQ(ReadVolume("phantom:abdomen?size=16", tiny).status().code(),
            absl::StatusCode::kResourceExhausted);
}

TEST(ReadVolume, RejectsUnknownFormsListingSupportedOnes) {
  auto v = ReadVolume("scan.png", {});
  ASSERT_FALSE(v.ok());
  EXPECT_EQ(v.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(v.status().message().find(".nrrd"), absl::string_view::npos) << v.status();
  EXPECT_NE(v.status().message().find("raw:PATH?dims="), absl::string_view::npos);
  EXPECT_NE(v.status().message().find("phantom:"), absl::string_view::npos);
}

TEST(ReadVolume, ReportsMissingFilesAsNotFound) {
  EXPECT_EQ(ReadVolume((MakeTempDir() / "nope.nii.gz").string(), {}).status().code(),
            absl::StatusCode::kNotFound);
  EXPECT_EQ(ReadVolume("raw:/no/such.raw?dims=1,1,1&type=int8&spacing=1,1,1", {}).status().code(),
            absl::StatusCode::kNotFound);
}

}  // namespace
}  // namespace vpm

namespace vpm {
namespace {

struct Recorded {
  std::vector<double> fractions;
  std::vector<std::string> stages;
  ProgressFn Fn() {
    return [this](double f, std::string_view stage) {
      fractions.push_back(f);
      stages.emplace_back(stage);
    };
  }
};

TEST(ReadVolume, ReportsMonotoneProgressReachingOne) {
  const auto path = testing::MakeTempDir() / "progress.nii";
  // 40 MiB of float voxels: the reader reports per 16 MiB chunk.
  VolumeGeometry g;
  g.dims = {256, 256, 160};
  ASSERT_TRUE(WriteNifti(*Volume::Create(g, std::vector<float>(g.voxel_count(), 1.0f)), path).ok());
  Recorded r;
  auto v = ReadVolume(path.string(), {}, r.Fn());
  ASSERT_TRUE(v.ok()) << v.status();
  ASSERT_GE(r.fractions.size(), 4u);  // start, 3 chunks, end
  EXPECT_EQ(r.fractions.front(), 0.0);
  EXPECT_EQ(r.fractions.back(), 1.0);
  EXPECT_TRUE(std::is_sorted(r.fractions.begin(), r.fractions.end()));
  EXPECT_NE(std::find(r.stages.begin(), r.stages.end(), "reading"), r.stages.end());
}

TEST(ReadVolume, ProgressStopsShortOfOneOnError) {
  const auto path = testing::MakeTempDir() / "truncated.nii";
  ASSERT_TRUE(WriteNifti(SmallVolume(), path).ok());
  std::filesystem::resize_file(path, std::filesystem::file_size(path) - 8);
  Recorded r;
  EXPECT_FALSE(ReadVolume(path.string(), {}, r.Fn()).ok());
  ASSERT_FALSE(r.fractions.empty());
  EXPECT_LT(r.fractions.back(), 1.0);
  EXPECT_TRUE(std::is_sorted(r.fractions.begin(), r.fractions.end()));
}

}  // namespace
}  // namespace vpm
