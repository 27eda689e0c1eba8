// A storm of Render calls that nobody waits for does not starve an Interact
// stream: 2,000 Render calls with 1 ms deadlines arrive while one client
// drags. The stream takes its turn in its own lane of the render pool
// (fair_job_queue.h); expired calls are purged or dropped unrun, and a full
// lane answers RESOURCE_EXHAUSTED with a retry hint at once.
//
// What is asserted is counted, not timed: at most a handful of the expired
// renders run (each one that runs is render time taken from the drag), and
// the drag is never stalled behind the storm (the longest wait for a frame
// is bounded far above a frame's time, far below the storm's backlog). The
// frame rate in the storm against alone is a benchmark:
// bench/render_storm_bench.cc (figures in README.md).
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <thread>
#include <vector>

#include "client/common/closed_loop_drag.h"
#include "tests/service/service_test_util.h"

namespace vpm::service::testing {
namespace {

using Clock = std::chrono::steady_clock;

using RenderStormTest = ServiceTest;

// Render calls nobody waits for: each with a 1 ms deadline, 2 ms apart,
// from a channel of its own (another connection of the same client
// address), and how they were answered. Holds what the asynchronous calls
// use until every one is answered.
struct RenderStorm {
  explicit RenderStorm(int port, int calls)
      : stub(v3::Vpm::NewStub(grpc::CreateChannel("127.0.0.1:" + std::to_string(port),
                                                  grpc::InsecureChannelCredentials()))),
        contexts(calls),
        frames(calls) {}

  void Count(const grpc::Status& status) {
    ok += status.ok();
    expired += status.error_code() == grpc::DEADLINE_EXCEEDED;
    exhausted += status.error_code() == grpc::RESOURCE_EXHAUSTED;
    if (!status.ok() && status.error_code() != grpc::DEADLINE_EXCEEDED &&
        status.error_code() != grpc::RESOURCE_EXHAUSTED) {
      ++unexpected;
      std::printf("unexpected: %d %s\n", status.error_code(), status.error_message().c_str());
    }
    ++answered;
  }

  // Sends every call (about 2 ms each); `storming` is true meanwhile.
  void Run(const v3::RenderRequest& request) {
    storming = true;
    for (size_t i = 0; i < contexts.size(); ++i) {
      contexts[i] = std::make_unique<grpc::ClientContext>();
      contexts[i]->AddMetadata("authorization", std::string("Bearer ") + kToken);
      contexts[i]->set_deadline(std::chrono::system_clock::now() + std::chrono::milliseconds(1));
      stub->async()->Render(contexts[i].get(), &request, &frames[i],
                            [this](grpc::Status status) { Count(status); });
      std::this_thread::sleep_for(std::chrono::microseconds(2000));
    }
    storming = false;
  }

  bool WaitForAllAnswers(std::chrono::seconds limit) {
    const auto end = Clock::now() + limit;
    while (answered < static_cast<int>(contexts.size()) && Clock::now() < end) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return answered == static_cast<int>(contexts.size());
  }

  std::unique_ptr<v3::Vpm::Stub> stub;
  std::vector<std::unique_ptr<grpc::ClientContext>> contexts;
  std::vector<v3::Frame> frames;
  std::atomic<bool> storming{false};
  std::atomic<int> answered{0}, ok{0}, expired{0}, exhausted{0}, unexpected{0};
};

TEST_F(RenderStormTest, ExpiredRenderStormRunsAlmostNoneAndNeverStallsTheDrag) {
  const v3::VolumeInfo volume = LoadPhantom();
  const v3::SessionInfo session = OpenSession(volume.volume_id());
  v3::RenderSettings small;
  small.set_width(96);
  small.set_height(96);

  auto context = Context();
  auto stream = stub_->Interact(context.get());
  v3::InteractRequest first;
  first.set_session_id(session.session_id());
  first.mutable_event()->set_sequence(1);
  *first.mutable_event()->mutable_settings() = small;
  *first.mutable_event()->mutable_grab()->mutable_point_mm() = Centre(volume);
  ASSERT_TRUE(stream->Write(first));
  v3::Frame frame;
  ASSERT_TRUE(stream->Read(&frame));
  uint64_t sequence = 1;
  cli::DragFor(stream.get(), 0.5, &sequence);

  // The storm: 2,000 calls over about 4 s while the drag goes on.
  constexpr int kCalls = 2000;
  RenderStorm storm(server_->port(), kCalls);
  v3::RenderRequest request;
  request.set_session_id(session.session_id());
  *request.mutable_settings() = small;
  const double rendered_before = server_->metrics().requests("Render", "OK");
  std::thread storm_thread([&] { storm.Run(request); });
  while (!storm.storming) std::this_thread::yield();
  int storm_frames = 0;
  double longest_wait_s = 0;
  while (storm.storming) {
    const cli::ClosedLoopDrag drag = cli::DragFor(stream.get(), 0.25, &sequence);
    storm_frames += drag.frames;
    longest_wait_s = std::max(longest_wait_s, drag.longest_wait_s);
  }
  storm_thread.join();
  ASSERT_TRUE(storm.WaitForAllAnswers(std::chrono::seconds(30))) << storm.answered.load();

  const double rendered = server_->metrics().requests("Render", "OK") - rendered_before;
  std::printf(
      "drag frames in the storm %d, longest wait %.0f ms; of %d expired renders: "
      "%d deadline, %d refused (queue full), %d ran (server counted %.0f)\n",
      storm_frames, 1000 * longest_wait_s, kCalls, storm.expired.load(), storm.exhausted.load(),
      storm.ok.load(), rendered);
  EXPECT_LE(rendered, 20) << "expired renders that ran";
  EXPECT_EQ(storm.unexpected.load(), 0);
  EXPECT_EQ(storm.expired + storm.exhausted + storm.ok, kCalls);
  EXPECT_GT(storm_frames, 0);
  // A 96^2 frame takes tens of ms here; the storm, were it run, hundreds of
  // seconds. A drag that waited behind it would wait far longer than this.
  EXPECT_LT(longest_wait_s, 3.0) << "the drag waited behind the storm";

  stream->WritesDone();
  while (stream->Read(&frame)) {
  }
  EXPECT_TRUE(stream->Finish().ok());
}

// A client that floods one pool gets RESOURCE_EXHAUSTED with gRPC's retry
// pushback trailer once its lane is full, and the calls it had queued still
// run.
TEST_F(RenderStormTest, FullLaneIsRefusedWithARetryHint) {
  const v3::VolumeInfo volume = LoadPhantom();
  const v3::SessionInfo session = OpenSession(volume.volume_id());
  v3::RenderRequest request;
  request.set_session_id(session.session_id());
  request.mutable_settings()->set_width(64);
  request.mutable_settings()->set_height(64);
  constexpr int kCalls = 200;  // past the default lane cap of 64
  std::vector<std::unique_ptr<grpc::ClientContext>> contexts(kCalls);
  std::vector<v3::Frame> frames(kCalls);
  std::atomic<int> answered{0}, ok{0}, exhausted{0}, hinted{0};
  for (int i = 0; i < kCalls; ++i) {
    contexts[i] = Context();
    grpc::ClientContext* c = contexts[i].get();
    stub_->async()->Render(c, &request, &frames[i], [&, c](grpc::Status status) {
      ok += status.ok();
      if (status.error_code() == grpc::RESOURCE_EXHAUSTED) {
        ++exhausted;
        const auto& trailers = c->GetServerTrailingMetadata();
        auto it = trailers.find("grpc-retry-pushback-ms");
        hinted += it != trailers.end() && std::stoll(std::string(it->second.data(),
                                                                  it->second.size())) > 0 &&
                  status.error_message().find("retry after") != std::string::npos;
      }
      ++answered;
    });
  }
  const auto end = Clock::now() + std::chrono::seconds(120);
  while (answered < kCalls && Clock::now() < end) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_EQ(answered.load(), kCalls);
  EXPECT_GT(exhausted.load(), 0);
  EXPECT_EQ(hinted.load(), exhausted.load());
  EXPECT_GE(ok.load(), 64);
  EXPECT_EQ(ok + exhausted, kCalls);
}

}  // namespace
}  // namespace vpm::service::testing
