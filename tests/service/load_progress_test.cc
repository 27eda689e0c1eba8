// LoadVolume's progress (progress_id, polled through GetLoadProgress) and
// the per-volume byte budget (--max-volume-bytes).
#include <algorithm>
#include <atomic>
#include <filesystem>
#include <thread>

#include "server/io/read_volume.h"
#include "server/io/write_nifti.h"
#include "server/service/load_progress_registry.h"
#include "tests/service/service_test_util.h"

namespace vpm::service::testing {
namespace {

namespace fs = std::filesystem;

TEST(LoadProgressRegistry, IsMonotoneEndsAtOneAndKeepsErrors) {
  LoadProgressRegistry registry;
  ASSERT_TRUE(registry.Start("u", "a").ok());
  EXPECT_EQ(registry.Start("u", "a").code(), absl::StatusCode::kAlreadyExists);
  const ProgressFn report = registry.Reporter("u", "a");
  report(0.5, "reading");
  report(0.2, "reading");  // a second file starting over: not shown
  auto state = registry.Get("u", "a");
  ASSERT_TRUE(state.ok());
  EXPECT_EQ(state->fraction, 0.5);
  EXPECT_FALSE(state->done);
  registry.Finish("u", "a", absl::OkStatus());
  state = registry.Get("u", "a");
  EXPECT_TRUE(state->done);
  EXPECT_EQ(state->fraction, 1.0);
  EXPECT_EQ(state->stage, "done");
  report(0.7, "late");  // ignored once done
  EXPECT_EQ(registry.Get("u", "a")->stage, "done");

  ASSERT_TRUE(registry.Start("u", "b").ok());
  registry.Reporter("u", "b")(0.3, "reading");
  registry.Finish("u", "b", absl::NotFoundError("gone"));
  state = registry.Get("u", "b");
  EXPECT_TRUE(state->done);
  EXPECT_EQ(state->stage, "failed");
  EXPECT_EQ(state->fraction, 0.3);
  EXPECT_EQ(state->status.code(), absl::StatusCode::kNotFound);

  EXPECT_EQ(registry.Get("u", "never").status().code(), absl::StatusCode::kNotFound);
  // Another user's id is theirs alone: not found, and free to take.
  EXPECT_EQ(registry.Get("v", "b").status().code(), absl::StatusCode::kNotFound);
  EXPECT_TRUE(registry.Start("v", "a").ok());
  EXPECT_EQ(registry.Start("u", "has space").code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(registry.Start("u", std::string(65, 'x')).code(), absl::StatusCode::kInvalidArgument);
}

TEST(LoadProgressRegistry, EvictsFinishedLoadsWhenFull) {
  LoadProgressRegistry registry({.max_entries = 2, .keep_after_done = std::chrono::hours(1)});
  ASSERT_TRUE(registry.Start("u", "a").ok());
  ASSERT_TRUE(registry.Start("u", "b").ok());
  EXPECT_EQ(registry.Start("u", "c").code(), absl::StatusCode::kResourceExhausted);
  registry.Finish("u", "a", absl::OkStatus());
  EXPECT_TRUE(registry.Start("u", "c").ok());
  EXPECT_EQ(registry.Get("u", "a").status().code(), absl::StatusCode::kNotFound);
}

class LoadProgressTest : public ServiceTest {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() / ("vpm-progress-root-" + std::to_string(::getpid()));
    fs::remove_all(root_);
    fs::create_directories(root_);
    auto volume = ReadVolume("phantom:abdomen?size=48", {});
    ASSERT_TRUE(volume.ok());
    ASSERT_TRUE(WriteNifti(*volume, root_ / "small.nii").ok());  // 48^3 float: 442 KiB
    ServerOptions options = SmallServerOptions();
    options.data_root = root_.string();
    options.max_volume_bytes = 48 * 48 * 48 * 4;
    StartServer(options);
  }
  void TearDown() override {
    ServiceTest::TearDown();
    fs::remove_all(root_);
  }
  grpc::Status Load(const std::string& source, const std::string& progress_id) {
    v3::LoadVolumeRequest request;
    request.set_source(source);
    request.set_progress_id(progress_id);
    v3::VolumeInfo info;
    auto context = Context();
    return stub_->LoadVolume(context.get(), request, &info);
  }
  grpc::Status Poll(const std::string& progress_id, v3::LoadProgress* out) {
    v3::GetLoadProgressRequest request;
    request.set_progress_id(progress_id);
    auto context = Context();
    return stub_->GetLoadProgress(context.get(), request, out);
  }
  fs::path root_;
};

TEST_F(LoadProgressTest, PollsSeeMonotoneProgressReachingOne) {
  std::vector<double> seen;
  std::atomic<bool> loaded{false};
  std::thread poller([&] {
    while (!loaded) {
      v3::LoadProgress p;
      if (Poll("load-1", &p).ok()) seen.push_back(p.fraction());
    }
  });
  const grpc::Status status = Load("small.nii", "load-1");
  loaded = true;
  poller.join();
  ASSERT_TRUE(status.ok()) << status.error_message();
  v3::LoadProgress last;
  ASSERT_TRUE(Poll("load-1", &last).ok());
  EXPECT_TRUE(last.done());
  EXPECT_EQ(last.fraction(), 1.0);
  EXPECT_EQ(last.stage(), "done");
  EXPECT_EQ(last.error_code(), 0);
  seen.push_back(last.fraction());
  EXPECT_TRUE(std::is_sorted(seen.begin(), seen.end()));
}

TEST_F(LoadProgressTest, FailedLoadIsDoneWithItsError) {
  EXPECT_EQ(Load("missing.nii", "load-2").error_code(), grpc::NOT_FOUND);
  v3::LoadProgress p;
  ASSERT_TRUE(Poll("load-2", &p).ok());
  EXPECT_TRUE(p.done());
  EXPECT_EQ(p.stage(), "failed");
  EXPECT_LT(p.fraction(), 1.0);
  EXPECT_EQ(p.error_code(), static_cast<int>(absl::StatusCode::kNotFound));
  EXPECT_FALSE(p.error_message().empty());
  EXPECT_EQ(Poll("never-started", &p).error_code(), grpc::NOT_FOUND);
  EXPECT_EQ(Poll("bad id", &p).error_code(), grpc::INVALID_ARGUMENT);
  EXPECT_EQ(Load("small.nii", "bad id").error_code(), grpc::INVALID_ARGUMENT);
}

TEST_F(LoadProgressTest, VolumeOverTheBudgetIsResourceExhausted) {
  // 49^3 float voxels: over the 48^3 * 4 bytes of --max-volume-bytes.
  const grpc::Status status = Load("phantom:abdomen?size=49", "load-3");
  EXPECT_EQ(status.error_code(), grpc::RESOURCE_EXHAUSTED);
  EXPECT_NE(status.error_message().find("--max-volume-bytes"), std::string::npos)
      << status.error_message();
  EXPECT_TRUE(Load("phantom:abdomen?size=48", "").ok());
}

}  // namespace
}  // namespace vpm::service::testing
