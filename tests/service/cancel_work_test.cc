// Cancellation stops work that is already running: a BuildMesh whose client
// cancels it stops at its next poll of the call's CancelToken, so another
// user's call waiting for the request pool runs at once (the case
// 5: two cancelled 60^3 builds by alice, then bob's LoadVolume of a tiny
// phantom must wait under 1 s); the shutdown grace period ends running
// builds too.
#include <chrono>
#include <cstdio>
#include <condition_variable>
#include <mutex>
#include <thread>

#include "tests/service/two_users.h"

namespace vpm::service::testing {
namespace {

using Clock = std::chrono::steady_clock;

// A volume on which a 60^3 lattice build takes seconds.
constexpr char kBigPhantom[] = "phantom:abdomen?size=96";

class CancelWorkTest : public TwoUsersTest {
 protected:
  void SetUp() override {
    ServerOptions options = SmallServerOptions();
    options.request_threads = 2;
    // Both of alice's builds run at once, as in the issue (by default one
    // user's calls keep a worker free for others: fair_share_test.cc), so
    // that only cancellation can free a worker for bob.
    options.max_running_per_user = 2;
    StartWithUsers(options);
    volume_ = LoadPhantom(kBigPhantom, kAliceToken);
  }

  // BuildMesh calls of alice's on the 60^3 lattice, answered asynchronously.
  struct Builds {
    std::vector<std::unique_ptr<grpc::ClientContext>> contexts;
    std::vector<v3::MeshInfo> infos;
    std::mutex mutex;
    std::condition_variable done;
    std::vector<grpc::Status> statuses;
  };
  void StartBuilds(Builds& builds, int count, int64_t target) {
    builds.infos.resize(count);
    for (int i = 0; i < count; ++i) {
      v3::BuildMeshRequest request;
      request.set_volume_id(volume_.volume_id());
      for (int a = 0; a < 3; ++a) request.mutable_params()->add_grid(60);
      // Distinct targets: distinct meshes, not one build shared.
      request.mutable_params()->set_target(target + i);
      builds.contexts.push_back(Context(kAliceToken));
      stub_->async()->BuildMesh(builds.contexts.back().get(), &request, &builds.infos[i],
                                [&builds](grpc::Status status) {
                                  std::lock_guard lock(builds.mutex);
                                  builds.statuses.push_back(status);
                                  builds.done.notify_all();
                                });
    }
  }
  // True once `count` calls have reached the workers (none left queued).
  bool WaitUntilRunning(int count) {
    const auto end = Clock::now() + std::chrono::seconds(60);
    while (Clock::now() < end) {
      if (server_->metrics().unary_in_flight() >= count &&
          server_->context().request_pool->queued() == 0) {
        return true;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return false;
  }

  v3::VolumeInfo volume_;
};

// Cancelled in step 2 (0.3 s in) and in the Steiner rounds (2.5 s in; a
// build here takes about 20 s uncancelled).
TEST_F(CancelWorkTest, CancelledBuildsFreeTheWorkersForAnotherUser) {
  int64_t target = 4000;
  for (const int cancel_after_ms : {300, 2500}) {
    SCOPED_TRACE(cancel_after_ms);
    Builds builds;
    StartBuilds(builds, 2, target);
    target += 2;  // new meshes next time, not the held ones
    ASSERT_TRUE(WaitUntilRunning(2));
    std::this_thread::sleep_for(std::chrono::milliseconds(cancel_after_ms));
    const auto cancelled_at = Clock::now();
    for (auto& context : builds.contexts) context->TryCancel();

    const v3::VolumeInfo tiny = LoadPhantom(
        "phantom:abdomen?size=" + std::to_string(16 + cancel_after_ms % 7), kBobToken);
    const double waited_ms =
        std::chrono::duration<double, std::milli>(Clock::now() - cancelled_at).count();
    EXPECT_FALSE(tiny.volume_id().empty());
    std::printf("cancelled %d ms in: bob's LoadVolume waited %.1f ms behind two cancelled "
                "60^3 builds\n", cancel_after_ms, waited_ms);
    EXPECT_LT(waited_ms, 1000.0) << "the issue's bound for case 5";

    std::unique_lock lock(builds.mutex);
    ASSERT_TRUE(builds.done.wait_for(lock, std::chrono::seconds(60),
                                     [&] { return builds.statuses.size() == 2; }));
    for (const grpc::Status& status : builds.statuses) {
      EXPECT_EQ(status.error_code(), grpc::CANCELLED) << status.error_message();
    }
  }
}

TEST_F(CancelWorkTest, ABuildPastItsDeadlineStops) {
  v3::BuildMeshRequest request;
  request.set_volume_id(volume_.volume_id());
  for (int a = 0; a < 3; ++a) request.mutable_params()->add_grid(60);
  request.mutable_params()->set_target(4200);
  auto context = Context(kAliceToken);
  context->set_deadline(std::chrono::system_clock::now() + std::chrono::milliseconds(700));
  v3::MeshInfo info;
  const auto start = Clock::now();
  const grpc::Status status = stub_->BuildMesh(context.get(), request, &info);
  EXPECT_EQ(status.error_code(), grpc::DEADLINE_EXCEEDED);
  // The client's deadline ends its wait, not the server's work: the call is
  // answered (no longer in flight) once the build has noticed and stopped.
  const auto stop_by = Clock::now() + std::chrono::seconds(30);
  while (server_->metrics().unary_in_flight() > 0 && Clock::now() < stop_by) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  const double stopped_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
  std::printf("deadline 700 ms: the server's build ended %.1f ms after the call began\n",
              stopped_ms);
  EXPECT_EQ(server_->metrics().unary_in_flight(), 0);
  EXPECT_LT(stopped_ms, 700.0 + 1000.0);
}

TEST_F(CancelWorkTest, ShutdownEndsRunningBuildsWithinTheGrace) {
  Builds builds;
  StartBuilds(builds, 2, 4100);
  ASSERT_TRUE(WaitUntilRunning(2));
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  const auto start = Clock::now();
  server_->Shutdown(std::chrono::milliseconds(500));
  const double shutdown_ms =
      std::chrono::duration<double, std::milli>(Clock::now() - start).count();
  std::printf("Shutdown with a 500 ms grace took %.1f ms with two builds running\n",
              shutdown_ms);
  // The grace plus the 100 ms for a build to notice, with margin.
  EXPECT_LT(shutdown_ms, 500.0 + 1000.0);
  std::unique_lock lock(builds.mutex);
  ASSERT_TRUE(builds.done.wait_for(lock, std::chrono::seconds(30),
                                   [&] { return builds.statuses.size() == 2; }));
  for (const grpc::Status& status : builds.statuses) {
    EXPECT_EQ(status.error_code(), grpc::UNAVAILABLE) << status.error_message();
  }
}

}  // namespace
}  // namespace vpm::service::testing
