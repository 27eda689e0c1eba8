// The viewer's window-free logic: the bitmap font, the controls table, the
// outbound event queue, the stream meters and the status bar text.
#include <gtest/gtest.h>

#include <array>
#include <set>
#include <thread>

#include "client/view/bitmap_font.h"
#include "client/view/key_bindings.h"
#include "client/view/outbound_events.h"
#include "client/view/status_text.h"
#include "client/view/stream_meters.h"

namespace vpm::view {
namespace {

using std::chrono::milliseconds;

TEST(BitmapFont, EveryGlyphIsSevenRowsOfFivePixels) {
  for (int c = 32; c < 127; ++c) {
    const auto rows = Glyph(static_cast<char>(c));
    ASSERT_EQ(rows.size(), size_t(kGlyphHeight)) << char(c);
    for (std::string_view row : rows) {
      ASSERT_EQ(row.size(), size_t(kGlyphWidth)) << char(c);
      for (char p : row) ASSERT_TRUE(p == '#' || p == '.') << char(c);
    }
  }
}

TEST(BitmapFont, LettersDigitsAndPunctuationAreDistinct) {
  std::set<std::string> seen;
  for (char c : std::string("ABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789.,:;-+/()[]%?!=<>_'")) {
    ASSERT_TRUE(HasGlyph(c)) << c;
    std::string bits;
    for (std::string_view row : Glyph(c)) bits += row;
    EXPECT_TRUE(seen.insert(bits).second) << c << " looks like another glyph";
  }
  EXPECT_TRUE(HasGlyph('q'));  // lower case folds to capitals
  EXPECT_EQ(Glyph('q')[6], Glyph('Q')[6]);
}

TEST(BitmapFont, TextWidthCountsAdvancesWithoutTrailingGap) {
  EXPECT_EQ(TextWidth(""), 0);
  EXPECT_EQ(TextWidth("A"), kGlyphWidth);
  EXPECT_EQ(TextWidth("AB"), kGlyphAdvance + kGlyphWidth);
}

TEST(KeyBindings, EveryActionHasAKeyAndNoKeyTwoActions) {
  std::set<Action> actions;
  std::set<std::string> keys;
  for (const KeyBinding& b : KeyBindings()) {
    EXPECT_TRUE(actions.insert(b.action).second);
    EXPECT_FALSE(b.keys.empty());
    for (std::string_view k : b.keys) {
      std::string upper(k);
      for (char& ch : upper) ch = char(std::toupper(static_cast<unsigned char>(ch)));
      EXPECT_TRUE(keys.insert(upper).second) << k << " is bound twice";
    }
  }
  EXPECT_EQ(actions.size(), size_t(Action::kQuit) + 1);
}

TEST(KeyBindings, SdlKeyNamesMapCaseInsensitively) {
  EXPECT_EQ(ActionForKey("F1"), Action::kToggleHelp);
  EXPECT_EQ(ActionForKey("h"), Action::kToggleHelp);
  EXPECT_EQ(ActionForKey("G"), Action::kToggleGrabMode);
  EXPECT_EQ(ActionForKey("Escape"), Action::kQuit);
  EXPECT_EQ(ActionForKey("Z"), std::nullopt);
}

TEST(KeyBindings, HelpTextListsEveryControlInTheFont) {
  const std::vector<std::string> lines = HelpLines();
  std::string all;
  for (const std::string& l : lines) all += l + "\n";
  for (const KeyBinding& b : KeyBindings()) {
    EXPECT_NE(all.find(std::string(b.description)), std::string::npos) << b.description;
  }
  for (const MouseBinding& m : MouseBindings()) {
    EXPECT_NE(all.find(std::string(m.description)), std::string::npos) << m.description;
  }
  for (char c : all) {
    if (c != '\n') {
      EXPECT_TRUE(HasGlyph(c)) << "no glyph for '" << c << "'";
    }
  }
}

v3::ClientEvent CameraAt(double azimuth) {
  v3::ClientEvent e;
  e.mutable_camera()->set_azimuth_deg(azimuth);
  return e;
}

TEST(OutboundEvents, NewestCameraReplacesOneWaitingAtTheTail) {
  OutboundEvents q;
  q.Push(CameraAt(1));
  q.Push(CameraAt(2));
  ASSERT_EQ(q.size(), 1u);
  EXPECT_EQ(q.Pop(milliseconds(0))->camera().azimuth_deg(), 2);
}

TEST(OutboundEvents, GrabsAndReleasesKeepTheirOrder) {
  OutboundEvents q;
  v3::ClientEvent grab, drag1, drag2, release;
  grab.mutable_grab()->set_pick(true);
  drag1.mutable_drag()->mutable_offset_mm()->set_x(1);
  drag2.mutable_drag()->mutable_offset_mm()->set_x(2);
  release.mutable_release();
  q.Push(CameraAt(1));
  q.Push(grab);
  q.Push(drag1);
  q.Push(drag2);
  q.Push(release);
  q.Push(release);
  ASSERT_EQ(q.size(), 5u);  // camera, grab, drag (newest), release, release
  EXPECT_TRUE(q.Pop(milliseconds(0))->has_camera());
  EXPECT_TRUE(q.Pop(milliseconds(0))->has_grab());
  EXPECT_EQ(q.Pop(milliseconds(0))->drag().offset_mm().x(), 2);
  EXPECT_TRUE(q.Pop(milliseconds(0))->has_release());
}

TEST(OutboundEvents, PopWaitsThenTimesOutAndCloseWakesIt) {
  OutboundEvents q;
  const auto t0 = SteadyClock::now();
  EXPECT_FALSE(q.Pop(milliseconds(30)).has_value());
  EXPECT_GE(SteadyClock::now() - t0, milliseconds(25));
  std::thread closer([&] {
    std::this_thread::sleep_for(milliseconds(20));
    q.Close();
  });
  EXPECT_FALSE(q.Pop(milliseconds(5000)).has_value());
  EXPECT_LT(SteadyClock::now() - t0, milliseconds(3000));
  closer.join();
  q.Reopen();
  q.Push(CameraAt(3));
  EXPECT_TRUE(q.Pop(milliseconds(0)).has_value());
}

TEST(LatencyMeter, MeasuresFromTheNewestEventAFrameCovers) {
  LatencyMeter m;
  const SteadyClock::time_point t0 = SteadyClock::now();
  m.Sent(1, t0);
  m.Sent(2, t0 + milliseconds(10));
  m.Sent(3, t0 + milliseconds(20));
  auto latency = m.Received(2, t0 + milliseconds(50));
  ASSERT_TRUE(latency.has_value());
  EXPECT_NEAR(*latency, 40.0, 1e-6);
  EXPECT_FALSE(m.Received(2, t0 + milliseconds(60)).has_value());  // nothing new
  EXPECT_NEAR(*m.Received(3, t0 + milliseconds(70)), 50.0, 1e-6);
}

TEST(FrameRateMeter, CountsFramesOverTheWindowAndDecaysWhenTheyStop) {
  FrameRateMeter meter(milliseconds(1000));
  const SteadyClock::time_point t0 = SteadyClock::now();
  EXPECT_EQ(meter.Fps(t0), 0.0);
  for (int i = 0; i <= 20; ++i) meter.OnFrame(t0 + milliseconds(100 * i));
  EXPECT_NEAR(meter.Fps(t0 + milliseconds(2000)), 10.0, 1e-6);
  EXPECT_EQ(meter.Fps(t0 + milliseconds(5000)), 0.0);
}

TEST(ReconnectBackoff, RetriesOnlyWhatCanSucceed) {
  EXPECT_TRUE(RetryCanSucceed(absl::UnavailableError("server down")));
  EXPECT_TRUE(RetryCanSucceed(absl::ResourceExhaustedError("too many sessions")));
  EXPECT_TRUE(RetryCanSucceed(absl::DeadlineExceededError("slow")));
  // `--volume /abs/path.nii.gz` the server may not read, a gone session, a
  // bad token: the same answer every time.
  EXPECT_FALSE(RetryCanSucceed(absl::InvalidArgumentError("absolute paths are refused")));
  EXPECT_FALSE(RetryCanSucceed(absl::NotFoundError("no such file")));
  EXPECT_FALSE(RetryCanSucceed(absl::PermissionDeniedError("outside the data root")));
  EXPECT_FALSE(RetryCanSucceed(absl::UnauthenticatedError("bad token")));
}

TEST(ReconnectBackoff, DoublesFromAQuarterSecondUpToFive) {
  EXPECT_DOUBLE_EQ(ReconnectBackoffS(0), 0.25);
  EXPECT_DOUBLE_EQ(ReconnectBackoffS(1), 0.5);
  EXPECT_DOUBLE_EQ(ReconnectBackoffS(3), 2.0);
  EXPECT_DOUBLE_EQ(ReconnectBackoffS(5), 5.0);
  EXPECT_DOUBLE_EQ(ReconnectBackoffS(1000), 5.0);
}

v3::Frame FrameOf(int side, bool interactive, double displacement_mm,
                  std::array<double, 6> stage_ms) {  // fem warp render encode queue total
  v3::Frame f;
  f.set_width(side);
  f.set_height(side * 3 / 4);
  f.set_interactive(interactive);
  f.set_max_displacement_mm(displacement_mm);
  v3::StageTimings* t = f.mutable_timings();
  t->set_fem_ms(stage_ms[0]);
  t->set_warp_ms(stage_ms[1]);
  t->set_render_ms(stage_ms[2]);
  t->set_encode_ms(stage_ms[3]);
  t->set_queue_ms(stage_ms[4]);
  t->set_total_ms(stage_ms[5]);
  return f;
}

TEST(StatusLines, ShowRateLatencySizeQualityDisplacementAndServerTimes) {
  StatusInputs in;
  in.fps = 12.34;
  in.latency_ms = 85.4;
  in.frame = FrameOf(256, true, 3.21, {10.2, 0, 0, 0, 0, 60.3});
  in.grab_mode = true;
  const auto lines = StatusLines(in);
  EXPECT_EQ(lines[0], "12.3 fps  rtt 85 ms  256x192 auto");
  EXPECT_EQ(lines[1], "interactive  disp 3.2 mm  GRAB MODE");
  EXPECT_EQ(lines[2], "server ms fem 10 warp 0 rend 0");
  EXPECT_EQ(lines[3], "enc 0 queue 0 total 60  F1/h: help");
  in.interactive_quality = v3::INTERACTIVE_QUALITY_SHARP;
  EXPECT_EQ(StatusLines(in)[0], "12.3 fps  rtt 85 ms  256x192 sharp");
  in.interactive_quality = v3::INTERACTIVE_QUALITY_BALANCED;
  EXPECT_EQ(StatusLines(in)[0], "12.3 fps  rtt 85 ms  256x192 bal");
  in.frame->set_refine_level(1);
  EXPECT_EQ(StatusLines(in)[1], "refine 1  disp 3.2 mm  GRAB MODE");
}

TEST(StatusLines, FitA256PixelWindowWithSlowStages) {
  StatusInputs in;
  in.fps = 123.4;
  in.latency_ms = 12345;
  in.frame = FrameOf(4096, true, 123.4, {1234, 123, 1234, 123, 123, 12345});
  in.grab_mode = in.grabbed = true;
  in.interactive_quality = v3::INTERACTIVE_QUALITY_SHARP;
  for (const std::string& line : StatusLines(in)) {
    EXPECT_LE(TextWidth(line), 256 - 2 * 3) << line;  // 3-pixel margins
  }
}

}  // namespace
}  // namespace vpm::view
