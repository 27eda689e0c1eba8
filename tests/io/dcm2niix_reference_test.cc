// vpm's DICOM reader against dcm2niix, the reference converter: both read
// the same series, and the two volumes must agree at the same world (LPS)
// points. dcm2niix writes a tilt-corrected copy of a gantry-tilted series
// (*_Tilt_1.nii.gz) and an equally spaced copy of an unevenly spaced one
// (*_Eq_1.nii.gz); vpm's ReadNifti converts its RAS to LPS. dcm2niix must be
// installed (scripts/install-deps.sh): without it the test fails.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "server/io/read_dicom_series.h"
#include "server/io/read_nifti.h"
#include "server/volume/sample_trilinear.h"
#include "tests/io/dicom_test_util.h"
#include "tests/io/io_test_util.h"

namespace vpm {
namespace {

using ::vpm::testing::DicomSliceSpec;
using ::vpm::testing::MakeTempDir;
using ::vpm::testing::WriteDicomSlice;

// Runs dcm2niix on `folder` into a new folder under `work` (the test's
// temporary folder) and returns the NIfTI whose name ends with `ending`
// (names: the SeriesInstanceUID, dcm2niix's %j, then its suffixes); empty,
// with a failure, when there is none.
std::filesystem::path RunDcm2niix(const std::filesystem::path& folder,
                                  const std::filesystem::path& work, const std::string& ending) {
  const std::filesystem::path out = work / ("dcm2niix_" + folder.filename().string());
  std::filesystem::remove_all(out);
  std::filesystem::create_directories(out);
  const std::string command = "dcm2niix -z y -f %j -o '" + out.string() + "' '" + folder.string() +
                              "' > '" + out.string() + "/log.txt' 2>&1";
  const int rc = std::system(command.c_str());
  EXPECT_EQ(rc, 0) << command << " failed; is dcm2niix installed (scripts/install-deps.sh)?";
  for (const auto& entry : std::filesystem::directory_iterator(out)) {
    if (entry.path().filename().string().ends_with(ending)) return entry.path();
  }
  ADD_FAILURE() << "dcm2niix wrote no *" << ending << " in " << out;
  return {};
}

struct Agreement {
  int points = 0;         // sample points inside both volumes
  double mean_abs = 0.0;  // mean |vpm - dcm2niix|, volume units (HU)
  double p99_abs = 0.0;   // 99th percentile of |vpm - dcm2niix|
  double box_mm = 0.0;    // largest difference between the world bounding boxes' bounds
};

// World (LPS) axis-aligned bounds of a volume's voxel centres.
std::pair<glm::dvec3, glm::dvec3> WorldBounds(const VolumeGeometry& g) {
  glm::dvec3 low(1e300), high(-1e300);
  for (int c = 0; c < 8; ++c) {
    const glm::dvec3 index((c & 1) ? g.dims[0] - 1 : 0, (c & 2) ? g.dims[1] - 1 : 0,
                           (c & 4) ? g.dims[2] - 1 : 0);
    const glm::dvec3 w = g.PhysicalToWorld(g.IndexToPhysical(index));
    low = glm::min(low, w);
    high = glm::max(high, w);
  }
  return {low, high};
}

bool InsideAwayFromEdge(const VolumeGeometry& g, const glm::dvec3& index) {
  for (int a = 0; a < 3; ++a) {
    if (!(index[a] >= 1.0 && index[a] <= g.dims[a] - 2.0)) return false;
  }
  return true;
}

// Where a comparison may sample: a world point (LPS, mm) -> whether to use it.
using WorldFilter = std::function<bool(const glm::dvec3&)>;

// Samples both volumes trilinearly at random world points that lie at least
// one voxel inside each box (and pass `use`).
Agreement Compare(const Volume& ours, const Volume& reference, int wanted_points,
                  const WorldFilter& use) {
  const VolumeGeometry& a = ours.geometry();
  const VolumeGeometry& b = reference.geometry();
  std::mt19937 random(16);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<double> diffs;
  for (int tries = 0; tries < 20 * wanted_points && static_cast<int>(diffs.size()) < wanted_points;
       ++tries) {
    const glm::dvec3 index_a(1.0 + unit(random) * (a.dims[0] - 3.0),
                             1.0 + unit(random) * (a.dims[1] - 3.0),
                             1.0 + unit(random) * (a.dims[2] - 3.0));
    const glm::dvec3 world = a.PhysicalToWorld(a.IndexToPhysical(index_a));
    const glm::dvec3 physical_b = b.WorldToPhysical(world);
    if (!InsideAwayFromEdge(b, b.PhysicalToIndex(physical_b)) || !use(world)) continue;
    diffs.push_back(std::abs(SampleTrilinear(ours, a.IndexToPhysical(index_a)) -
                             SampleTrilinear(reference, physical_b)));
  }
  Agreement r;
  r.points = static_cast<int>(diffs.size());
  if (diffs.empty()) return r;
  for (double d : diffs) r.mean_abs += d / diffs.size();
  std::sort(diffs.begin(), diffs.end());
  r.p99_abs = diffs[static_cast<size_t>(0.99 * (diffs.size() - 1))];
  const auto [low_a, high_a] = WorldBounds(a);
  const auto [low_b, high_b] = WorldBounds(b);
  for (int c = 0; c < 3; ++c) {
    r.box_mm = std::max({r.box_mm, std::abs(low_a[c] - low_b[c]), std::abs(high_a[c] - high_b[c])});
  }
  return r;
}

void ExpectAgreement(
    const std::string& name, const Volume& ours, const Volume& reference, double max_mean_abs,
    double max_p99_abs, double max_box_mm,
    const WorldFilter& use = [](const glm::dvec3&) { return true; }) {
  const Agreement r = Compare(ours, reference, 20000, use);
  // The figures, for docs/VOLUMES.md and the report.
  std::printf("dcm2niix vs vpm, %s: %d points, mean |diff| %.3f, p99 |diff| %.3f, box %.4f mm\n",
              name.c_str(), r.points, r.mean_abs, r.p99_abs, r.box_mm);
  EXPECT_GE(r.points, 10000) << name << ": the volumes hardly overlap";
  EXPECT_LE(r.mean_abs, max_mean_abs) << name;
  EXPECT_LE(r.p99_abs, max_p99_abs) << name;
  EXPECT_LE(r.box_mm, max_box_mm) << name;
}

// A smooth CT-like field of world position (HU): varies by a few hundred HU
// over some tens of mm, so that interpolation differences show but stay small.
double Field(const glm::dvec3& w) {
  return 200.0 * std::sin(0.15 * w.x) * std::cos(0.11 * w.y) + 150.0 * std::sin(0.09 * w.z) + 40.0;
}

// Writes a 32 x 28 CT series: slice k at `positions[k]` (LPS, mm), rows along
// `column_dir`, values Field rounded to whole HU.
void WriteFieldSeries(const std::filesystem::path& dir, const std::string& uid,
                      const glm::dvec3& column_dir, const std::vector<glm::dvec3>& positions,
                      int series_number, const std::string& gantry_tilt_deg = "") {
  std::filesystem::create_directories(dir);
  DicomSliceSpec s;
  // dcm2niix corrects tilt only for a vendor it knows and a tilt it is told.
  s.manufacturer = "Philips";
  s.gantry_tilt_deg = gantry_tilt_deg;
  s.series_uid = uid;
  s.series_number = series_number;
  s.rows = 28;
  s.columns = 32;
  s.pixel_spacing_mm = {0.9, 0.8};
  s.orientation = {1, 0, 0, column_dir.x, column_dir.y, column_dir.z};
  s.slice_thickness_mm = 1.0;
  const glm::dvec3 row_dir(1, 0, 0);
  for (size_t k = 0; k < positions.size(); ++k) {
    s.position_mm = positions[k];
    s.instance_number = static_cast<int>(k) + 1;
    s.stored.clear();
    for (int j = 0; j < s.rows; ++j) {
      for (int i = 0; i < s.columns; ++i) {
        const glm::dvec3 w = positions[k] + (i * 0.8) * row_dir + (j * 0.9) * column_dir;
        s.stored.push_back(static_cast<int32_t>(std::lround(Field(w) + 1024.0)));
      }
    }
    ASSERT_TRUE(WriteDicomSlice(dir / (uid + "_" + std::to_string(k) + ".dcm"), s));
  }
}

Volume ReadOurs(const std::filesystem::path& folder, const std::string& series = "") {
  auto v = ReadDicomSeries(folder, {}, {.series = series});
  EXPECT_TRUE(v.ok()) << v.status();
  return v.ok() ? *std::move(v) : *Volume::Create(VolumeGeometry{{1, 1, 1}}, {0.0f});
}

Volume ReadReference(const std::filesystem::path& nifti) {
  auto v = ReadNifti(nifti, {});
  EXPECT_TRUE(v.ok()) << v.status();
  return v.ok() ? *std::move(v) : *Volume::Create(VolumeGeometry{{1, 1, 1}}, {0.0f});
}

TEST(Dcm2niixReference, PhilipsTiltedCtMatchesTiltCorrectedOutput) {
  const std::filesystem::path folder =
      std::filesystem::path(VPM_TEST_SOURCE_DIR) / "tests/data/ct-philips-tilt";
  const Volume ours = ReadOurs(folder);
  const std::filesystem::path tilt = RunDcm2niix(folder, MakeTempDir(), "_Tilt_1.nii.gz");
  ASSERT_FALSE(tilt.empty());
  EXPECT_FALSE(ours.notes().empty());
  // Real data, sampled over the whole box (outside the stack both fill with
  // air, -1024 HU): measured mean 0.30 HU, p99 4.8 HU, the bulk at dcm2niix's
  // int16 rounding, the tail at bone edges. The boxes differ by under one
  // pixel (0.48 mm): dcm2niix rounds its box to whole pixels differently.
  ExpectAgreement("ct-philips-tilt", ours, ReadReference(tilt), 1.0, 10.0, 0.45);
}

TEST(Dcm2niixReference, SyntheticTiltedSeriesMatchesTiltCorrectedOutput) {
  const std::filesystem::path folder = MakeTempDir() / "tilt";
  const double tilt = glm::radians(15.0);
  const glm::dvec3 column_dir(0, std::cos(tilt), -std::sin(tilt));
  std::vector<glm::dvec3> positions;
  for (int k = 0; k < 16; ++k) positions.push_back(glm::dvec3(-12.0, -10.0, 2.0 * k));
  WriteFieldSeries(folder, "1.2.826.0.1.3680043.8.498.71", column_dir, positions, 1, "-15");
  const Volume ours = ReadOurs(folder);
  // Only where both hold data: at least one pixel inside the two slices
  // around the point. Outside the sheared stack both fill with the minimum,
  // and at its border a sub-voxel difference in where the fill starts would
  // weigh hundreds of HU (the field there is far from its minimum).
  const glm::dvec3 row_dir(1, 0, 0);
  const glm::dvec3 normal = glm::cross(row_dir, column_dir);
  const auto inside_stack = [&](const glm::dvec3& w) {
    const double k =
        glm::dot(w - positions[0], normal) / glm::dot(positions[1] - positions[0], normal);
    if (!(k >= 0.0 && k <= positions.size() - 1.0)) return false;
    for (const double slice : {std::floor(k), std::ceil(k)}) {
      const glm::dvec3 d = w - positions[static_cast<size_t>(slice)];
      const double i = glm::dot(d, row_dir) / 0.8, j = glm::dot(d, column_dir) / 0.9;
      if (!(i >= 1.0 && i <= 30.0 && j >= 1.0 && j <= 26.0)) return false;
    }
    return true;
  };
  ExpectAgreement("synthetic tilt 15 deg", ours,
                  ReadReference(RunDcm2niix(folder, folder.parent_path(), "_Tilt_1.nii.gz")), 0.5,
                  1.5, 0.45, inside_stack);
}

TEST(Dcm2niixReference, SyntheticUnevenSeriesMatchesEquallySpacedOutput) {
  const std::filesystem::path folder = MakeTempDir() / "uneven";
  std::vector<glm::dvec3> positions;
  for (double z : {0.0, 1.5, 3.0, 4.5, 6.0, 7.5, 12.0, 13.5, 15.0, 16.5, 18.0, 19.5}) {
    positions.push_back(glm::dvec3(-12.0, -10.0, z));
  }
  WriteFieldSeries(folder, "1.2.826.0.1.3680043.8.498.72", glm::dvec3(0, 1, 0), positions, 1);
  const Volume ours = ReadOurs(folder);
  // dcm2niix's _Eq_ output stops one plane short: 13 planes where 19.5 mm at
  // 1.5 mm needs 14 (vpm's box ends on the last slice), hence one spacing.
  ExpectAgreement("synthetic uneven gaps", ours,
                  ReadReference(RunDcm2niix(folder, folder.parent_path(), "_Eq_1.nii.gz")), 0.2,
                  1.0, 1.5 + 1e-3);
}

TEST(Dcm2niixReference, EachSeriesOfAFolderMatchesItsOwnConversion) {
  const std::filesystem::path folder = MakeTempDir() / "several";
  std::vector<glm::dvec3> axial, shifted;
  for (int k = 0; k < 12; ++k) {
    axial.push_back(glm::dvec3(-12.0, -10.0, 1.25 * k));
    shifted.push_back(glm::dvec3(-5.0, -3.0, 30.0 + 2.0 * k));
  }
  WriteFieldSeries(folder, "1.2.826.0.1.3680043.8.498.73", glm::dvec3(0, 1, 0), axial, 2);
  WriteFieldSeries(folder, "1.2.826.0.1.3680043.8.498.74", glm::dvec3(0, 1, 0), shifted, 3);
  for (const char* uid : {"1.2.826.0.1.3680043.8.498.73", "1.2.826.0.1.3680043.8.498.74"}) {
    const Volume ours = ReadOurs(folder, uid);
    ExpectAgreement(
        StrCat("several series, ", uid), ours,
        ReadReference(RunDcm2niix(folder, folder.parent_path(), StrCat(uid, ".nii.gz"))), 1e-3,
        1e-3, 1e-3);
  }
}

}  // namespace
}  // namespace vpm
