#include "server/volume/volume.h"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

namespace vpm {
namespace {

VolumeGeometry SmallGeometry() {
  VolumeGeometry g;
  g.dims = {4, 3, 2};
  g.spacing_mm = {0.5, 1.0, 2.5};
  g.origin_mm = {-10.0, 20.0, 5.0};
  // A rotation about z by 90 degrees: i -> +y, j -> -x.
  g.direction = glm::dmat3(glm::dvec3(0, 1, 0), glm::dvec3(-1, 0, 0), glm::dvec3(0, 0, 1));
  return g;
}

TEST(Volume, WorldAndPhysicalAreExactInverses) {
  const VolumeGeometry g = SmallGeometry();
  const glm::dvec3 index(1.25, 2.0, 0.5);
  const glm::dvec3 p = g.IndexToPhysical(index);
  EXPECT_DOUBLE_EQ(p.x, 0.625);
  EXPECT_DOUBLE_EQ(p.z, 1.25);
  const glm::dvec3 w = g.PhysicalToWorld(p);
  EXPECT_DOUBLE_EQ(w.x, -10.0 - 2.0);  // j axis maps to -x, 2 mm along it
  EXPECT_DOUBLE_EQ(w.y, 20.0 + 0.625);
  const glm::dvec3 back = g.WorldToPhysical(w);
  EXPECT_NEAR(glm::length(back - p), 0.0, 1e-12);
}

TEST(Volume, ClampsIndicesOutside) {
  std::vector<float> values(24);
  for (int n = 0; n < 24; ++n) values[n] = static_cast<float>(n);
  auto v = Volume::Create(SmallGeometry(), values);
  ASSERT_TRUE(v.ok()) << v.status();
  EXPECT_EQ(v->AtClamped(-5, 0, 0), 0.0f);
  EXPECT_EQ(v->AtClamped(10, 10, 10), 23.0f);
  EXPECT_EQ(v->min_value(), 0.0f);
  EXPECT_EQ(v->max_value(), 23.0f);
}

TEST(Volume, RejectsBadGeometry) {
  VolumeGeometry g = SmallGeometry();
  g.spacing_mm.y = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(Volume::Create(g, std::vector<float>(24)).status().code(),
            absl::StatusCode::kInvalidArgument);
  g = SmallGeometry();
  g.spacing_mm.x = -1.0;
  EXPECT_EQ(Volume::Create(g, std::vector<float>(24)).status().code(),
            absl::StatusCode::kInvalidArgument);
  g = SmallGeometry();
  g.dims = {0, 3, 2};
  EXPECT_EQ(Volume::Create(g, std::vector<float>{}).status().code(), absl::StatusCode::kInvalidArgument);
  g = SmallGeometry();
  g.direction[0] = glm::dvec3(2, 0, 0);
  EXPECT_EQ(Volume::Create(g, std::vector<float>(24)).status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(Volume::Create(SmallGeometry(), std::vector<float>(23)).status().code(),
            absl::StatusCode::kInvalidArgument);
}

TEST(Volume, RejectsOverCapWithoutOverflow) {
  VolumeGeometry g = SmallGeometry();
  g.dims = {int64_t{1} << 40, int64_t{1} << 40, int64_t{1} << 40};
  VolumeLimits limits;
  limits.max_volume_bytes = int64_t{1} << 62;
  EXPECT_EQ(ValidateGeometry(g, limits).code(), absl::StatusCode::kResourceExhausted);
  g.dims = {1024, 1024, 1024};
  EXPECT_EQ(ValidateGeometry(g, VolumeLimits{}).code(), absl::StatusCode::kResourceExhausted);
}

TEST(Volume, ReplacesNonFiniteWithBackgroundAndCountsThem) {
  std::vector<float> values(24, 5.0f);
  values[3] = std::numeric_limits<float>::quiet_NaN();
  values[7] = -std::numeric_limits<float>::infinity();
  values[9] = -2.0f;
  auto v = Volume::Create(SmallGeometry(), values);
  ASSERT_TRUE(v.ok());
  EXPECT_EQ(v->non_finite_count(), 2);
  EXPECT_EQ(v->At(3, 0, 0), -2.0f);
  EXPECT_EQ(v->voxels()[7], -2.0f);
}

}  // namespace
}  // namespace vpm
