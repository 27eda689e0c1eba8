// Cancellation stops work that is already running: a BuildMesh whose client
// cancels it stops at its next poll of the call's CancelToken, so another
// user's call waiting for the request pool runs at once (the case
// 5: two cancelled 60^3 builds by alice, then bob's LoadVolume of a tiny
// phantom must wait under 1 s); the shutdown grace period ends running
// builds too. A load cancelled inside its reader and a still cancelled
// between its bands stop within 100 ms.
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <mutex>
#include <optional>
#include <thread>

#include "server/io/read_volume.h"
#include "server/io/write_nifti.h"

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

// Waits until no unary call is in flight on the server; the time since
// `since`, ms.
double MsUntilIdle(VpmServer& server, Clock::time_point since) {
  const auto stop_by = Clock::now() + std::chrono::seconds(30);
  while (server.metrics().unary_in_flight() > 0 && Clock::now() < stop_by) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return std::chrono::duration<double, std::milli>(Clock::now() - since).count();
}

// Cancellation inside the file readers and between the bands of a still:
// a LoadVolume of a large .nii.gz from the data root, and a Render of a
// 2048^2 still (bands of about 15 ms), each cancelled by its client while it
// runs. The suite runs alone (tests/service/CMakeLists.txt).
class CancelReadAndRenderTest : public TwoUsersTest {
 protected:
  void SetUp() override {
    root_ =
        std::filesystem::temp_directory_path() / ("vpm-cancel-read-" + std::to_string(::getpid()));
    std::filesystem::remove_all(root_);
    std::filesystem::create_directories(root_);
    ServerOptions options = SmallServerOptions();
    options.data_root = root_.string();
    options.max_frame_side = 2048;
    StartWithUsers(options);
  }
  void TearDown() override {
    TwoUsersTest::TearDown();
    std::filesystem::remove_all(root_);
  }
  // Starts `call` (given a context), waits until the server runs it, lets
  // it run `run_ms`, cancels it; returns the ms from the cancel until the
  // server answered it.
  double CancelWhileRunning(const std::function<void(grpc::ClientContext*)>& call, double run_ms) {
    auto context = Context(kAliceToken);
    call(context.get());
    const auto arrived_by = Clock::now() + std::chrono::seconds(30);
    while (server_->metrics().unary_in_flight() < 1 && Clock::now() < arrived_by) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(run_ms));
    EXPECT_EQ(server_->metrics().unary_in_flight(), 1) << "the call ended before its cancel";
    const auto cancelled_at = Clock::now();
    context->TryCancel();
    return MsUntilIdle(*server_, cancelled_at);
  }

  std::filesystem::path root_;
};

TEST_F(CancelReadAndRenderTest, ALoadCancelledWhileReadingStopsWithin100Ms) {
  auto volume = ReadVolume("phantom:abdomen?size=256", {});
  ASSERT_TRUE(volume.ok()) << volume.status();
  ASSERT_TRUE(WriteNifti(*volume, root_ / "big.nii.gz").ok());
  // The whole load, uncancelled (then deleted, so the next one reads again).
  v3::LoadVolumeRequest request;
  request.set_source("big.nii.gz");
  v3::VolumeInfo info;
  const auto start = Clock::now();
  ASSERT_TRUE(stub_->LoadVolume(Context(kAliceToken).get(), request, &info).ok());
  const double whole_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
  v3::DeleteVolumeRequest del;
  del.set_volume_id(info.volume_id());
  v3::DeleteVolumeResponse deleted;
  ASSERT_TRUE(stub_->DeleteVolume(Context(kAliceToken).get(), del, &deleted).ok());

  std::mutex mutex;
  std::condition_variable done;
  std::optional<grpc::Status> answer;
  const double stop_ms = CancelWhileRunning(
      [&](grpc::ClientContext* context) {
        stub_->async()->LoadVolume(context, &request, &info, [&](grpc::Status status) {
          std::lock_guard lock(mutex);
          answer = status;
          done.notify_all();
        });
      },
      whole_ms / 3);
  std::unique_lock lock(mutex);
  ASSERT_TRUE(done.wait_for(lock, std::chrono::seconds(30), [&] { return answer.has_value(); }));
  std::printf(
      "LoadVolume of a 256^3 .nii.gz: %.0f ms whole; cancelled a third in, the server "
      "answered %.1f ms after the cancel\n",
      whole_ms, stop_ms);
  EXPECT_EQ(answer->error_code(), grpc::CANCELLED);
  EXPECT_LT(stop_ms, 100.0);
}

TEST_F(CancelReadAndRenderTest, AStillCancelledBetweenBandsStopsWithin100Ms) {
  const v3::VolumeInfo volume = LoadPhantom("phantom:abdomen?size=96", kAliceToken);
  const v3::SessionInfo session = OpenSession(volume.volume_id(), kAliceToken);
  v3::RenderRequest request;
  request.set_session_id(session.session_id());
  request.mutable_settings()->set_width(2048);
  request.mutable_settings()->set_height(2048);
  v3::Frame frame;
  const auto start = Clock::now();
  ASSERT_TRUE(stub_->Render(Context(kAliceToken).get(), request, &frame).ok());
  const double whole_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();

  std::mutex mutex;
  std::condition_variable done;
  std::optional<grpc::Status> answer;
  const double stop_ms = CancelWhileRunning(
      [&](grpc::ClientContext* context) {
        stub_->async()->Render(context, &request, &frame, [&](grpc::Status status) {
          std::lock_guard lock(mutex);
          answer = status;
          done.notify_all();
        });
      },
      whole_ms / 3);
  std::unique_lock lock(mutex);
  ASSERT_TRUE(done.wait_for(lock, std::chrono::seconds(30), [&] { return answer.has_value(); }));
  std::printf(
      "Render of a 2048^2 still (bands of about 15 ms): %.0f ms whole; cancelled a third in, the "
      "server answered %.1f ms after the cancel\n",
      whole_ms, stop_ms);
  EXPECT_EQ(answer->error_code(), grpc::CANCELLED);
  EXPECT_LT(stop_ms, 100.0);
}

}  // namespace
}  // namespace vpm::service::testing
