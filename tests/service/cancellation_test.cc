// Queued work that nobody waits for is dropped before it runs: a burst of
// Render calls whose deadlines pass in the queue does not occupy the render
// workers, and the server answers the next call at once.
#include <condition_variable>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "tests/service/held_worker.h"
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
  const v3::VolumeInfo volume = LoadPhantom();
  const v3::SessionInfo session = OpenSession(volume.volume_id());
  v3::RenderRequest request;
  request.set_session_id(session.session_id());
  request.mutable_settings()->set_width(128);
  request.mutable_settings()->set_height(128);

  // The one render worker is held busy until the whole burst has expired, so
  // every call of the burst reaches the server (its deadline, 2 s, is far
  // longer than a local call takes to arrive, under sanitizers too) and
  // waits in the queue past its deadline.
  HeldWorker worker(*server_->context().render_pool);
  ASSERT_TRUE(worker.posted());

  constexpr int kCalls = 40;  // under the lane's cap, max_queued_per_user (64)
  std::vector<std::unique_ptr<grpc::ClientContext>> contexts;
  std::vector<v3::Frame> frames(kCalls);
  std::mutex mutex;
  std::condition_variable done;
  int finished = 0, expired = 0;
  const int64_t dropped_before = server_->metrics().dropped_jobs();
  const double rendered_before = server_->metrics().requests("Render", "OK");
  for (int i = 0; i < kCalls; ++i) {
    auto context = Context();
    context->set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(2));
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
  EXPECT_EQ(expired, kCalls);
  // The server's deadline for a call is the client's plus the time the call
  // took to arrive (grpc-timeout is relative): milliseconds, under the
  // sanitizers too. The worker is released once that has surely passed.
  std::this_thread::sleep_for(std::chrono::seconds(1));
  worker.Release();

  // The single render worker serves in order, and the burst and this call
  // share the user's lane: once this call returns, every call of the burst
  // has been taken from the queue, and each must have been dropped unrun.
  auto context = Context();
  v3::Frame frame;
  const grpc::Status status = stub_->Render(context.get(), request, &frame);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_GT(frame.image().size(), 0u);
  const int64_t dropped = server_->metrics().dropped_jobs() - dropped_before;
  const double rendered = server_->metrics().requests("Render", "OK") - rendered_before - 1;
  EXPECT_EQ(dropped, kCalls);
  EXPECT_EQ(rendered, 0) << dropped << " expired renders were dropped, " << rendered << " ran";
  // Every call was answered, the dropped ones too (a call never answered
  // would hold the server's shutdown forever).
  EXPECT_EQ(server_->metrics().unary_in_flight(), 0);
}

}  // namespace
}  // namespace vpm::service::testing
