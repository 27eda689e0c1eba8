// 3D Slicer volume property files: the nine lines Slicer writes, read back
// into colour and opacity points and lighting, and a clear error for each
// kind of malformed file.
#include <string>

#include <gtest/gtest.h>

#include "server/io/read_render_transfer_function.h"
#include "server/io/read_slicer_volume_property.h"
#include "tests/io/io_test_util.h"

namespace vpm {
namespace {

// Slicer's CT-Bone preset saved from Slicer's Volume Rendering module.
const char* kCtBoneVp =
    "1\n1\n0.9\n0.1\n0.2\n10\n"
    "8 -3024 0 -16.4458 0 641.385 0.715686 3071 0.705882\n"
    "4 0 1 255 1\n"
    "16 -3024 0 0 0 -16.4458 0.729412 0.254902 0.301961 641.385 0.905882 0.815686 0.552941 "
    "3071 1 1 1\n";

TEST(ReadSlicerVolumeProperty, ReadsWhatSlicerWrites) {
  const auto dir = testing::MakeTempDir();
  const std::string path = (dir / "MyBone.vp").string();
  testing::WriteText(path, kCtBoneVp);
  auto tf = ReadRenderTransferFunction(path);
  ASSERT_TRUE(tf.ok()) << tf.status();
  EXPECT_EQ(tf->name, "MyBone");
  ASSERT_EQ(tf->opacities.size(), 4u);
  EXPECT_EQ(tf->opacities[2], (TfOpacityPoint{641.385, 0.715686}));
  ASSERT_EQ(tf->colors.size(), 4u);
  EXPECT_EQ(tf->colors[1], (TfColorPoint{-16.4458, glm::dvec3(0.729412, 0.254902, 0.301961)}));
  ASSERT_TRUE(tf->lighting.has_value());
  // Line 3 is the diffuse coefficient, line 4 the ambient one (Slicer's order).
  EXPECT_EQ(*tf->lighting, (TfLighting{true, 0.1, 0.9, 0.2, 10.0}));
  // Windows line ends read the same.
  std::string crlf;
  for (char c : std::string(kCtBoneVp)) crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
  auto again = ParseSlicerVolumeProperty(crlf, "MyBone", "crlf.vp");
  ASSERT_TRUE(again.ok()) << again.status();
  EXPECT_EQ(*again, *tf);
}

TEST(ReadSlicerVolumeProperty, RejectsMalformedFilesNamingTheLine) {
  const std::string head = "1\n1\n0.9\n0.1\n0.2\n10\n";
  const std::string grad = "4 0 1 255 1\n";
  const std::string color = "8 0 0 0 0 100 1 1 1\n";
  struct Case {
    std::string text, message;
  };
  const Case cases[] = {
      {head + "4 0 0 100 1\n" + grad, "8 lines"},
      {"1\nyes\n0.9\n0.1\n0.2\n10\n4 0 0 100 1\n" + grad + color, "line 2 (shade)"},
      {head + "4 0 0 100\n" + grad + color, "line 7 (scalar opacity): count says 4"},
      {head + "3 0 0 100\n" + grad + color, "multiple of 2"},
      {head + "4 0 0 100 nan\n" + grad + color, "'nan' is not a finite number"},
      {head + "4 0 0 100 1x\n" + grad + color, "'1x'"},
      {head + "4 100 0 0 1\n" + grad + color, "values must ascend"},
      {head + "4 0 0 100 1.5\n" + grad + color, "in [0, 1]"},
      {head + "4 0 0 100 1\n" + "\n" + color, "line 8 (gradient opacity): empty"},
      {head + "4 0 0 100 1\n" + grad + "8 0 0 0 0 100 1 2 1\n", "colour point 1"},
      {head + "2000000 0 0\n" + grad + color, "at most 1024"},
  };
  for (const Case& c : cases) {
    auto tf = ParseSlicerVolumeProperty(c.text, "t", "t.vp");
    ASSERT_FALSE(tf.ok()) << c.text;
    EXPECT_EQ(tf.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(std::string(tf.status().message()).find(c.message), std::string::npos)
        << c.message << " -> " << tf.status();
  }
}

}  // namespace
}  // namespace vpm
