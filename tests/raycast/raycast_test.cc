// The GPU ray caster against its CPU reference, and the properties the
// renderer promises: skipping and early termination change the work, not the
// picture; a half turn of the camera mirrors a MIP; a golden frame of the
// phantom; bad requests are refused.
//
// Tolerances (per channel, normalised to [0, 1]): GPU vs CPU mean |error| <
// 1/255 and max < 8/255 (both cast the same rays through the same table in
// float; differences come from the order of float operations, the GPU's
// pow, and an occasional early-termination or shading threshold crossed on
// one side only). The sampler3D variant is held to mean < 2/255, max <
// 24/255: its trilinear weights carry 8 bits (lavapipe). Golden: PSNR > 35 dB.
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>

#include <gtest/gtest.h>

#include "server/phantom/phantom.h"
#include "server/raycast/raycast_cpu.h"
#include "server/raycast/volume_renderer.h"
#include "tests/gpu/gpu_test_context.h"
#include "tests/raycast/raycast_fixture.h"
#include "tests/raycast/render_test_util.h"
#include "tests/volume/int16_twin.h"

namespace vpm {
namespace {

using testing::CompareRgba;
using testing::ExpectClose;
using testing::LitPixels;
using testing::MaybeDump;

using testing::RaycastTest;

// Both gradients of a still frame: the cell gradient (the default) and the
// central-difference taps.
TEST_F(RaycastTest, Dvr_GpuMatchesCpuReference) {
  for (const char* preset : {"ct-vessels", "ct-soft-tissue", "ct-bone"}) {
    for (bool cell : {true, false}) {
      SCOPED_TRACE(::testing::Message() << preset << (cell ? " cell gradient" : " taps"));
      RenderRequest r = Request(RenderMode::kDvr, preset);
      r.settings.still_cell_gradient = cell;
      const Frame gpu = RenderGpu(r);
      const Frame cpu = RenderCpu(r);
      const std::string name = std::string(preset) + (cell ? "" : "_taps");
      MaybeDump("dvr_gpu_" + name, gpu.rgba, gpu.width, gpu.height);
      MaybeDump("dvr_cpu_" + name, cpu.rgba, cpu.width, cpu.height);
      EXPECT_GT(LitPixels(gpu), 300) << preset;
      ExpectClose(gpu, cpu, 1.0 / 255, 8.0 / 255, preset);
    }
  }
}

TEST_F(RaycastTest, Mip_GpuMatchesCpuReference) {
  RenderRequest r = Request(RenderMode::kMip);
  const Frame gpu = RenderGpu(r);
  const Frame cpu = RenderCpu(r);
  MaybeDump("mip_gpu", gpu.rgba, gpu.width, gpu.height);
  EXPECT_GT(LitPixels(gpu), 300);
  ExpectClose(gpu, cpu, 1.0 / 255, 8.0 / 255, "mip");
}

TEST_F(RaycastTest, IdentityMapImage_SameAsNoMap) {
  HostBackwardMap host;
  auto map = MakeMap(7, 0.0, &host);
  ASSERT_TRUE(map.ok()) << map.status();
  for (RenderMode mode : {RenderMode::kDvr, RenderMode::kMip}) {
    RenderRequest r = Request(mode);
    const Frame plain = RenderGpu(r);
    r.backward_map = &*map;
    const Frame mapped = RenderGpu(r);
    ExpectClose(mapped, plain, 0.5 / 255, 4.0 / 255, "identity map");
    ExpectClose(mapped, RenderCpu(r, &host), 1.0 / 255, 8.0 / 255, "identity map vs CPU");
  }
}

TEST_F(RaycastTest, DeformingMap_GpuMatchesCpuAndSkippingStaysExact) {
  HostBackwardMap host;
  auto map = MakeMap(9, 6.0, &host);
  ASSERT_TRUE(map.ok()) << map.status();
  for (int variant = 0; variant < 3; ++variant) {
    // DVR with the cell gradient, DVR with the taps, MIP.
    const RenderMode mode = variant < 2 ? RenderMode::kDvr : RenderMode::kMip;
    SCOPED_TRACE(variant);
    RenderRequest r = Request(mode);
    r.settings.still_cell_gradient = variant == 0;
    const Frame undeformed = RenderGpu(r);
    r.backward_map = &*map;
    const Frame gpu = RenderGpu(r);
    MaybeDump(variant == 0 ? "deformed_dvr" : variant == 1 ? "deformed_dvr_taps" : "deformed_mip",
              gpu.rgba, gpu.width, gpu.height);
    // The map moves the picture.
    EXPECT_GT(CompareRgba(gpu.rgba, undeformed.rgba).mean_abs, 2.0 / 255);
    // Lavapipe's sampler weighs the map with 8-bit fractions, the CPU exactly.
    ExpectClose(gpu, RenderCpu(r, &host), 1.5 / 255, 16.0 / 255, "deformed vs CPU");
    r.settings.empty_space_skipping = false;
    const Frame no_skip = RenderGpu(r);
    ExpectClose(gpu, no_skip, 0.25 / 255, 4.0 / 255, "deformed, skipping on/off");
  }
}

// The map's values given as a buffer (BackwardMap::values_buffer) are read
// in place, with the same picture as the renderer's own copy of the image;
// a buffer too small for the map is refused.
TEST_F(RaycastTest, MapTexelsInPlace_SameFrameAsImageCopy) {
  HostBackwardMap host;
  auto map = MakeMap(9, 6.0, &host);
  ASSERT_TRUE(map.ok()) << map.status();
  using BU = vk::BufferUsageFlagBits;
  auto texels = gpu::GpuBuffer::Create(context(), host.texels.size() * sizeof(glm::vec4),
                                       BU::eStorageBuffer | BU::eUniformTexelBuffer);
  ASSERT_TRUE(texels.ok()) << texels.status();
  ASSERT_TRUE(texels->UploadSpan(std::span<const glm::vec4>(host.texels)).ok());
  for (RenderMode mode : {RenderMode::kDvr, RenderMode::kMip}) {
    RenderRequest r = Request(mode);
    r.backward_map = &*map;
    const Frame copied = RenderGpu(r);
    r.backward_map_texels = &*texels;
    const Frame in_place = RenderGpu(r);
    EXPECT_EQ(in_place.timings.map_copy_ms, 0.0);
    EXPECT_EQ(in_place.rgba, copied.rgba);
  }
  auto small = gpu::GpuBuffer::Create(context(), 16 * sizeof(glm::vec4),
                                      BU::eStorageBuffer | BU::eUniformTexelBuffer);
  ASSERT_TRUE(small.ok()) << small.status();
  RenderRequest r = Request(RenderMode::kDvr);
  r.backward_map = &*map;
  r.backward_map_texels = &*small;
  EXPECT_EQ(renderer_->Render(r).status().code(), absl::StatusCode::kInvalidArgument);
}

TEST_F(RaycastTest, Occupancy_ReusedOnlyWhileMapVersionAndPresetHold) {
  HostBackwardMap host;
  auto map = MakeMap(9, 6.0, &host);
  ASSERT_TRUE(map.ok()) << map.status();
  RenderRequest r = Request(RenderMode::kDvr);
  r.backward_map = &*map;
  EXPECT_FALSE(RenderGpu(r).occupancy_reused);
  EXPECT_FALSE(RenderGpu(r).occupancy_reused);  // version 0: the content may have changed
  r.backward_map_version = 7;
  const Frame first = RenderGpu(r);
  const Frame again = RenderGpu(r);
  EXPECT_FALSE(first.occupancy_reused);
  EXPECT_TRUE(again.occupancy_reused);
  EXPECT_EQ(again.rgba, first.rgba);
  r.backward_map_version = 8;
  EXPECT_FALSE(RenderGpu(r).occupancy_reused);
  r.preset = *MakeRenderPreset("ct-bone", *volume_);
  EXPECT_FALSE(RenderGpu(r).occupancy_reused);
  r.mode = RenderMode::kMip;
  EXPECT_FALSE(RenderGpu(r).occupancy_reused);
  r.backward_map = nullptr;
  EXPECT_FALSE(RenderGpu(r).occupancy_reused);
  EXPECT_TRUE(RenderGpu(r).occupancy_reused);  // no map: nothing can change behind our back
}

// After a map update that changed a box of grid points, a renderer whose
// occupancy is of the previous version redoes only the bricks meeting that
// box (RenderRequest::backward_map_previous_version); the frame, samples and
// occupied bricks are those of a renderer that computes every brick.
TEST_F(RaycastTest, Occupancy_PartialAfterAMapChangeEqualsAFullPass) {
  for (int variant = 0; variant < 4; ++variant) {
    const RenderMode mode = variant % 2 == 0 ? RenderMode::kDvr : RenderMode::kMip;
    SCOPED_TRACE(::testing::Message() << "variant " << variant);
    HostBackwardMap host;
    auto map = MakeMap(17, 6.0, &host);
    ASSERT_TRUE(map.ok()) << map.status();
    RenderRequest r = Request(mode, mode == RenderMode::kDvr ? "ct-bone" : "ct-vessels");
    r.quality = variant < 2 ? RenderQuality::kStill : RenderQuality::kInteractive;
    r.backward_map = &*map;
    r.backward_map_version = 100 + variant;
    r.settings.count_samples = true;
    const Frame before = RenderGpu(r);
    // A large shift in one corner of the map: the bricks there see other
    // source bricks.
    const glm::ivec3 lo(0, 2, 3), hi(6, 10, 12);
    for (int c = lo.z; c <= hi.z; ++c)
      for (int b = lo.y; b <= hi.y; ++b)
        for (int a = lo.x; a <= hi.x; ++a) {
          host.texels[a + 17 * (b + 17 * c)] += glm::vec4(14.0f, -9.0f, 11.0f, 0.0f);
        }
    ASSERT_TRUE(map->Upload(std::as_bytes(std::span<const glm::vec4>(host.texels))).ok());
    r.backward_map_previous_version = r.backward_map_version;
    r.backward_map_version += 10;
    r.backward_map_changed_lo = lo;
    r.backward_map_changed_hi = hi;
    const Frame partial = RenderGpu(r);
    EXPECT_FALSE(partial.occupancy_reused);
    EXPECT_EQ(before.occupancy_bricks_computed, before.total_bricks);
    EXPECT_GT(partial.occupancy_bricks_computed, 0);
    EXPECT_LT(partial.occupancy_bricks_computed, partial.total_bricks / 2);
    auto fresh = VolumeRenderer::Create(context(), {});
    ASSERT_TRUE(fresh.ok()) << fresh.status();
    auto full = (*fresh)->Render(r);
    ASSERT_TRUE(full.ok()) << full.status();
    // The change shows in the occupancy (DVR) or the samples (MIP, which
    // counts the bricks whose maximum passes the window: the same here).
    EXPECT_TRUE(partial.occupied_bricks != before.occupied_bricks ||
                partial.samples != before.samples);
    EXPECT_EQ(full->occupancy_bricks_computed, full->total_bricks);
    EXPECT_EQ(partial.occupied_bricks, full->occupied_bricks);
    EXPECT_EQ(partial.samples, full->samples);
    EXPECT_EQ(partial.rgba, full->rgba);
  }
}

TEST_F(RaycastTest, EmptySpaceSkipping_SameImageFewerSamples) {
  for (RenderMode mode : {RenderMode::kDvr, RenderMode::kMip}) {
    SCOPED_TRACE(mode == RenderMode::kDvr ? "DVR" : "MIP");
    RenderRequest r = Request(mode, "ct-bone");
    r.mip_window = MipWindow{450.0, 500.0};  // black at 200 HU: the soft tissue is skipped
    r.settings.count_samples = true;
    const Frame on = RenderGpu(r);
    r.settings.empty_space_skipping = false;
    const Frame off = RenderGpu(r);
    ExpectClose(on, off, 0.25 / 255, 4.0 / 255, "skipping on/off");
    ASSERT_GT(off.samples, 0);
    EXPECT_LT(on.samples, off.samples / 2) << "on " << on.samples << ", off " << off.samples;
    EXPECT_GT(on.occupied_bricks, 0);
    EXPECT_LT(on.occupied_bricks, on.total_bricks / 2);
    // The CPU reference skips the same bricks and takes the same samples.
    r.settings.empty_space_skipping = true;
    const Frame cpu = RenderCpu(r);
    EXPECT_EQ(cpu.occupied_bricks, on.occupied_bricks);
    EXPECT_NEAR(double(cpu.samples), double(on.samples), 0.002 * on.samples);
  }
}

// The occupancy pass (brick_occupancy.comp) keeps the bricks the CPU
// reference keeps, through deforming maps coarser and finer than the voxels
// (9^3, 48^3, 160^3, 1100 x 9 x 9 points on a 48^3 volume; 1200 x 3 x 3 on a
// 6^3 one), for the bricks of still (4^3) and interactive (8^3) frames.
TEST_F(RaycastTest, Occupancy_GpuMatchesCpuThroughDeformingMaps) {
  struct MapCase {
    int n;  // volume side
    std::array<int, 3> dims;
  };
  for (const MapCase& c : {MapCase{48, {9, 9, 9}}, MapCase{48, {48, 48, 48}},
                           MapCase{48, {160, 160, 160}}, MapCase{48, {1100, 9, 9}},
                           MapCase{6, {1200, 3, 3}}}) {
    const Volume volume = testing::MakeSphereRodVolume(c.n);
    auto gpu_volume = GpuVolume::Upload(context(), volume);
    ASSERT_TRUE(gpu_volume.ok()) << gpu_volume.status();
    HostBackwardMap host{c.dims, {}};
    const auto& m = c.dims;
    host.texels.resize(size_t(m[0]) * m[1] * m[2]);
    for (int k = 0; k < m[2]; ++k)
      for (int j = 0; j < m[1]; ++j)
        for (int i = 0; i < m[0]; ++i) {
          const double s = std::sin(std::numbers::pi * i / (m[0] - 1)) *
                           std::sin(std::numbers::pi * (j + 0.5) / m[1]) *
                           std::sin(std::numbers::pi * (k + 0.5) / m[2]);
          host.texels[i + m[0] * (j + m[1] * k)] =
              glm::vec4(float(5.0 * s), float(-2.0 * s), float(-3.0 * s), 1.0f);
        }
    auto map = gpu::GpuImage3D::Create(
        context(), {uint32_t(m[0]), uint32_t(m[1]), uint32_t(m[2])},
        vk::Format::eR32G32B32A32Sfloat);
    ASSERT_TRUE(map.ok()) << map.status();
    ASSERT_TRUE(map->Upload(std::as_bytes(std::span<const glm::vec4>(host.texels))).ok());
    for (int variant = 0; variant < 4; ++variant) {
      const RenderMode mode = variant % 2 == 0 ? RenderMode::kDvr : RenderMode::kMip;
      const RenderQuality quality = variant < 2 ? RenderQuality::kStill : RenderQuality::kInteractive;
      SCOPED_TRACE(::testing::Message() << "volume " << c.n << ", map " << m[0] << "x" << m[1]
                                        << "x" << m[2] << (mode == RenderMode::kDvr ? " DVR" : " MIP")
                                        << (variant < 2 ? " still" : " interactive"));
      // The 6^3 volume has no bone: its soft tissue instead.
      RenderRequest r = Request(mode, c.n > 6 ? "ct-bone" : "ct-soft-tissue", 48);
      r.camera = Camera::ForVolume(volume.geometry());
      r.camera.Orbit(30.0, 20.0);
      r.volume = &*gpu_volume;
      r.backward_map = &*map;
      r.quality = quality;
      r.mip_window = c.n > 6 ? MipWindow{450.0, 500.0} : MipWindow{-100.0, 200.0};
      r.settings.count_samples = true;
      const Frame gpu = RenderGpu(r);
      auto cpu = RenderReference(r, volume, &host, 2);
      ASSERT_TRUE(cpu.ok()) << cpu.status();
      EXPECT_GT(gpu.occupied_bricks, 0);
      EXPECT_EQ(gpu.occupied_bricks, cpu->occupied_bricks);
      EXPECT_NEAR(double(cpu->samples), double(gpu.samples), 0.002 * gpu.samples + 2.0);
    }
  }
}

TEST_F(RaycastTest, EarlyTermination_SameImageFewerSamples) {
  RenderRequest r = Request(RenderMode::kDvr, "ct-soft-tissue");
  r.settings.count_samples = true;
  r.settings.empty_space_skipping = false;
  const Frame on = RenderGpu(r);
  r.settings.early_termination = false;
  const Frame off = RenderGpu(r);
  ExpectClose(on, off, 1.0 / 255, 4.0 / 255, "early termination on/off");
  EXPECT_LT(on.samples, off.samples);
}

// MIP stops once its maximum reaches the window's white (the bone rod at
// 700 HU, white at 450 under ct-vessels): the picture cannot change, so it
// must stay bit for bit; GPU and CPU stop alike.
TEST_F(RaycastTest, MipEarlyTermination_SameImageFewerSamples) {
  RenderRequest r = Request(RenderMode::kMip);
  r.settings.count_samples = true;
  const Frame on = RenderGpu(r);
  ExpectClose(on, RenderCpu(r), 1.0 / 255, 8.0 / 255, "mip, early termination");
  r.settings.early_termination = false;
  const Frame off = RenderGpu(r);
  ExpectClose(on, off, 1e-9, 1e-9, "mip, early termination on/off");
  EXPECT_LT(on.samples, off.samples);
}

// MIP samples the brick that can show the most first, then skips the bricks
// under what it found: the picture stays bit for bit that of the walk in
// order (the maximum of the same samples above the window's black), with
// and without early termination, and the CPU reference takes the samples
// the GPU takes.
TEST_F(RaycastTest, MipBrightestFirst_SameImageFewerSamples) {
  for (bool early : {true, false}) {
    SCOPED_TRACE(early ? "early termination" : "no early termination");
    RenderRequest r = Request(RenderMode::kMip);
    r.settings.count_samples = true;
    r.settings.early_termination = early;
    const Frame first = RenderGpu(r);
    const Frame cpu = RenderCpu(r);
    EXPECT_NEAR(double(cpu.samples), double(first.samples), 0.002 * first.samples + 2.0);
    ExpectClose(first, cpu, 1.0 / 255, 8.0 / 255, "mip, brightest first, GPU/CPU");
    r.settings.mip_brightest_first = false;
    const Frame in_order = RenderGpu(r);
    ExpectClose(first, in_order, 1e-9, 1e-9, "mip, brightest first on/off");
    EXPECT_LT(first.samples, in_order.samples);
  }
}

TEST_F(RaycastTest, InteractiveQuality_HalfResolutionUpscaled) {
  RenderRequest r = Request(RenderMode::kDvr);
  r.quality = RenderQuality::kInteractive;
  r.width = 101;  // odd: the ray-cast size rounds up
  r.height = 64;
  const Frame gpu = RenderGpu(r);
  EXPECT_EQ(gpu.render_width, 51);
  EXPECT_EQ(gpu.render_height, 32);
  EXPECT_EQ(gpu.rgba.size(), size_t(101 * 64 * 4));
  EXPECT_DOUBLE_EQ(gpu.step_mm, 1.0);  // 1 x the smallest spacing
  ExpectClose(gpu, RenderCpu(r), 1.0 / 255, 8.0 / 255, "interactive");
  // Close to the still frame of the same view.
  r.quality = RenderQuality::kStill;
  EXPECT_GT(CompareRgba(gpu.rgba, RenderGpu(r).rgba).psnr_db, 22.0);
}

// A still frame cast in bands (interleaved rows of tiles), one submit each
// or several to a submit, is the frame cast in one: the same pixels bit for
// bit and the same samples, for DVR and MIP, through a map, with bands of
// unequal height; interactive frames stay whole.
// Interactive DVR shades with the gradient of the trilinear cells (chain
// rule through the map): GPU and CPU agree as for the tap gradient, and the
// picture stays close to that of the taps.
TEST_F(RaycastTest, CellGradient_MatchesCpuAndTheTapGradient) {
  HostBackwardMap host;
  auto map = MakeMap(9, 6.0, &host);
  ASSERT_TRUE(map.ok()) << map.status();
  for (RenderQuality quality : {RenderQuality::kInteractive, RenderQuality::kStill}) {
    const bool interactive = quality == RenderQuality::kInteractive;
    for (const char* preset : {"ct-soft-tissue", "ct-vessels", "ct-bone"}) {
      for (bool with_map : {false, true}) {
        SCOPED_TRACE(::testing::Message() << (interactive ? "interactive " : "still ") << preset
                                          << (with_map ? " with map" : ""));
        RenderRequest r = Request(RenderMode::kDvr, preset);
        r.quality = quality;
        r.backward_map = with_map ? &*map : nullptr;
        const HostBackwardMap* host_map = with_map ? &host : nullptr;
        const Frame cell = RenderGpu(r);
        MaybeDump(std::string(interactive ? "interactive_cell_" : "still_cell_") + preset +
                      (with_map ? "_map" : ""),
                  cell.rgba, cell.width, cell.height);
        ExpectClose(cell, RenderCpu(r, host_map), 1.0 / 255, 8.0 / 255, "cell gradient vs CPU");
        r.settings.interactive_cell_gradient = false;
        r.settings.still_cell_gradient = false;
        const Frame taps = RenderGpu(r);
        const auto diff = CompareRgba(cell.rgba, taps.rgba);
        std::printf("  %s %s%s: cell vs tap gradient mean %.3f/255, max %.0f/255, PSNR %.1f dB\n",
                    interactive ? "interactive" : "still", preset, with_map ? " (map)" : "",
                    diff.mean_abs * 255, diff.max_abs * 255, diff.psnr_db);
        EXPECT_GT(diff.psnr_db, 30.0);
      }
    }
  }
}

TEST_F(RaycastTest, OrbitHalfTurn_MirrorsMipHorizontally) {
  RenderRequest r = Request(RenderMode::kMip, "ct-vessels", 80);
  // Nearly parallel rays (a 1 degree field of view from far away, same
  // framing): under perspective the front and back views see the box's
  // near face larger, so only parallel projection mirrors exactly.
  r.camera = Camera::ForVolume(volume_->geometry());
  Camera::Pose pose = r.camera.pose();
  pose.distance_mm *= std::tan(pose.fov_deg * std::numbers::pi / 360.0) /
                      std::tan(std::numbers::pi / 360.0);
  pose.fov_deg = 1.0;
  r.camera.set_pose(pose);
  const Frame front = RenderGpu(r);
  r.camera.Orbit(180.0, 0.0);
  const Frame back = RenderGpu(r);
  std::vector<uint8_t> mirrored(back.rgba.size());
  for (int y = 0; y < back.height; ++y)
    for (int x = 0; x < back.width; ++x)
      for (int c = 0; c < 4; ++c) {
        mirrored[(size_t(y) * back.width + x) * 4 + c] =
            back.rgba[(size_t(y) * back.width + (back.width - 1 - x)) * 4 + c];
      }
  MaybeDump("mip_front", front.rgba, front.width, front.height);
  MaybeDump("mip_back_mirrored", mirrored, back.width, back.height);
  EXPECT_GT(LitPixels(front), 300);
  const auto e = CompareRgba(front.rgba, mirrored);
  // Samples sit at other depths along mirrored rays: small differences.
  EXPECT_LT(e.mean_abs, 2.0 / 255);
  EXPECT_GT(e.psnr_db, 30.0);
  // And it is not symmetric on its own: unmirrored, the frames differ.
  EXPECT_GT(CompareRgba(front.rgba, back.rgba).mean_abs, 4.0 * e.mean_abs);
}

TEST_F(RaycastTest, Sampler3DVariant_MatchesCpuReference) {
  auto renderer = VolumeRenderer::Create(context(), {.volume_access = VolumeAccess::kSampler3D});
  ASSERT_TRUE(renderer.ok()) << renderer.status();
  auto image = gpu_volume_->Image(context(), *volume_);
  ASSERT_TRUE(image.ok()) << image.status();
  for (RenderMode mode : {RenderMode::kDvr, RenderMode::kMip}) {
    RenderRequest r = Request(mode);
    EXPECT_EQ((*renderer)->Render(r).status().code(), absl::StatusCode::kInvalidArgument);
    r.volume_image = *image;
    auto gpu = (*renderer)->Render(r);
    ASSERT_TRUE(gpu.ok()) << gpu.status();
    ExpectClose(*gpu, RenderCpu(r), 2.0 / 255, 24.0 / 255, "sampler3D");
  }
  // Interactive DVR (cell gradient): texelFetch of the 8 corners, as the CPU.
  HostBackwardMap host;
  auto map = MakeMap(9, 6.0, &host);
  ASSERT_TRUE(map.ok()) << map.status();
  RenderRequest r = Request(RenderMode::kDvr, "ct-soft-tissue");
  r.quality = RenderQuality::kInteractive;
  r.volume_image = *image;
  r.backward_map = &*map;
  auto gpu = (*renderer)->Render(r);
  ASSERT_TRUE(gpu.ok()) << gpu.status();
  ExpectClose(*gpu, RenderCpu(r, &host), 2.0 / 255, 24.0 / 255, "sampler3D, cell gradient");
}

// The sphere-rod volume rounded to integers, held as int16 (offset 0 and
// 30000) and as float: the GPU reads int16 voxels in pairs or packed and
// floats in pairs (server/volume/gpu_volume.h) and decodes all to the same
// floats, so every frame is bit for bit the same;
// the int16 frames match the CPU reference within the tolerances above, the
// sampler3D's R16_UNORM image within its own.
TEST_F(RaycastTest, Int16Volume_SameFramesAsFloatAndCpu) {
  HostBackwardMap host;
  auto map = MakeMap(9, 6.0, &host);
  ASSERT_TRUE(map.ok()) << map.status();
  for (int32_t offset : {0, 30000}) {
    const auto [int16, floats] = testing::MakeInt16Twin(*volume_, offset);
    auto gpu16 = GpuVolume::Upload(context(), int16);
    auto gpu32 = GpuVolume::Upload(context(), floats);
    auto packed = GpuVolume::Upload(context(), int16, {}, GpuVolume::TexelLayout::kPacked);
    ASSERT_TRUE(gpu16.ok() && gpu32.ok() && packed.ok());
    for (RenderMode mode : {RenderMode::kDvr, RenderMode::kMip}) {
      for (bool interactive : {false, true}) {
        SCOPED_TRACE(::testing::Message() << "offset " << offset << " mode " << int(mode)
                                          << (interactive ? " interactive" : " still"));
        RenderRequest r = Request(mode);
        r.preset = *MakeRenderPreset(mode == RenderMode::kDvr ? "ct-soft-tissue" : "ct-vessels",
                                     floats);
        if (interactive) {
          r.quality = RenderQuality::kInteractive;
          r.backward_map = &*map;
        }
        r.volume = &*gpu16;
        const Frame a = RenderGpu(r);
        r.volume = &*gpu32;
        const Frame b = RenderGpu(r);
        r.volume = &*packed;  // the layout of int16 volumes past the texel limit
        const Frame c = RenderGpu(r);
        EXPECT_GT(LitPixels(a), 300);
        EXPECT_EQ(a.rgba, b.rgba);
        EXPECT_EQ(a.rgba, c.rgba);
        auto cpu = RenderReference(r, int16, interactive ? &host : nullptr, 2);
        ASSERT_TRUE(cpu.ok()) << cpu.status();
        ExpectClose(a, *cpu, 1.0 / 255, 8.0 / 255, "int16 GPU vs CPU");
      }
    }
    auto renderer = VolumeRenderer::Create(context(), {.volume_access = VolumeAccess::kSampler3D});
    ASSERT_TRUE(renderer.ok()) << renderer.status();
    auto image = gpu16->Image(context(), int16);
    ASSERT_TRUE(image.ok()) << image.status();
    EXPECT_EQ((*image)->format(), vk::Format::eR16Unorm);
    RenderRequest r = Request(RenderMode::kMip);
    r.volume = &*gpu16;
    r.volume_image = *image;
    auto gpu = (*renderer)->Render(r);
    ASSERT_TRUE(gpu.ok()) << gpu.status();
    auto cpu = RenderReference(r, int16, nullptr, 2);
    ASSERT_TRUE(cpu.ok()) << cpu.status();
    ExpectClose(*gpu, *cpu, 2.0 / 255, 24.0 / 255, "int16 sampler3D");
  }
}

// A crop box and a plane, through a deforming map: the GPU keeps the same
// interval of each ray as the CPU reference (tolerances as above).
TEST_F(RaycastTest, CropAndClip_GpuMatchesCpuReference) {
  HostBackwardMap host;
  auto map = MakeMap(9, 3.0, &host);
  ASSERT_TRUE(map.ok()) << map.status();
  const glm::dvec3 c = 0.5 * volume_->geometry().extent_mm();
  for (RenderMode mode : {RenderMode::kDvr, RenderMode::kMip}) {
    SCOPED_TRACE(mode == RenderMode::kMip ? "mip" : "dvr");
    RenderRequest r = Request(mode);
    r.backward_map = &*map;
    r.clip.crop = CropBox{c - glm::dvec3(14.0, 30.0, 12.0), c + glm::dvec3(30.0, 30.0, 20.0)};
    r.clip.planes.push_back(ClipPlane{glm::dvec3(1.0, -1.0, 0.5), glm::dot(glm::dvec3(1.0, -1.0, 0.5), c)});
    const Frame gpu = RenderGpu(r);
    const Frame cpu = RenderCpu(r, &host);
    MaybeDump(mode == RenderMode::kMip ? "clip_mip_gpu" : "clip_dvr_gpu", gpu.rgba, gpu.width,
              gpu.height);
    EXPECT_GT(LitPixels(gpu), 300);
    ExpectClose(gpu, cpu, 1.0 / 255, 8.0 / 255, "crop and clip");
    // The cut changed the picture.
    r.clip = {};
    EXPECT_GT(CompareRgba(RenderGpu(r).rgba, gpu.rgba).mean_abs, 4.0 / 255);
  }
}

// A box round all of the volume shows what no box shows; a box in empty
// space (outside the image box) and a plane that keeps nothing show the
// background only.
TEST_F(RaycastTest, CropBox_WholeVolumeUnchangedOutsideEmpty) {
  const glm::dvec3 extent = volume_->geometry().extent_mm();
  RenderRequest r = Request(RenderMode::kMip);
  const Frame plain = RenderGpu(r);
  r.clip.crop = CropBox{glm::dvec3(-1.0), extent + 1.0};
  EXPECT_EQ(CompareRgba(RenderGpu(r).rgba, plain.rgba).max_abs, 0.0);
  r.clip.crop = CropBox{extent + 5.0, extent + 50.0};
  EXPECT_EQ(LitPixels(RenderGpu(r)), 0);
  r.clip.crop.reset();
  r.clip.planes = {ClipPlane{glm::dvec3(0.0, 0.0, 1.0), extent.z + 1.0}};
  EXPECT_EQ(LitPixels(RenderGpu(r)), 0);
}

TEST_F(RaycastTest, BadRequests_InvalidArgument) {
  auto code = [&](const RenderRequest& r) { return renderer_->Render(r).status().code(); };
  constexpr auto kInvalid = absl::StatusCode::kInvalidArgument;
  RenderRequest r = Request(RenderMode::kDvr);
  r.width = 0;
  EXPECT_EQ(code(r), kInvalid);
  r.width = 100000;
  EXPECT_EQ(code(r), kInvalid);
  r.width = 64;
  r.height = 4097;
  EXPECT_EQ(code(r), kInvalid);
  r.height = 64;
  Camera::Pose pose = r.camera.pose();
  pose.azimuth_deg = NAN;
  r.camera.set_pose(pose);
  EXPECT_EQ(code(r), kInvalid);
  pose = Camera::ForVolume(volume_->geometry()).pose();
  pose.distance_mm = 0.0;
  r.camera.set_pose(pose);
  EXPECT_EQ(code(r), kInvalid);
  r.camera = Camera::ForVolume(volume_->geometry());
  r.settings.step_mm = NAN;
  EXPECT_EQ(code(r), kInvalid);
  r.settings.step_mm = 1e-6;  // millions of samples per ray
  EXPECT_EQ(code(r), kInvalid);
  r.settings.step_mm = 0.0;
  r.mip_window = MipWindow{100.0, 0.0};
  EXPECT_EQ(code(r), kInvalid);
  r.mip_window.reset();
  r.preset.points.resize(1);
  EXPECT_EQ(code(r), kInvalid);
  r = Request(RenderMode::kDvr);
  r.volume = nullptr;
  EXPECT_EQ(code(r), kInvalid);
  r = Request(RenderMode::kDvr);
  r.clip.planes.push_back(ClipPlane{glm::dvec3(0.0), 1.0});
  EXPECT_EQ(code(r), kInvalid);
  r.clip.planes.assign(kMaxClipPlanes + 1, ClipPlane{glm::dvec3(1.0, 0.0, 0.0), 0.0});
  EXPECT_EQ(code(r), kInvalid);
  EXPECT_TRUE(renderer_->Render(Request(RenderMode::kDvr)).ok());
  EXPECT_EQ(MakeRenderPreset("no-such-preset", *volume_).status().code(), kInvalid);
}

std::filesystem::path GoldenDir() {
  const char* env = std::getenv("VPM_SOURCE_DIR");
  return std::filesystem::path(env ? env : VPM_TEST_SOURCE_DIR) / "tests/raycast/golden";
}

// The 64^3 phantom, ct-vessels DVR and MIP, anterior view, 64x64, against
// stored PNGs (tests/raycast/golden/phantom64_ct_vessels_{dvr,mip}.png). Regenerate (after an intended change to the picture) with
//   VPM_UPDATE_GOLDEN=1 build/tests/raycast/raycast_test --gtest_filter='*Golden*'
TEST_F(RaycastTest, GoldenPhantomFrame_Psnr) {
  auto phantom = MakePhantom("abdomen?size=64", {});
  ASSERT_TRUE(phantom.ok()) << phantom.status();
  auto gpu_phantom = GpuVolume::Upload(context(), *phantom);
  ASSERT_TRUE(gpu_phantom.ok()) << gpu_phantom.status();
  for (const char* mode : {"dvr", "mip"}) {
    RenderRequest r;
    r.camera = Camera::ForVolume(phantom->geometry());
    r.mode = std::string(mode) == "dvr" ? RenderMode::kDvr : RenderMode::kMip;
    r.preset = *MakeRenderPreset("ct-vessels", *phantom);
    r.width = r.height = 64;
    r.volume = &*gpu_phantom;
    const Frame frame = RenderGpu(r);
    const auto path = GoldenDir() / (std::string("phantom64_ct_vessels_") + mode + ".png");
    if (std::getenv("VPM_UPDATE_GOLDEN") != nullptr) {
      auto png = EncodePng(frame.rgba, frame.width, frame.height);
      ASSERT_TRUE(png.ok());
      std::ofstream(path, std::ios::binary)
          .write(reinterpret_cast<const char*>(png->data()), std::streamsize(png->size()));
      continue;
    }
    std::ifstream in(path, std::ios::binary);
    ASSERT_TRUE(in.good()) << "missing golden image " << path;
    const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                     std::istreambuf_iterator<char>());
    auto stored = DecodePng(bytes);
    ASSERT_TRUE(stored.ok()) << stored.status();
    ASSERT_EQ(stored->width, 64);
    ASSERT_EQ(stored->height, 64);
    const auto e = CompareRgba(frame.rgba, stored->rgba);
    std::printf("  golden %s: PSNR %.1f dB, mean %.3f/255, max %.0f/255\n", mode, e.psnr_db,
                e.mean_abs * 255, e.max_abs * 255);
    EXPECT_GT(e.psnr_db, 35.0) << mode << ": mean " << e.mean_abs * 255 << "/255";
  }
}

}  // namespace
}  // namespace vpm
