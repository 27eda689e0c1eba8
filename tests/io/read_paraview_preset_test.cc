// ParaView colour-map presets: entries by position and name, opacity curves
// with VTK's midpoint and sharpness, the default opacity ramp, and a clear
// error for every kind of malformed file.
#include <string>

#include <gtest/gtest.h>

#include "server/io/read_paraview_preset.h"
#include "server/io/read_render_transfer_function.h"
#include "tests/io/io_test_util.h"

namespace vpm {
namespace {

// Two presets as ParaView's colour map editor exports them: a volume
// rendering one with opacity points, and a plain colour map.
const char* kTwoPresets = R"([
  {
    "ColorSpace" : "RGB",
    "Name" : "Bone HU",
    "NanColor" : [ 1, 0, 0 ],
    "Points" : [ -1000, 0, 0.5, 0, 200, 0, 0.5, 0, 700, 0.8, 0.5, 0, 3000, 0.8, 0.5, 0 ],
    "RGBPoints" : [ -1000, 0, 0, 0, 200, 0.7, 0.3, 0.3, 700, 1, 1, 0.9, 3000, 1, 1, 1 ]
  },
  {
    "ColorSpace" : "Diverging",
    "Name" : "Cool to Warm",
    "RGBPoints" : [ 0, 0.23, 0.299, 0.754, 100, 0.706, 0.016, 0.15 ]
  }
])";

Result<RenderTransferFunction> Parse(const std::string& text, std::string_view name = "") {
  return ParseParaviewPreset(text, name, "test.json");
}

TEST(ReadParaviewPreset, TakesTheFirstEntryOrTheNamedOne) {
  auto first = Parse(kTwoPresets);
  ASSERT_TRUE(first.ok()) << first.status();
  EXPECT_EQ(first->name, "Bone HU");
  ASSERT_EQ(first->colors.size(), 4u);
  EXPECT_EQ(first->colors[1], (TfColorPoint{200.0, glm::dvec3(0.7, 0.3, 0.3)}));
  ASSERT_EQ(first->opacities.size(), 4u);  // linear segments stay 4 points
  EXPECT_EQ(first->opacities[2], (TfOpacityPoint{700.0, 0.8}));
  EXPECT_FALSE(first->lighting.has_value());

  auto named = Parse(kTwoPresets, "Cool to Warm");
  ASSERT_TRUE(named.ok()) << named.status();
  EXPECT_EQ(named->colors.back().value, 100.0);
  // No "Points": ParaView's default ramp over the colour range.
  EXPECT_EQ(named->opacities, (std::vector<TfOpacityPoint>{{0.0, 0.0}, {100.0, 1.0}}));
}

TEST(ReadParaviewPreset, FollowsVtkMidpointAndSharpness) {
  // Midpoint 0.25: the curve reaches half way a quarter along the segment.
  auto mid = Parse(R"({"Name": "m", "RGBPoints": [0, 0, 0, 0, 100, 1, 1, 1],
                       "Points": [0, 0, 0.25, 0, 100, 1, 0.5, 0]})");
  ASSERT_TRUE(mid.ok()) << mid.status();
  ASSERT_EQ(mid->opacities.size(), 17u);  // 16 sub-segments
  EXPECT_EQ(mid->opacities[4].value, 25.0);
  EXPECT_NEAR(mid->opacities[4].opacity, 0.5, 1e-12);
  for (size_t i = 1; i < mid->opacities.size(); ++i) {
    EXPECT_GE(mid->opacities[i].opacity, mid->opacities[i - 1].opacity);  // monotone
  }
  // Sharpness 1: a step at the midpoint.
  auto step = Parse(R"([{"Name": "s", "RGBPoints": [0, 0, 0, 0, 100, 1, 1, 1],
                         "Points": [0, 0.1, 0.5, 1, 100, 0.9, 0.5, 0]}])");
  ASSERT_TRUE(step.ok()) << step.status();
  EXPECT_EQ(step->opacities, (std::vector<TfOpacityPoint>{
                                 {0.0, 0.1}, {50.0, 0.1}, {50.0, 0.9}, {100.0, 0.9}}));
}

TEST(ReadParaviewPreset, RejectsMalformedFilesNamingTheProblem) {
  struct Case {
    std::string text, name, message;
  };
  const std::string rgb = R"("RGBPoints": [0, 0, 0, 0, 10, 1, 1, 1])";
  const Case cases[] = {
      {"[{\"Name\": \"x\", ", "", "not valid JSON"},
      {R"([{"Name": "x", "RGBPoints": [0, NaN, 0, 0]}])", "", "not valid JSON"},
      {"42", "", "expected a JSON array"},
      {"[]", "", "empty"},
      {"[7]", "", "preset 0 is not a JSON object"},
      {R"([{"Name": "x"}])", "", "no \"RGBPoints\""},
      {R"([{"Name": "x", "RGBPoints": [0, 0, 0]}])", "", "4 numbers per point"},
      {R"([{"Name": "x", "RGBPoints": [0, 0, 0, null]}])", "", "item 3 is not a number"},
      {R"([{"Name": "x", "RGBPoints": [10, 0, 0, 0, 0, 1, 1, 1]}])", "", "values must ascend"},
      {R"([{"Name": "x", "RGBPoints": [0, 0, 0, 1.5]}])", "", "in [0, 1]"},
      {"[{\"Name\": \"x\", " + rgb + R"(, "Points": [0, 2, 0.5, 0]}])", "", "in [0, 1]"},
      {"[{\"Name\": \"x\", " + rgb + R"(, "Points": [0, 0, 1.5, 0]}])", "", "midpoint"},
      {"[{\"Name\": \"x\", " + rgb + "}]", "y", "no preset named 'y'; the file holds 'x'"},
  };
  for (const Case& c : cases) {
    auto tf = Parse(c.text, c.name);
    ASSERT_FALSE(tf.ok()) << c.text;
    EXPECT_EQ(tf.status().code(), absl::StatusCode::kInvalidArgument) << c.text;
    EXPECT_NE(std::string(tf.status().message()).find(c.message), std::string::npos)
        << c.text << " -> " << tf.status();
    EXPECT_NE(std::string(tf.status().message()).find("test.json"), std::string::npos);
  }
}

TEST(ReadParaviewPreset, RejectsAbsurdSizes) {
  std::string points;
  for (size_t i = 0; i <= kMaxRenderTfPoints; ++i) {
    points += StrCat(i == 0 ? "" : ", ", i, ", 0.5, 0.5, 0.5");
  }
  auto tf = Parse("[{\"Name\": \"big\", \"RGBPoints\": [" + points + "]}]");
  ASSERT_FALSE(tf.ok());
  EXPECT_NE(std::string(tf.status().message()).find("at most 1024"), std::string::npos)
      << tf.status();
}

TEST(ReadRenderTransferFunction, DispatchesOnTheFileName) {
  const auto dir = testing::MakeTempDir();
  const std::string json = (dir / "presets.json").string();
  testing::WriteText(json, kTwoPresets);
  auto named = ReadRenderTransferFunction(json + "#Cool to Warm");
  ASSERT_TRUE(named.ok()) << named.status();
  EXPECT_EQ(named->name, "Cool to Warm");
  auto first = ReadRenderTransferFunction(json);
  ASSERT_TRUE(first.ok()) << first.status();
  EXPECT_EQ(first->name, "Bone HU");
  EXPECT_EQ(ReadRenderTransferFunction((dir / "missing.json").string()).status().code(),
            absl::StatusCode::kNotFound);
  for (const std::string& spec : {(dir / "a.vp.json").string(), (dir / "a.png").string(),
                                 (dir / "a.vp").string() + "#x"}) {
    EXPECT_EQ(ReadRenderTransferFunction(spec).status().code(),
              absl::StatusCode::kInvalidArgument)
        << spec;
  }
}

}  // namespace
}  // namespace vpm
