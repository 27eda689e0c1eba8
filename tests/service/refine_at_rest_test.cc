// Refinement at rest (frame_stream.h, refine_ladder.h): after a drag, once
// the pointer rests, an Interact stream sends the ladder's rungs (interactive,
// refine_level 1, 2, ...), each closer to the still, then the still, byte for
// byte the still that Render returns; a move during the refinement gets an
// interactive frame next and the rest of the ladder is dropped; no rung
// comes before a still predicted quick.
#include <chrono>
#include <thread>
#include <vector>

#include "server/raycast/frame_encoder.h"
#include "server/raycast/refine_ladder.h"
#include "tests/raycast/render_test_util.h"
#include "tests/service/service_test_util.h"

namespace vpm::service::testing {
namespace {

class RefineAtRestTest : public PhantomSessionTest {
 protected:
  // Lossless frames of `side` pixels, fast interactive frames (half the rays).
  static v3::RenderSettings Lossless(int side) {
    v3::RenderSettings s;
    s.set_width(side);
    s.set_height(side);
    s.set_encoding(v3::ENCODING_PNG);
    s.set_interactive_quality(v3::INTERACTIVE_QUALITY_FAST);
    return s;
  }
  static v3::InteractRequest Drag(double dx, uint64_t sequence) {
    v3::InteractRequest r;
    r.mutable_event()->set_sequence(sequence);
    *r.mutable_event()->mutable_drag()->mutable_offset_mm() = V(dx, 0, 0);
    return r;
  }
  using Stream = grpc::ClientReaderWriter<v3::InteractRequest, v3::Frame>;
  // Opens the stream with `settings` (event 1) and reads up to its still.
  void Open(Stream& stream, const v3::RenderSettings& settings) {
    v3::InteractRequest first;
    first.set_session_id(session_.session_id());
    first.mutable_event()->set_sequence(1);
    *first.mutable_event()->mutable_settings() = settings;
    ASSERT_TRUE(stream.Write(first));
    ASSERT_FALSE(ReadUntilStill(stream, 1).empty());
  }
  // Grabs the centre (event 2) and drags it 6 mm in kDrags steps (events 3
  // to kLastDrag) 25 ms apart, as a pointer would: the frames meanwhile are
  // interactive.
  static constexpr int kDrags = 6;
  static constexpr uint64_t kLastDrag = 2 + kDrags;
  void GrabAndDrag(Stream& stream) {
    v3::InteractRequest grab;
    grab.mutable_event()->set_sequence(2);
    *grab.mutable_event()->mutable_grab()->mutable_point_mm() = Centre(volume_);
    ASSERT_TRUE(stream.Write(grab));
    for (int i = 1; i <= kDrags; ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(25));
      ASSERT_TRUE(stream.Write(Drag(1.0 * i, 2 + i)));
    }
  }
  // Opens the stream, grabs and drags (GrabAndDrag) and returns the frames
  // up to the still of the last drag.
  std::vector<v3::Frame> OpenDragAndRest(Stream& stream, const v3::RenderSettings& settings) {
    Open(stream, settings);
    std::jthread pointer([&] { GrabAndDrag(stream); });
    std::vector<v3::Frame> frames = ReadUntilStill(stream, kLastDrag);
    pointer.join();
    return frames;
  }
  // Frames until the still that reflects event `sequence` (inclusive).
  static std::vector<v3::Frame> ReadUntilStill(
      Stream& stream, uint64_t sequence) {
    std::vector<v3::Frame> frames;
    v3::Frame frame;
    while (stream.Read(&frame)) {
      frames.push_back(frame);
      if (frame.last_sequence() == sequence && !frame.interactive()) break;
    }
    return frames;
  }
  // The still Render returns now, with `settings`.
  v3::Frame DirectStill(const v3::RenderSettings& settings) {
    v3::RenderRequest request;
    request.set_session_id(session_.session_id());
    *request.mutable_settings() = settings;
    v3::Frame frame;
    auto context = Context();
    grpc::Status status = stub_->Render(context.get(), request, &frame);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return frame;
  }
  static std::vector<uint8_t> Pixels(const v3::Frame& frame) {
    auto decoded = DecodePng({reinterpret_cast<const uint8_t*>(frame.image().data()),
                              frame.image().size()});
    EXPECT_TRUE(decoded.ok()) << decoded.status();
    return decoded.ok() ? decoded->rgba : std::vector<uint8_t>{};
  }
};

TEST_F(RefineAtRestTest, DragThenRest_RungsRisingToTheStillRenderGives) {
  const v3::RenderSettings settings = Lossless(256);
  auto context = Context();
  auto stream = stub_->Interact(context.get());
  const std::vector<v3::Frame> frames = OpenDragAndRest(*stream, settings);
  ASSERT_FALSE(frames.empty());
  const v3::Frame& still = frames.back();
  ASSERT_FALSE(still.interactive()) << frames.size() << " frames, none the still";
  EXPECT_EQ(still.refine_level(), 0);
  // Back from the still: rungs N, ..., 1, then the last frame cast while moving.
  size_t first_rung = frames.size() - 1;
  while (first_rung > 0 && frames[first_rung - 1].refine_level() > 0) --first_rung;
  const size_t rungs = frames.size() - 1 - first_rung;
  ASSERT_GE(rungs, kRefineStepMultiples.size() > 0 ? 1u : 0u);
  ASSERT_GE(first_rung, 1u) << "no interactive frame before the rungs";
  const v3::Frame& moving = frames[first_rung - 1];
  EXPECT_TRUE(moving.interactive());
  EXPECT_EQ(moving.refine_level(), 0);

  const std::vector<uint8_t> reference = Pixels(still);
  double last_db = vpm::testing::CompareRgba(Pixels(moving), reference).psnr_db;
  for (size_t r = 0; r < rungs; ++r) {
    const v3::Frame& rung = frames[first_rung + r];
    EXPECT_EQ(rung.refine_level(), int32_t(r + 1));
    EXPECT_TRUE(rung.interactive());
    EXPECT_EQ(rung.last_sequence(), kLastDrag);
    EXPECT_EQ(rung.width(), 256);
    const double db = vpm::testing::CompareRgba(Pixels(rung), reference).psnr_db;
    EXPECT_GT(db, last_db) << "rung " << r + 1;
    EXPECT_LT(db, 99.0) << "rung " << r + 1 << " is the still";
    last_db = db;
  }
  // The still ends the ladder exactly as Render casts it.
  const v3::Frame direct = DirectStill(settings);
  EXPECT_EQ(direct.image(), still.image());
  stream->WritesDone();
  EXPECT_TRUE(stream->Finish().ok());
}

TEST_F(RefineAtRestTest, MoveDuringRefinement_InteractiveFrameNextLadderDropped) {
  // Full-size frames, JPEG: rung 1 reaches the client quickly while the
  // still after it takes hundreds of ms to cast, so the move arrives during
  // the refinement.
  v3::RenderSettings settings = Lossless(512);
  settings.set_encoding(v3::ENCODING_JPEG);
  auto context = Context();
  auto stream = stub_->Interact(context.get());
  Open(*stream, settings);
  std::jthread pointer([&] { GrabAndDrag(*stream); });
  v3::Frame frame;
  bool rung = false;
  while (!rung && stream->Read(&frame)) {
    ASSERT_TRUE(frame.interactive()) << "the still came without a rung";
    rung = frame.refine_level() == 1;
  }
  pointer.join();  // done: the rest began after its last drag
  ASSERT_TRUE(rung);
  constexpr uint64_t kMove = kLastDrag + 1;
  ASSERT_TRUE(stream->Write(Drag(9.0, kMove)));
  // The move cancels the rung in progress; the frame that answers it may be
  // cast before the move is applied (then it still carries kLastDrag, and
  // the move's own frame follows), but never as a rung or a still.
  do {
    ASSERT_TRUE(stream->Read(&frame));
    EXPECT_TRUE(frame.interactive()) << "the ladder went on to the still";
    EXPECT_EQ(frame.refine_level(), 0) << "a rung went on after the move";
    ASSERT_TRUE(frame.last_sequence() == kLastDrag || frame.last_sequence() == kMove)
        << frame.last_sequence();
  } while (frame.last_sequence() != kMove);
  // Rest again: the ladder starts over and ends with the move's still.
  const std::vector<v3::Frame> frames = ReadUntilStill(*stream, kMove);
  ASSERT_GE(frames.size(), 2u);
  EXPECT_FALSE(frames.back().interactive());
  EXPECT_EQ(frames.back().last_sequence(), kMove);
  EXPECT_EQ(frames[frames.size() - 2].refine_level(), int32_t(kRefineStepMultiples.size()));
  stream->WritesDone();
  EXPECT_TRUE(stream->Finish().ok());
}

// Where the still is predicted quicker than --refine-min-still-ms (here
// always, once the stream's first still has been cast), the rest goes from
// the interactive frames straight to the still: no rung puts it off.
TEST_F(RefineAtRestTest, QuickStill_NoRungs) {
  server_->Shutdown(std::chrono::milliseconds(2000));
  ServerOptions options = SmallServerOptions();
  options.refine_min_still_ms = 1e9;
  StartServer(options);
  volume_ = LoadPhantom();
  session_ = OpenSession(volume_.volume_id());
  const v3::RenderSettings settings = Lossless(256);
  auto context = Context();
  auto stream = stub_->Interact(context.get());
  const std::vector<v3::Frame> frames = OpenDragAndRest(*stream, settings);
  ASSERT_GE(frames.size(), 2u);
  const v3::Frame& still = frames.back();
  ASSERT_FALSE(still.interactive()) << frames.size() << " frames, none the still";
  for (const v3::Frame& frame : frames) EXPECT_EQ(frame.refine_level(), 0);
  EXPECT_TRUE(frames[frames.size() - 2].interactive());
  EXPECT_EQ(DirectStill(settings).image(), still.image());
  stream->WritesDone();
  EXPECT_TRUE(stream->Finish().ok());
}

}  // namespace
}  // namespace vpm::service::testing
