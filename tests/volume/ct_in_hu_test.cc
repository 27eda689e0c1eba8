// Which volumes vpm's HU rules apply to (server/volume/ct_in_hu.h), and the
// transfer cost "auto" that follows from it.
#include <memory>

#include <gtest/gtest.h>

#include "server/volume/ct_in_hu.h"
#include "server/volume/dicom_origin.h"
#include "server/volume/transfer_function.h"

namespace vpm {
namespace {

// 4 x 3 x 2 voxels from lo to hi.
Volume ValueRamp(float lo, float hi) {
  VolumeGeometry g;
  g.dims = {4, 3, 2};
  std::vector<float> values(g.voxel_count());
  for (size_t i = 0; i < values.size(); ++i) {
    values[i] = lo + (hi - lo) * static_cast<float>(i) / static_cast<float>(values.size() - 1);
  }
  return *Volume::Create(g, values);
}

Volume WithModality(Volume volume, const std::string& modality) {
  auto origin = std::make_shared<DicomOrigin>();
  origin->attributes.push_back({kDicomModalityTag, modality});
  volume.set_dicom_origin(origin);
  return volume;
}

TEST(CtInHu, AirMakesCtUnlessTheDicomModalitySaysOtherwise) {
  // Without a modality: air (below -500) makes it CT in HU.
  EXPECT_TRUE(IsCtInHu(ValueRamp(-1000.0f, 1500.0f)));
  EXPECT_TRUE(IsCtInHu(ValueRamp(-3024.0f, 60.0f)));   // a scanner's padding
  EXPECT_FALSE(IsCtInHu(ValueRamp(0.0f, 2500.0f)));    // magnitude MRI
  EXPECT_FALSE(IsCtInHu(ValueRamp(-400.0f, 400.0f)));  // no air
  // A DICOM series: its Modality decides.
  EXPECT_FALSE(IsCtInHu(WithModality(ValueRamp(-1000.0f, 800.0f), "MR")));
  EXPECT_TRUE(IsCtInHu(WithModality(ValueRamp(-100.0f, 800.0f), "CT")));  // cropped inside the body
  EXPECT_FALSE(IsCtInHu(WithModality(ValueRamp(-1000.0f, 800.0f), "PT")));
  // A DICOM origin without the attribute falls back on the values.
  EXPECT_TRUE(IsCtInHu(WithModality(ValueRamp(-1000.0f, 800.0f), "")));
}

TEST(CtInHu, AutoTransferCostIsTheCtOneOnCtAndPercentilesElse) {
  const Volume ct = ValueRamp(-1000.0f, 1500.0f);
  const Volume mri = ValueRamp(0.0f, 2500.0f);
  auto on_ct = TransferFunction::FromSpec("auto", ct);
  auto on_mri = TransferFunction::FromSpec("auto", mri);
  auto mri_t1 = TransferFunction::FromSpec("mri-t1", mri);
  ASSERT_TRUE(on_ct.ok() && on_mri.ok() && mri_t1.ok());
  EXPECT_EQ(on_ct->ToString(), TransferFunction::CtSoftTissue().ToString());
  EXPECT_EQ(on_mri->ToString(), mri_t1->ToString());
  EXPECT_NE(on_mri->ToString(), TransferFunction::CtSoftTissue().ToString());
}

}  // namespace
}  // namespace vpm
