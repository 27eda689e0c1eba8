// ReadTransferFunction: a client's ParaView preset or Slicer .vp text read
// by the server's readers, and clear refusals of what is not one.
#include "tests/service/service_test_util.h"

namespace vpm::service::testing {
namespace {

// Slicer's CT-Bone, as Slicer's Volume Rendering module saves it.
constexpr char kCtBoneVp[] =
    "1\n1\n0.9\n0.1\n0.2\n10\n"
    "8 -3024 0 -16.4458 0 641.385 0.715686 3071 0.705882\n"
    "4 0 1 255 1\n"
    "16 -3024 0 0 0 -16.4458 0.729412 0.254902 0.301961 641.385 0.905882 0.815686 0.552941 "
    "3071 1 1 1\n";
constexpr char kParaview[] = R"([
  {"Name": "first", "RGBPoints": [0, 0, 0, 0, 100, 1, 1, 1]},
  {"Name": "Bones", "RGBPoints": [-1000, 0, 0, 0, 700, 1, 1, 0.9],
   "Points": [-1000, 0, 0.5, 0, 700, 0.8, 0.5, 0]}
])";

class ReadTransferFunctionTest : public ServiceTest {
 protected:
  grpc::Status Read(const std::string& file_name, const std::string& text,
                    v3::RenderTransferFunction* tf, const std::string& preset = "") {
    v3::ReadTransferFunctionRequest request;
    request.set_file_name(file_name);
    request.set_text(text);
    request.set_preset(preset);
    auto context = Context();
    return stub_->ReadTransferFunction(context.get(), request, tf);
  }
};

TEST_F(ReadTransferFunctionTest, ReadTransferFunction_ReadsSlicerAndParaviewFiles) {
  v3::RenderTransferFunction tf;
  grpc::Status status = Read("MyBone.vp", kCtBoneVp, &tf);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(tf.name(), "MyBone");
  ASSERT_EQ(tf.opacities_size(), 4);
  EXPECT_DOUBLE_EQ(tf.opacities(2).value(), 641.385);
  ASSERT_EQ(tf.colors_size(), 4);
  EXPECT_TRUE(tf.has_lighting());
  status = Read("presets.json", kParaview, &tf, "Bones");
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(tf.name(), "Bones");
  EXPECT_EQ(tf.colors_size(), 2);
  EXPECT_DOUBLE_EQ(tf.colors(1).value(), 700);
  EXPECT_FALSE(tf.has_lighting());
}

TEST_F(ReadTransferFunctionTest, ReadTransferFunction_RefusesWhatIsNotOne) {
  v3::RenderTransferFunction tf;
  struct Bad {
    std::string file_name, text, preset, says;
  };
  for (const Bad& b :
       std::vector<Bad>{{"a.png", kCtBoneVp, "", "ParaView preset file"},
                        {"a.json", "{not json", "", "not valid JSON"},
                        {"a.json", kParaview, "nope", "no preset named 'nope'"},
                        {"a.vp", "1\n1\n", "", "a.vp"},
                        {"a.vp", kCtBoneVp, "x", "a Slicer .vp holds one property"},
                        {"a.json", std::string((1 << 20) + 1, ' '), "", "at most"}}) {
    SCOPED_TRACE(b.file_name + " " + b.preset);
    grpc::Status status = Read(b.file_name, b.text, &tf, b.preset);
    EXPECT_EQ(status.error_code(), grpc::INVALID_ARGUMENT);
    EXPECT_NE(status.error_message().find(b.says), std::string::npos) << status.error_message();
  }
}

}  // namespace
}  // namespace vpm::service::testing
