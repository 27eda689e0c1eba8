// Transfer functions from other tools as render presets: the merge of
// colour and opacity is exact and keeps steps, Slicer's presets are there by
// name and show what Slicer shows, a preset's lighting reaches the ray
// caster, and the GPU renders a custom transfer function as the CPU
// reference does (tolerances of raycast_test.cc: per channel mean < 1/255,
// max < 8/255).
#include <gtest/gtest.h>

#include "server/io/read_paraview_preset.h"
#include "server/raycast/raycast_cpu.h"
#include "server/raycast/render_preset_from_tf.h"
#include "server/raycast/slicer_presets.h"
#include "server/raycast/volume_renderer.h"
#include "tests/gpu/gpu_test_context.h"
#include "tests/raycast/render_test_util.h"

namespace vpm {
namespace {

using glm::dvec3;

// Colour on 0 and 100, opacity on 50, 150 and a step at 120.
RenderTransferFunction TwoListTf() {
  return {"two lists",
          {{0.0, dvec3(1, 0, 0)}, {100.0, dvec3(0, 0, 1)}},
          {{50.0, 0.0}, {120.0, 0.2}, {120.0, 0.6}, {150.0, 0.8}},
          std::nullopt};
}

TEST(RenderPresetFromTf, MergesColourAndOpacityExactly) {
  const Volume volume = testing::MakeSphereRodVolume(16);
  auto preset = RenderPresetFromTf(TwoListTf(), volume);
  ASSERT_TRUE(preset.ok()) << preset.status();
  ASSERT_TRUE(ValidateRenderPreset(*preset).ok());
  EXPECT_EQ(preset->name, "two lists");
  // Union 0, 50, 100, 120 (twice: the step), 150.
  ASSERT_EQ(preset->points.size(), 6u);
  EXPECT_EQ(preset->points[1].value, 50.0);
  EXPECT_EQ(preset->points[1].rgba, glm::dvec4(0.5, 0, 0.5, 0.0));  // colour halfway
  EXPECT_NEAR(preset->points[2].rgba.a, 0.2 * 50.0 / 70.0, 1e-12);  // opacity 5/7 up its ramp
  EXPECT_EQ(preset->points[3].rgba, glm::dvec4(0, 0, 1, 0.2));  // colour clamped past 100
  EXPECT_EQ(preset->points[4].rgba, glm::dvec4(0, 0, 1, 0.6));  // the step's right side
  EXPECT_EQ(preset->points[0].rgba.a, 0.0);                     // opacity clamped below 50
  // Step 1 mm: the table's opacity is the per-mm opacity itself.
  const RenderLut lut = BakeRenderLut(*preset, 1.0);
  EXPECT_NEAR(SampleRenderLut(lut, 75.0f).a, 0.2 * 25.0 / 70.0, 2e-3);
  EXPECT_NEAR(SampleRenderLut(lut, 75.0f).b, 0.75, 2e-3);
  EXPECT_LT(SampleRenderLut(lut, 119.0f).a, 0.21f);
  EXPECT_GT(SampleRenderLut(lut, 121.0f).a, 0.59f);
  // Step 0.5 mm: 1 - (1 - a)^0.5.
  EXPECT_NEAR(SampleRenderLut(BakeRenderLut(*preset, 0.5), 150.0f).a, 1.0 - std::sqrt(0.2), 1e-3);
}

TEST(RenderPresetFromTf, RejectsInvalidFunctions) {
  const Volume volume = testing::MakeSphereRodVolume(16);
  RenderTransferFunction bad = TwoListTf();
  bad.opacities[1].opacity = std::nan("");
  EXPECT_EQ(RenderPresetFromTf(bad, volume).status().code(), absl::StatusCode::kInvalidArgument);
  bad = TwoListTf();
  bad.colors.clear();
  EXPECT_EQ(RenderPresetFromTf(bad, volume).status().code(), absl::StatusCode::kInvalidArgument);
}

TEST(SlicerPresets, EveryNameMakesAValidPresetWithSlicersLighting) {
  const Volume volume = testing::MakeSphereRodVolume(16);
  ASSERT_EQ(SlicerPresetNames().size(), 6u);
  for (const auto& [name, description] : SlicerPresetNames()) {
    auto preset = MakeRenderPreset(name, volume);
    ASSERT_TRUE(preset.ok()) << name << ": " << preset.status();
    EXPECT_EQ(preset->name, name);
    ASSERT_TRUE(preset->lighting.has_value()) << name;
    EXPECT_EQ(preset->lighting, SlicerPreset(name)->lighting);
  }
  // Names are Slicer's, case and all: CT-Bone is not vpm's ct-bone.
  EXPECT_NE(MakeRenderPreset("CT-Bone", volume)->points,
            MakeRenderPreset("ct-bone", volume)->points);
  EXPECT_FALSE(MakeRenderPreset("ct-aaa", volume).ok());
}

TEST(SlicerPresets, ShowWhatSlicerShows) {
  const Volume volume = testing::MakeSphereRodVolume(16);
  const RenderLut bone = BakeRenderLut(*MakeRenderPreset("CT-Bone", volume), 1.0);
  const glm::vec4 cortex = SampleRenderLut(bone, 1500.0f);
  EXPECT_GT(cortex.r, 0.9f);  // bone ivory to white
  EXPECT_GT(std::min({cortex.g, cortex.b}), 0.7f);
  EXPECT_GT(cortex.a, 0.7f);
  const glm::vec4 muscle = SampleRenderLut(bone, 40.0f);
  EXPECT_GT(muscle.r, 1.5f * muscle.g);  // soft tissue red, translucent
  EXPECT_LT(muscle.a, 0.1f);
  EXPECT_EQ(SampleRenderLut(bone, -100.0f).a, 0.0f);
  const RenderLut soft = BakeRenderLut(*MakeRenderPreset("CT-Soft-Tissue", volume), 1.0);
  EXPECT_EQ(SampleRenderLut(soft, -500.0f).a, 0.0f);  // air and lung clear
  EXPECT_GT(SampleRenderLut(soft, 0.0f).a, 0.99f);    // skin an opaque surface
  EXPECT_FALSE(MakeRenderPreset("CT-Soft-Tissue", volume)->lighting->shade);
}

TEST(SlicerPresets, LightingReachesTheRayCaster) {
  const Volume volume = testing::MakeSphereRodVolume(16);
  RenderRequest r;
  r.camera = Camera::ForVolume(volume.geometry());
  r.preset = *MakeRenderPreset("CT-Soft-Tissue", volume);  // unshaded, ambient 0.2, diffuse 1
  auto setup = PrepareRaycast(r, volume.geometry(), {0, 0, 0});
  ASSERT_TRUE(setup.ok()) << setup.status();
  EXPECT_EQ(setup->params.image.z & gpu::kRaycastShading, 0);
  EXPECT_EQ(setup->params.shading, glm::vec4(0.2f, 1.0f, 0.0f, 1.0f));
  r.preset = *MakeRenderPreset("ct-soft-tissue", volume);  // RaycastSettings' lighting
  setup = PrepareRaycast(r, volume.geometry(), {0, 0, 0});
  ASSERT_TRUE(setup.ok()) << setup.status();
  EXPECT_NE(setup->params.image.z & gpu::kRaycastShading, 0);
  EXPECT_EQ(setup->params.shading.x, float(r.settings.ambient));
}

class CustomTfRaycastTest : public testing::GpuTest {};

// A ParaView preset with a non-linear opacity segment and a colour step,
// rendered by the GPU and by the CPU reference, with and without shading.
TEST_F(CustomTfRaycastTest, GpuMatchesCpuReference) {
  const Volume volume = testing::MakeSphereRodVolume();
  auto tf = ParseParaviewPreset(R"([{"Name": "custom", "ColorSpace": "RGB",
      "RGBPoints": [-200, 0.2, 0.8, 0.3, 100, 0.9, 0.2, 0.2, 100, 0.2, 0.3, 1.0, 900, 1, 1, 1],
      "Points": [-200, 0, 0.5, 0, 20, 0.05, 0.3, 0.4, 150, 0.5, 0.5, 0, 900, 0.9, 0.5, 0]}])",
                                "", "custom.json");
  ASSERT_TRUE(tf.ok()) << tf.status();
  auto preset = RenderPresetFromTf(*tf, volume);
  ASSERT_TRUE(preset.ok()) << preset.status();
  auto gpu_volume = GpuVolume::Upload(context(), volume);
  ASSERT_TRUE(gpu_volume.ok()) << gpu_volume.status();
  auto renderer = VolumeRenderer::Create(context(), {});
  ASSERT_TRUE(renderer.ok()) << renderer.status();
  for (bool shading : {true, false}) {
    SCOPED_TRACE(shading ? "shaded" : "unshaded");
    RenderRequest r;
    r.camera = Camera::ForVolume(volume.geometry());
    r.camera.Orbit(30.0, 20.0);
    r.preset = *preset;
    r.width = r.height = 96;
    r.volume = &*gpu_volume;
    r.settings.shading = shading;
    auto gpu = (*renderer)->Render(r);
    ASSERT_TRUE(gpu.ok()) << gpu.status();
    auto cpu = RenderReference(r, volume, nullptr, 2);
    ASSERT_TRUE(cpu.ok()) << cpu.status();
    testing::MaybeDump(shading ? "custom_tf_gpu" : "custom_tf_gpu_flat", gpu->rgba, 96, 96);
    int64_t lit = 0;
    for (size_t i = 0; i < gpu->rgba.size(); i += 4) lit += gpu->rgba[i + 1] > 60;
    EXPECT_GT(lit, 300);  // not a blank frame
    const auto e = testing::CompareRgba(gpu->rgba, cpu->rgba);
    EXPECT_LT(e.mean_abs, 1.0 / 255);
    EXPECT_LT(e.max_abs, 8.0 / 255);
  }
}

}  // namespace
}  // namespace vpm
