// Queued work that nobody waits for is dropped before it runs: a burst of
// Render calls whose deadlines pass in the queue does not occupy the render
// workers, and the server answers the next call at once.
#include <condition_variable>
#include <memory>
#include <mutex>
#include <vector>

#include "tests/service/service_test_util.h"

namespace vpm::service::testing {
namespace {

class CancellationTest : public ServiceTest {
 protected:
  void SetUp() override {
    ServerOptions options = SmallServerOptions();
    options.render_threads = 1;  // one queue, served in order
    StartServer(options);
  }
};

TEST_F(CancellationTest, RendersPastTheirDeadlineAreDroppedBeforeTheyRun) {
  const v2::VolumeInfo volume = LoadPhantom();
  const v2::SessionInfo session = OpenSession(volume.volume_id());
  v2::RenderRequest request;
  request.set_session_id(session.session_id());
  request.mutable_settings()->set_width(128);
  request.mutable_settings()->set_height(128);

  constexpr int kCalls = 300;
  std::vector<std::unique_ptr<grpc::ClientContext>> contexts;
  std::vector<v2::Frame> frames(kCalls);
  std::mutex mutex;
  std::condition_variable done;
  int finished = 0, expired = 0;
  const int64_t dropped_before = server_->metrics().dropped_jobs();
  const double rendered_before = server_->metrics().requests("Render", "OK");
  for (int i = 0; i < kCalls; ++i) {
    auto context = Context();
    context->set_deadline(std::chrono::system_clock::now() + std::chrono::milliseconds(1));
    stub_->async()->Render(context.get(), &request, &frames[i], [&](grpc::Status status) {
      std::lock_guard lock(mutex);
      ++finished;
      expired += status.error_code() == grpc::DEADLINE_EXCEEDED;
      done.notify_all();
    });
    contexts.push_back(std::move(context));
  }
  {
    std::unique_lock lock(mutex);
    ASSERT_TRUE(done.wait_for(lock, std::chrono::seconds(60), [&] { return finished == kCalls; }));
  }
  // A call the server happens to finish inside its millisecond succeeds.
  EXPECT_GE(expired, kCalls - 10);

  // The single render worker serves in order: once this call returns, every
  // call of the burst has been run or dropped.
  auto context = Context();
  v2::Frame frame;
  const grpc::Status status = stub_->Render(context.get(), request, &frame);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_GT(frame.image().size(), 0u);
  // Calls whose millisecond ran out on the client never reach the server;
  // of those that did, a handful may start inside their millisecond, and
  // every other one must be dropped, not rendered.
  const int64_t dropped = server_->metrics().dropped_jobs() - dropped_before;
  const double rendered = server_->metrics().requests("Render", "OK") - rendered_before - 1;
  EXPECT_GT(dropped, 0);
  EXPECT_LE(rendered, 10) << dropped << " expired renders were dropped, " << rendered << " ran";
}

}  // namespace
}  // namespace vpm::service::testing
