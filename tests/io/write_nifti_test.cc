#include "server/io/write_nifti.h"

#include <gtest/gtest.h>

#include "server/io/nifti_c_api.h"
#include "server/io/read_nifti.h"
#include "tests/io/io_test_util.h"

namespace vpm {
namespace {

using ::vpm::testing::MakeTempDir;

Volume MakeVolume(const VolumeGeometry& g) {
  auto v = Volume::Create(g, testing::RampValues(g.voxel_count()));
  EXPECT_TRUE(v.ok()) << v.status();
  return *std::move(v);
}

// An oblique geometry: a rotation by 30 degrees about x then 20 about z, and
// a reflection of the k axis, so that qfac = -1 is exercised.
VolumeGeometry ObliqueGeometry() {
  VolumeGeometry g;
  g.dims = {5, 4, 3};
  g.spacing_mm = {0.7, 1.1, 3.3};
  g.origin_mm = {-101.25, 42.5, -17.75};
  const double a = glm::radians(30.0), b = glm::radians(20.0);
  const glm::dmat3 rx(glm::dvec3(1, 0, 0), glm::dvec3(0, std::cos(a), std::sin(a)),
                      glm::dvec3(0, -std::sin(a), std::cos(a)));
  const glm::dmat3 rz(glm::dvec3(std::cos(b), std::sin(b), 0),
                      glm::dvec3(-std::sin(b), std::cos(b), 0), glm::dvec3(0, 0, 1));
  g.direction = rz * rx;
  g.direction[2] = -g.direction[2];
  return g;
}

void ExpectRoundTrip(const VolumeGeometry& g, const std::string& file_name) {
  const Volume original = MakeVolume(g);
  const auto path = MakeTempDir() / file_name;
  ASSERT_TRUE(WriteNifti(original, path).ok());
  auto read = ReadNifti(path, {});
  ASSERT_TRUE(read.ok()) << read.status();
  testing::ExpectGeometryNear(read->geometry(), g, 1e-5);
  ASSERT_EQ(read->voxels().size(), original.voxels().size());
  for (size_t n = 0; n < size_t(original.voxels().size()); ++n) {
    ASSERT_EQ(read->voxels()[n], original.voxels()[n]) << "voxel " << n;
  }
}

TEST(NiftiWriter, RoundTripsAxisAlignedGeometry) {
  ExpectRoundTrip(testing::RotatedGeometry({4, 3, 2}), "axes.nii");
}

TEST(NiftiWriter, RoundTripsObliqueGeometry) { ExpectRoundTrip(ObliqueGeometry(), "oblique.nii"); }

TEST(NiftiWriter, RoundTripsGzipped) { ExpectRoundTrip(ObliqueGeometry(), "oblique.nii.gz"); }

TEST(NiftiWriter, QformAgreesWithSform) {
  // Readers that only use the qform must see the same space: read the file
  // with nifti_clib and compare its qform and sform matrices.
  const VolumeGeometry g = ObliqueGeometry();
  const auto path = MakeTempDir() / "both.nii";
  ASSERT_TRUE(WriteNifti(MakeVolume(g), path).ok());
  nifti_image* image = nifti_image_read(path.c_str(), 1);
  ASSERT_NE(image, nullptr);
  EXPECT_EQ(image->qform_code, 1);
  EXPECT_EQ(image->sform_code, 1);
  EXPECT_EQ(image->datatype, DT_FLOAT32);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) {
      EXPECT_NEAR(image->qto_xyz.m[r][c], image->sto_xyz.m[r][c], 1e-5) << r << "," << c;
    }
  }
  // And the library reads the same voxel values.
  const float* data = static_cast<const float*>(image->data);
  EXPECT_EQ(data[7], 7 * 1.5f - 7.0f);
  nifti_image_free(image);
}

TEST(NiftiWriter, RejectsUnwritablePath) {
  const Volume v = MakeVolume(testing::RotatedGeometry({2, 2, 2}));
  const Status status = WriteNifti(v, MakeTempDir() / "no_such_dir" / "x.nii");
  EXPECT_EQ(status.code(), absl::StatusCode::kNotFound) << status;
}

}  // namespace
}  // namespace vpm
