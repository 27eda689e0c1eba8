// Presets: every named preset is valid, the CT presets show what they
// promise, the baked table matches the control points and its step
// correction, the non-zero prefix agrees with the table, and the still step
// follows the preset and the mode.
#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include "server/gpu/shader_interface.h"
#include "server/raycast/render_presets.h"
#include "server/raycast/render_request.h"
#include "server/volume/ct_in_hu.h"
#include "tests/raycast/render_test_util.h"

namespace vpm {
namespace {

TEST(RenderPresets, EveryNamedPresetIsValid) {
  const Volume volume = testing::MakeSphereRodVolume(16);
  for (const auto& [name, description] : RenderPresetNames()) {
    auto preset = MakeRenderPreset(name, volume);
    ASSERT_TRUE(preset.ok()) << name << ": " << preset.status();
    EXPECT_TRUE(ValidateRenderPreset(*preset).ok()) << name;
    EXPECT_EQ(preset->name, name == kAutoRenderPreset ? DefaultRenderPresetName(volume) : name);
    EXPECT_FALSE(description.empty());
  }
}

// "auto" and no name: ct-soft-tissue on CT in HU, mri-t1 on any other
// volume (the same volume shifted above 0, as an MRI's intensities).
TEST(RenderPresets, AutoIsTheSoftTissueOneOnCtAndMriT1Else) {
  const Volume ct = testing::MakeSphereRodVolume(16);
  ASSERT_TRUE(IsCtInHu(ct));
  std::vector<float> shifted(static_cast<size_t>(ct.voxels().size()));
  for (size_t n = 0; n < shifted.size(); ++n) {
    shifted[n] = ct.voxels()[static_cast<int64_t>(n)] - ct.min_value();
  }
  const Volume mri = *Volume::Create(ct.geometry(), std::move(shifted));
  ASSERT_FALSE(IsCtInHu(mri));
  for (const char* name : {"auto", ""}) {
    EXPECT_EQ(MakeRenderPreset(name, ct)->name, "ct-soft-tissue") << name;
    EXPECT_EQ(MakeRenderPreset(name, mri)->name, "mri-t1") << name;
    EXPECT_EQ(*MakeRenderPreset(name, mri), *MakeRenderPreset("mri-t1", mri)) << name;
  }
}

TEST(RenderPresets, CtPresetsShowWhatTheyPromise) {
  const Volume volume = testing::MakeSphereRodVolume(16);
  const RenderLut vessels = BakeRenderLut(*MakeRenderPreset("ct-vessels", volume), 1.0);
  const glm::vec4 contrast = SampleRenderLut(vessels, 200.0f);
  EXPECT_GT(contrast.r, 0.8f);  // red
  EXPECT_LT(contrast.g, 0.3f);
  EXPECT_GT(contrast.a, 0.3f);
  EXPECT_GT(SampleRenderLut(vessels, 160.0f).a, 0.2f);   // kidney cortex shows
  EXPECT_EQ(SampleRenderLut(vessels, 50.0f).a, 0.0f);    // soft tissue hidden
  const RenderLut bone = BakeRenderLut(*MakeRenderPreset("ct-bone", volume), 1.0);
  EXPECT_EQ(SampleRenderLut(bone, 210.0f).a, 0.0f);      // the aorta stays out
  EXPECT_GT(SampleRenderLut(bone, 700.0f).a, 0.9f);
  const RenderLut soft = BakeRenderLut(*MakeRenderPreset("ct-soft-tissue", volume), 1.0);
  EXPECT_EQ(SampleRenderLut(soft, -1000.0f).a, 0.0f);    // air
  EXPECT_GT(SampleRenderLut(soft, 40.0f).a, 4.0f * SampleRenderLut(soft, -100.0f).a);
  // Fat, kidney parenchyma (30 HU), blood and muscle (55 HU) and contrast
  // (200 HU) in colours apart by at least 0.2 in some channel.
  const float values[] = {-100.0f, 30.0f, 55.0f, 200.0f};
  for (int i = 0; i < 4; ++i) {
    for (int j = i + 1; j < 4; ++j) {
      const glm::vec4 a = SampleRenderLut(soft, values[i]), b = SampleRenderLut(soft, values[j]);
      const glm::vec3 d = glm::abs(glm::vec3(a) - glm::vec3(b));
      EXPECT_GT(std::max({d.r, d.g, d.b}), 0.2f) << values[i] << " HU against " << values[j];
    }
  }
}

TEST(RenderPresets, BakeAppliesTheStepCorrectionAndPrefixCounts) {
  RenderPreset preset{"test",
                      {{0.0, glm::dvec4(1, 0, 0, 0.0)},
                       {100.0, glm::dvec4(1, 0, 0, 0.5)},
                       {200.0, glm::dvec4(0, 1, 0, 0.5)}},
                      {100.0, 200.0}};
  ASSERT_TRUE(ValidateRenderPreset(preset).ok());
  for (double step : {0.25, 1.0, 3.0}) {
    const RenderLut lut = BakeRenderLut(preset, step);
    ASSERT_EQ(lut.entries.size(), size_t(gpu::kRenderLutEntries));
    EXPECT_NEAR(SampleRenderLut(lut, 150.0f).a, 1.0 - std::pow(0.5, step), 1e-3);
    EXPECT_NEAR(SampleRenderLut(lut, 150.0f).g, 0.5, 2e-3);
    EXPECT_EQ(SampleRenderLut(lut, -50.0f).a, 0.0f);  // clamped to the first entry
    for (size_t i = 0; i < lut.entries.size(); ++i) {
      EXPECT_EQ(lut.nonzero_prefix[i + 1] - lut.nonzero_prefix[i],
                lut.entries[i].a > 0.0f ? 1 : 0);
    }
  }
  const RenderLut lut = BakeRenderLut(preset, 1.0);
  const auto [lo, hi] = LutEntryRange(lut, -20.0f, 0.0f);
  EXPECT_EQ(lut.nonzero_prefix[hi + 1] - lut.nonzero_prefix[lo], 1);  // entry 1 is > 0
  const auto [lo2, hi2] = LutEntryRange(lut, 150.0f, 160.0f);
  EXPECT_LE(lo2, hi2);
  EXPECT_GT(lut.nonzero_prefix[hi2 + 1] - lut.nonzero_prefix[lo2], 0);
}

TEST(RenderPresets, RejectsBadPresets) {
  RenderPreset p{"bad", {{0.0, glm::dvec4(0, 0, 0, 0)}, {1.0, glm::dvec4(0, 0, 0, 1)}}, {0, 1}};
  ASSERT_TRUE(ValidateRenderPreset(p).ok());
  auto bad = p;
  bad.points[1].rgba.a = 1.5;
  EXPECT_FALSE(ValidateRenderPreset(bad).ok());
  bad = p;
  bad.points[0].value = 2.0;  // unsorted
  EXPECT_FALSE(ValidateRenderPreset(bad).ok());
  bad = p;
  bad.points[0].value = NAN;
  EXPECT_FALSE(ValidateRenderPreset(bad).ok());
  bad = p;
  bad.mip_window.width = -1.0;
  EXPECT_FALSE(ValidateRenderPreset(bad).ok());
  bad = p;
  bad.shading_gradient = 0.0;
  EXPECT_FALSE(ValidateRenderPreset(bad).ok());
  for (double factor : {0.0, -0.5, 4.5, double(NAN)}) {
    bad = p;
    bad.still_step_factor = factor;
    EXPECT_FALSE(ValidateRenderPreset(bad).ok()) << factor;
  }
}

// Still DVR steps by the preset's factor (ct-soft-tissue 1.0, the others
// 0.5) of the smallest spacing, still MIP by 1.0, but no coarser than
// kStillMaxStepMm (DVR) and kStillMipMaxStepMm (MIP); interactive frames by
// 1.0; an explicit step wins.
TEST(RenderPresets, StillStepFollowsPresetAndMode) {
  const Volume volume = testing::MakeSphereRodVolume(16);  // smallest spacing 1.0 mm
  VolumeGeometry fine = volume.geometry();
  fine.spacing_mm *= 0.25;  // smallest spacing 0.25 mm
  RenderRequest r;
  r.preset = *MakeRenderPreset("ct-vessels", volume);
  EXPECT_DOUBLE_EQ(RequestStepMm(r, fine), 0.125);
  EXPECT_DOUBLE_EQ(RequestStepMm(r, volume.geometry()), kStillMaxStepMm);
  r.preset = *MakeRenderPreset("ct-bone", volume);
  EXPECT_DOUBLE_EQ(RequestStepMm(r, fine), 0.125);
  r.preset = *MakeRenderPreset("ct-soft-tissue", volume);
  EXPECT_DOUBLE_EQ(RequestStepMm(r, fine), 0.25);
  EXPECT_DOUBLE_EQ(RequestStepMm(r, volume.geometry()), kStillMaxStepMm);
  r.mode = RenderMode::kMip;
  r.preset = *MakeRenderPreset("ct-vessels", volume);
  EXPECT_DOUBLE_EQ(RequestStepMm(r, fine), 0.25);
  EXPECT_DOUBLE_EQ(RequestStepMm(r, volume.geometry()), kStillMipMaxStepMm);
  r.mode = RenderMode::kDvr;
  r.quality = RenderQuality::kInteractive;
  EXPECT_DOUBLE_EQ(RequestStepMm(r, volume.geometry()), 1.0);
  r.settings.step_mm = 0.25;
  EXPECT_DOUBLE_EQ(RequestStepMm(r, volume.geometry()), 0.25);
}

}  // namespace
}  // namespace vpm
