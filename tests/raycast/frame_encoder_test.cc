// JPEG and PNG encoding: PNG round-trips exactly, JPEG at quality 90 stays
// above 30 dB PSNR; bad inputs are refused.
#include <cmath>

#include <gtest/gtest.h>

#include "server/raycast/frame_encoder.h"
#include "tests/raycast/render_test_util.h"

namespace vpm {
namespace {

// A smooth gradient with a disc and a hard edge: what rendered frames hold.
std::vector<uint8_t> TestImage(int w, int h) {
  std::vector<uint8_t> rgba(size_t(w) * h * 4);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      uint8_t* p = &rgba[(size_t(y) * w + x) * 4];
      const double d = std::hypot(x - 0.4 * w, y - 0.5 * h);
      p[0] = uint8_t(255.0 * x / (w - 1));
      p[1] = uint8_t(d < 0.25 * h ? 220 : 40);
      p[2] = uint8_t(128 + 100 * std::sin(0.05 * (x + 2 * y)));
      p[3] = 255;
    }
  return rgba;
}

TEST(FrameEncoder, PngRoundTripIsExact) {
  const auto image = TestImage(97, 61);
  auto png = EncodePng(image, 97, 61);
  ASSERT_TRUE(png.ok()) << png.status();
  EXPECT_EQ((*png)[1], 'P');
  auto back = DecodePng(*png);
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_EQ(back->width, 97);
  EXPECT_EQ(back->height, 61);
  EXPECT_EQ(back->rgba, image);
}

TEST(FrameEncoder, JpegRoundTripAbove30DbAtQuality90) {
  const auto image = TestImage(128, 96);
  auto jpeg = EncodeJpeg(image, 128, 96, 90);
  ASSERT_TRUE(jpeg.ok()) << jpeg.status();
  EXPECT_EQ((*jpeg)[0], 0xFF);
  EXPECT_EQ((*jpeg)[1], 0xD8);
  EXPECT_LT(jpeg->size(), image.size() / 4);
  auto back = DecodeJpeg(*jpeg);
  ASSERT_TRUE(back.ok()) << back.status();
  ASSERT_EQ(back->width, 128);
  ASSERT_EQ(back->height, 96);
  EXPECT_GT(testing::CompareRgba(back->rgba, image).psnr_db, 30.0);
  auto small = EncodeJpeg(image, 128, 96, 20);
  ASSERT_TRUE(small.ok());
  EXPECT_LT(small->size(), jpeg->size());
}

TEST(FrameEncoder, RejectsBadInput) {
  const auto image = TestImage(16, 16);
  constexpr auto kInvalid = absl::StatusCode::kInvalidArgument;
  EXPECT_EQ(EncodeJpeg(image, 16, 15, 90).status().code(), kInvalid);
  EXPECT_EQ(EncodeJpeg(image, 16, 16, 0).status().code(), kInvalid);
  EXPECT_EQ(EncodeJpeg(image, 16, 16, 101).status().code(), kInvalid);
  EXPECT_EQ(EncodePng(image, 0, 16).status().code(), kInvalid);
  const std::vector<uint8_t> junk = {1, 2, 3, 4, 5};
  EXPECT_EQ(DecodeJpeg(junk).status().code(), kInvalid);
  EXPECT_EQ(DecodePng(junk).status().code(), kInvalid);
}

}  // namespace
}  // namespace vpm
