#include "server/io/resample_sheared_stack.h"

#include <cmath>

#include <gtest/gtest.h>

namespace vpm {
namespace {

// A field linear in world coordinates: bilinear-then-linear resampling must
// reproduce it exactly wherever the output voxel lies inside the stack.
double Field(const glm::dvec3& world_mm) {
  return 3.0 + 2.0 * world_mm.x - 1.5 * world_mm.y + 0.75 * world_mm.z;
}

// Slices of `columns` x `rows` pixels at the given frame positions, filled
// with Field at each pixel's world position.
struct StackFixture {
  ShearedStack stack;
  std::vector<std::vector<float>> values;

  StackFixture(const glm::dmat3& frame, const std::vector<glm::dvec3>& positions,
               int64_t columns = 6, int64_t rows = 5, glm::dvec2 pitch = {0.5, 0.75}) {
    stack.columns = columns;
    stack.rows = rows;
    stack.pixel_spacing_mm = pitch;
    stack.frame = frame;
    for (const glm::dvec3& p : positions) {
      std::vector<float> v;
      for (int64_t j = 0; j < rows; ++j) {
        for (int64_t i = 0; i < columns; ++i) {
          v.push_back(
              static_cast<float>(Field(frame * (p + glm::dvec3(i * pitch.x, j * pitch.y, 0)))));
        }
      }
      values.push_back(std::move(v));
    }
    for (size_t k = 0; k < positions.size(); ++k) stack.slices.push_back({positions[k], values[k]});
  }
};

glm::dmat3 TiltedFrame(double degrees) {
  const double c = std::cos(glm::radians(degrees)), s = std::sin(glm::radians(degrees));
  return glm::dmat3(glm::dvec3(1, 0, 0), glm::dvec3(0, c, -s), glm::dvec3(0, s, c));
}

TEST(ResampleShearedStack, KeepsAnUnshearedEvenStackBitForBit) {
  StackFixture f(TiltedFrame(10.0), {{1, 2, 3}, {1, 2, 5}, {1, 2, 7}});
  auto v = ResampleShearedStack(f.stack, 2.0, -1000.0f, {});
  ASSERT_TRUE(v.ok()) << v.status();
  EXPECT_EQ(v->dims(), (std::array<int64_t, 3>{6, 5, 3}));
  for (int64_t k = 0; k < 3; ++k) {
    for (int64_t n = 0; n < 30; ++n) EXPECT_EQ(v->voxels()[k * 30 + n], f.values[k][n]);
  }
  EXPECT_NEAR(glm::distance(v->geometry().origin_mm, f.stack.frame * glm::dvec3(1, 2, 3)), 0.0,
              1e-12);
}

TEST(ResampleShearedStack, ShearedStackCoversEverySliceAndReproducesLinearField) {
  // Each slice 0.9 mm further along the column direction per 2 mm along the
  // normal (a 24 degree tilt), and 0.25 mm back along the row direction.
  std::vector<glm::dvec3> positions;
  for (int k = 0; k < 5; ++k) positions.push_back({-0.25 * k, 0.9 * k, 2.0 * k});
  StackFixture f(TiltedFrame(18.5), positions);
  auto v = ResampleShearedStack(f.stack, 2.0, -1000.0f, {});
  ASSERT_TRUE(v.ok()) << v.status();
  const VolumeGeometry& g = v->geometry();
  // x from -1.0 to 2.5 mm (8 voxels of 0.5); y from 0 to 3.6 + 3.0 mm: 8.8
  // steps of 0.75, rounded up to 9 so that the last rows are kept.
  EXPECT_EQ(g.dims, (std::array<int64_t, 3>{8, 10, 5}));
  EXPECT_NEAR(glm::distance(g.origin_mm, f.stack.frame * glm::dvec3(-1.0, 0.0, 0.0)), 0.0, 1e-12);
  int inside = 0, outside = 0;
  for (int64_t k = 0; k < g.dims[2]; ++k) {
    for (int64_t j = 0; j < g.dims[1]; ++j) {
      for (int64_t i = 0; i < g.dims[0]; ++i) {
        const glm::dvec3 p = glm::dvec3(i, j, k) * g.spacing_mm;
        const glm::dvec3 in_frame = glm::dvec3(-1.0, 0.0, 0.0) + p;
        const glm::dvec3 local = (in_frame - positions[k]) / glm::dvec3(0.5, 0.75, 1.0);
        const bool covered =
            local.x > -1e-9 && local.x < 5 + 1e-9 && local.y > -1e-9 && local.y < 4 + 1e-9;
        if (covered) {
          ++inside;
          EXPECT_NEAR(v->At(i, j, k), Field(g.PhysicalToWorld(p)), 1e-3)
              << i << " " << j << " " << k;
        } else {
          ++outside;
          EXPECT_EQ(v->At(i, j, k), -1000.0f) << i << " " << j << " " << k;
        }
      }
    }
  }
  EXPECT_GT(inside, 4 * 20);  // most of each slice's 30 pixels' area
  EXPECT_GT(outside, 0);
}

TEST(ResampleShearedStack, InterpolatesLinearlyBetweenUnevenSlices) {
  StackFixture f(glm::dmat3(1.0), {{0, 0, 0}, {0, 0, 1}, {0, 0, 4}, {0, 0, 4.5}});
  auto v = ResampleShearedStack(f.stack, 0.5, -1000.0f, {});
  ASSERT_TRUE(v.ok()) << v.status();
  const VolumeGeometry& g = v->geometry();
  ASSERT_EQ(g.dims[2], 10);  // 0, 0.5, ... 4.5 mm
  for (int64_t k = 0; k < g.dims[2]; ++k) {
    for (int64_t j = 0; j < g.dims[1]; ++j) {
      for (int64_t i = 0; i < g.dims[0]; ++i) {
        const glm::dvec3 p = glm::dvec3(i, j, k) * g.spacing_mm;
        EXPECT_NEAR(v->At(i, j, k), Field(g.PhysicalToWorld(p)), 1e-3);
      }
    }
  }
}

TEST(ResampleShearedStack, ChecksTheCapOnTheLargerGridAndRejectsBadInput) {
  std::vector<glm::dvec3> positions;
  for (int k = 0; k < 4; ++k) positions.push_back({0.0, 3.0 * k, 1.0 * k});
  StackFixture f(glm::dmat3(1.0), positions);
  VolumeLimits limits;
  limits.max_volume_bytes = 4 * 30 * 4;  // float  // the slices fit, the sheared box (6 x 17 x 4) does not
  auto v = ResampleShearedStack(f.stack, 1.0, 0.0f, limits);
  ASSERT_FALSE(v.ok());
  EXPECT_EQ(v.status().code(), absl::StatusCode::kResourceExhausted) << v.status();
  EXPECT_EQ(ResampleShearedStack(f.stack, 0.0, 0.0f, {}).status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(ResampleShearedStack(f.stack, std::nan(""), 0.0f, {}).status().code(),
            absl::StatusCode::kInvalidArgument);
  std::swap(f.stack.slices[0], f.stack.slices[1]);
  EXPECT_EQ(ResampleShearedStack(f.stack, 1.0, 0.0f, {}).status().code(),
            absl::StatusCode::kInvalidArgument);
  f.stack.slices.resize(1);
  EXPECT_EQ(ResampleShearedStack(f.stack, 1.0, 0.0f, {}).status().code(),
            absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace vpm
