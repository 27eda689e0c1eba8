// The default MIP window: the 1st to 99.5th percentile of the voxels above
// air for CT, of all voxels otherwise, checked against a full sort, on the
// phantom and on a synthetic MRI-like volume; every preset takes it.
#include <algorithm>

#include <gtest/gtest.h>

#include "server/phantom/phantom.h"
#include "server/raycast/volume_mip_window.h"
#include "tests/raycast/render_test_util.h"

namespace vpm {
namespace {

// The p-th percentile of `values` by a full sort (linear between ranks).
double SortedPercentile(std::vector<float> values, double p) {
  std::sort(values.begin(), values.end());
  const double pos = p / 100.0 * double(values.size() - 1);
  const size_t lo = size_t(pos);
  const size_t hi = std::min(lo + 1, values.size() - 1);
  return values[lo] + (pos - double(lo)) * (values[hi] - values[lo]);
}

TEST(VolumeMipWindow, PhantomSpansBodyTissueAboveAir) {
  auto phantom = MakePhantom("abdomen?size=64", {});
  ASSERT_TRUE(phantom.ok()) << phantom.status();
  ASSERT_TRUE(IsCtInHu(*phantom));
  std::vector<float> body;
  for (float v : phantom->voxels().floats()) {
    if (v > kCtAirCeilingHu) body.push_back(v);
  }
  const double black = SortedPercentile(body, 1.0);
  const double white = SortedPercentile(body, 99.5);
  const MipWindow w = VolumeMipWindow(*phantom);  // 64^3 < 2^20: every voxel counted
  EXPECT_NEAR(w.level - 0.5 * w.width, black, 1e-3);
  EXPECT_NEAR(w.level + 0.5 * w.width, white, 1e-3);
  // Black between lung and soft tissue (fat and below), white in bone.
  EXPECT_GT(black, -500.0);
  EXPECT_LT(black, 0.0);
  EXPECT_GT(white, 250.0);
  // Every preset starts from it.
  for (const char* name : {"ct-vessels", "CT-Bone", "mri-t1"}) {
    EXPECT_EQ(MakeRenderPreset(name, *phantom)->mip_window, w) << name;
  }
}

TEST(VolumeMipWindow, NonCtTakesAllVoxelsAndFlatVolumesStayValid) {
  VolumeGeometry g;
  g.dims = {10, 10, 10};
  std::vector<float> ramp(1000);
  for (size_t n = 0; n < ramp.size(); ++n) ramp[n] = float(n);  // MRI-like 0..999
  const Volume mri = *Volume::Create(g, ramp);
  EXPECT_FALSE(IsCtInHu(mri));
  const MipWindow w = VolumeMipWindow(mri);
  EXPECT_NEAR(w.level - 0.5 * w.width, SortedPercentile(ramp, 1.0), 1e-3);
  EXPECT_NEAR(w.level + 0.5 * w.width, SortedPercentile(ramp, 99.5), 1e-3);
  const Volume flat = *Volume::Create(g, std::vector<float>(1000, -1000.0f));  // all air
  const MipWindow f = VolumeMipWindow(flat);
  EXPECT_GT(f.width, 0.0);
  EXPECT_NEAR(f.level, -1000.0, 1e-2);
}

}  // namespace
}  // namespace vpm
