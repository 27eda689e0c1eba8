// Slices of the deformed volume: the grid of each named plane, the GPU
// kernel against its CPU reference through a deforming map, the window and
// the cut-tet outline.
//
// GPU vs CPU tolerance (values in HU over the test volume's 1,700 HU range):
// mean |error| < 0.5 HU and 99.9% of pixels within 10 HU. Both read the same
// map and the same trilinear source; the GPU reads the map through its
// sampler (8-bit weights on many GPUs), which moves the rest position by up
// to 1/256 of a map cell, a few HU across the test volume's sharpest edges.
#include <algorithm>
#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

#include "server/raycast/slice_image.h"
#include "server/raycast/slice_sampler.h"
#include "server/volume/sample_trilinear.h"
#include "tests/gpu/gpu_test_context.h"
#include "tests/raycast/render_test_util.h"

namespace vpm {
namespace {

VolumeGeometry Oblique(VolumeGeometry g) {
  g.origin_mm = {-30.0, 12.0, 500.0};
  const double a = 0.3;
  g.direction = glm::dmat3(glm::dvec3(std::cos(a), std::sin(a), 0.0),
                           glm::dvec3(-std::sin(a), std::cos(a), 0.0), glm::dvec3(0.0, 0.0, 1.0));
  return g;
}

TEST(SliceGrid, NamedPlanesShowThePatientAsARadiologistReadsIt) {
  VolumeGeometry g;
  g.dims = {40, 30, 20};
  g.spacing_mm = {1.0, 1.5, 2.0};
  g.origin_mm = {-20.0, -10.0, 100.0};
  auto axial = MakeSliceGrid({.orientation = SliceOrientation::kAxial, .at_mm = 110.0}, g);
  ASSERT_TRUE(axial.ok()) << axial.status();
  EXPECT_EQ(axial->width, 39);   // 39 mm of x at 1 mm
  EXPECT_EQ(axial->height, 44);  // 43.5 mm of y
  EXPECT_EQ(axial->world_u, glm::dvec3(1.0, 0.0, 0.0));  // patient left to the right
  EXPECT_EQ(axial->world_v, glm::dvec3(0.0, 1.0, 0.0));  // posterior down
  const glm::dvec3 centre = g.PhysicalToWorld(axial->PixelCentreMm(10, 10));
  EXPECT_NEAR(centre.z, 110.0, 1e-9);
  auto coronal = MakeSliceGrid({.orientation = SliceOrientation::kCoronal, .at_mm = 0.0}, g);
  ASSERT_TRUE(coronal.ok());
  EXPECT_EQ(coronal->world_v, glm::dvec3(0.0, 0.0, -1.0));  // superior up
  auto sagittal = MakeSliceGrid({.orientation = SliceOrientation::kSagittal, .at_mm = 0.0}, g);
  ASSERT_TRUE(sagittal.ok());
  EXPECT_EQ(sagittal->world_u, glm::dvec3(0.0, 1.0, 0.0));
  // An oblique plane facing S is the axial plane.
  auto oblique = MakeSliceGrid({.orientation = SliceOrientation::kOblique,
                                .point_mm = glm::dvec3(0.0, 0.0, 110.0),
                                .normal = glm::dvec3(0.0, 0.0, 3.0)},
                               g);
  ASSERT_TRUE(oblique.ok());
  EXPECT_NEAR(glm::length(oblique->origin_mm - axial->origin_mm), 0.0, 1e-9);
  EXPECT_EQ(oblique->width, axial->width);
  // Misses and absurd sizes are refused with the volume's span.
  auto miss = MakeSliceGrid({.orientation = SliceOrientation::kAxial, .at_mm = 50.0}, g);
  EXPECT_EQ(miss.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(miss.status().message().find("misses the volume"), std::string::npos);
  EXPECT_FALSE(MakeSliceGrid({.orientation = SliceOrientation::kAxial, .at_mm = 110.0}, g, 1e-3).ok());
  EXPECT_FALSE(MakeSliceGrid({.orientation = SliceOrientation::kAxial, .at_mm = NAN}, g).ok());
  EXPECT_FALSE(MakeSliceGrid({.orientation = SliceOrientation::kOblique, .normal = glm::dvec3(0.0)}, g).ok());
  EXPECT_FALSE(SliceOrientationFromName("transverse").ok());
}

// At rest, an axial slice through a voxel layer, one pixel per voxel, reads
// the voxels themselves (CPU reference).
TEST(SliceGrid, RestSliceReadsTheVoxelLayer) {
  const Volume volume = testing::MakeSphereRodVolume(24);
  const VolumeGeometry& g = volume.geometry();
  const int k = 11;
  auto grid = MakeSliceGrid({.orientation = SliceOrientation::kAxial, .at_mm = k * g.spacing_mm.z},
                            g, g.spacing_mm.x);
  ASSERT_TRUE(grid.ok());
  const std::vector<float> values = SampleSliceCpu(volume, nullptr, *grid);
  int compared = 0;
  for (int j = 0; j < grid->height; ++j) {
    for (int i = 0; i < grid->width; ++i) {
      const glm::dvec3 p = grid->PixelCentreMm(i, j);
      const float v = values[size_t(j) * grid->width + i];
      const glm::dvec3 extent = g.extent_mm();
      if (p.x < 0 || p.y < 0 || p.x > extent.x || p.y > extent.y) {
        EXPECT_TRUE(std::isnan(v));
        continue;
      }
      EXPECT_NEAR(v, SampleTrilinear(volume, p), 1e-3);
      ++compared;
    }
  }
  EXPECT_GT(compared, 400);
}

class SliceGpuTest : public testing::GpuTest {};

TEST_F(SliceGpuTest, GpuMatchesCpuThroughADeformingMap) {
  Volume source = testing::MakeSphereRodVolume(40);
  VolumeGeometry g = Oblique(source.geometry());
  auto volume = Volume::Create(g, std::vector<float>(source.voxels().floats().begin(), source.voxels().floats().end()));
  ASSERT_TRUE(volume.ok());
  auto gpu = GpuVolume::Upload(context(), *volume);
  ASSERT_TRUE(gpu.ok()) << gpu.status();
  // A smooth bump of up to 4 mm, zero on the box faces.
  BackwardMapValues map;
  const int m = 9;
  map.dims = {m, m, m};
  map.extent_mm = g.extent_mm();
  map.values.assign(size_t(m) * m * m, glm::vec4(0.0f, 0.0f, 0.0f, 1.0f));
  for (int c = 0; c < m; ++c)
    for (int b = 0; b < m; ++b)
      for (int a = 0; a < m; ++a) {
        const double s = std::sin(std::numbers::pi * a / (m - 1)) *
                         std::sin(std::numbers::pi * b / (m - 1)) *
                         std::sin(std::numbers::pi * c / (m - 1));
        map.values[map.Index(a, b, c)] = glm::vec4(float(4.0 * s), float(-2.0 * s), 0.0f, 1.0f);
      }
  auto image = gpu::GpuImage3D::Create(context(), {uint32_t(m), uint32_t(m), uint32_t(m)},
                                       vk::Format::eR32G32B32A32Sfloat);
  ASSERT_TRUE(image.ok());
  ASSERT_TRUE(image->Upload(std::as_bytes(std::span<const glm::vec4>(map.values))).ok());
  auto sampler = SliceSampler::Create(context());
  ASSERT_TRUE(sampler.ok()) << sampler.status();
  const glm::dvec3 centre = g.PhysicalToWorld(0.5 * g.extent_mm());
  for (SlicePlane plane :
       {SlicePlane{.orientation = SliceOrientation::kAxial, .at_mm = centre.z + 3.0},
        SlicePlane{.orientation = SliceOrientation::kCoronal, .at_mm = centre.y},
        SlicePlane{.orientation = SliceOrientation::kSagittal, .at_mm = centre.x - 4.0},
        SlicePlane{.orientation = SliceOrientation::kOblique, .point_mm = centre,
                   .normal = glm::dvec3(1.0, 2.0, 3.0)}}) {
    SCOPED_TRACE(SliceOrientationName(plane.orientation));
    auto grid = MakeSliceGrid(plane, g, 0.7);
    ASSERT_TRUE(grid.ok()) << grid.status();
    auto on_gpu = sampler->Sample(*gpu, *image, map.dims, *grid);
    ASSERT_TRUE(on_gpu.ok()) << on_gpu.status();
    const std::vector<float> on_cpu = SampleSliceCpu(*volume, &map, *grid);
    ASSERT_EQ(on_gpu->size(), on_cpu.size());
    std::vector<double> errors;
    int nan_mismatch = 0;
    for (size_t i = 0; i < on_cpu.size(); ++i) {
      const bool a = std::isnan((*on_gpu)[i]), b = std::isnan(on_cpu[i]);
      if (a != b) ++nan_mismatch;
      if (!a && !b) errors.push_back(std::abs(double((*on_gpu)[i]) - on_cpu[i]));
    }
    ASSERT_GT(errors.size(), 500u);
    EXPECT_LE(nan_mismatch, int(on_cpu.size() / 1000));  // box-face pixels only
    double mean = 0.0;
    for (double e : errors) mean += e;
    mean /= double(errors.size());
    std::sort(errors.begin(), errors.end());
    EXPECT_LT(mean, 0.5) << "HU";
    EXPECT_LT(errors[size_t(0.999 * double(errors.size() - 1))], 10.0) << "HU";
    // The map moved the picture: the rest slice differs.
    const std::vector<float> rest = SampleSliceCpu(*volume, nullptr, *grid);
    double moved = 0.0;
    for (size_t i = 0; i < rest.size(); ++i) {
      if (!std::isnan(rest[i]) && !std::isnan(on_cpu[i])) moved += std::abs(rest[i] - on_cpu[i]);
    }
    EXPECT_GT(moved / double(errors.size()), 2.0) << "HU per pixel";
  }
}

TEST(SliceImage, WindowMapsLevelToMidGreyAndNanToBlack) {
  const std::vector<float> values = {40.0f, -160.0f, 240.0f, 1000.0f, NAN, -2000.0f};
  const auto rgba = SliceToRgba(values, 3, 2, MipWindow{40.0, 400.0});
  EXPECT_EQ(rgba[0], 128);
  EXPECT_EQ(rgba[4], 0);
  EXPECT_EQ(rgba[8], 255);
  EXPECT_EQ(rgba[12], 255);
  EXPECT_EQ(rgba[16], 0);
  EXPECT_EQ(rgba[19], 255);
  EXPECT_FALSE(ValidateMipWindow({40.0, 0.0}).ok());
  EXPECT_FALSE(ValidateMipWindow({NAN, 10.0}).ok());
}

TEST(SliceImage, CutTetsOutlineOnlyTheTetsThePlaneCrosses) {
  VolumeGeometry g;
  g.dims = {21, 21, 21};
  auto grid = MakeSliceGrid({.orientation = SliceOrientation::kAxial, .at_mm = 10.0}, g);
  ASSERT_TRUE(grid.ok());
  const std::vector<glm::dvec3> positions = {{2, 2, 5},  {15, 2, 5},  {2, 15, 5},  {5, 5, 15},
                                             {2, 2, 12}, {15, 2, 12}, {2, 15, 12}, {5, 5, 18}};
  const std::vector<std::array<int32_t, 4>> tets = {{0, 1, 2, 3}, {4, 5, 6, 7}};
  std::vector<uint8_t> rgba(size_t(grid->width) * grid->height * 4, 0);
  const uint8_t red[3] = {255, 0, 0};
  EXPECT_EQ(DrawCutTets(*grid, positions, tets, red, rgba), 1);
  int lit = 0;
  for (size_t i = 0; i < rgba.size(); i += 4) lit += rgba[i] == 255;
  EXPECT_GT(lit, 10);
  EXPECT_TRUE(DrawSliceMarker(*grid, glm::dvec3(10.0, 10.0, 10.5), 1.0, red, rgba));
  EXPECT_FALSE(DrawSliceMarker(*grid, glm::dvec3(10.0, 10.0, 14.0), 1.0, red, rgba));
}

// The slices' default window: soft tissue (W 400 L 40) on CT in HU, the
// 1st..99th percentile on any other volume (the same values above 0, as an
// MRI's).
TEST(SliceWindow, SoftTissueOnCtPercentilesElse) {
  const Volume ct = testing::MakeSphereRodVolume(16);
  const MipWindow on_ct = DefaultSliceWindow(ct);
  EXPECT_EQ(on_ct.width, 400.0);
  EXPECT_EQ(on_ct.level, 40.0);
  std::vector<float> shifted(static_cast<size_t>(ct.voxels().size()));
  for (size_t n = 0; n < shifted.size(); ++n) {
    shifted[n] = ct.voxels()[static_cast<int64_t>(n)] - ct.min_value();
  }
  const Volume mri = *Volume::Create(ct.geometry(), std::move(shifted));
  const MipWindow on_mri = DefaultSliceWindow(mri);
  EXPECT_GT(on_mri.level - 0.5 * on_mri.width, -1.0);  // black at or above the lowest value
  EXPECT_LE(on_mri.level + 0.5 * on_mri.width, mri.max_value() + 1.0);
  EXPECT_GT(on_mri.width, 0.0);
  EXPECT_NE(on_mri.width, 400.0);
}

}  // namespace
}  // namespace vpm
