// Access is checked for the life of a stream: revoking a share ends the
// viewer's open Watch at once with PERMISSION_DENIED, and no frame reaches
// the viewer after the revoke; closing a session ends every stream on it
// (the owner's Interact and its viewers' Watch) with PERMISSION_DENIED.
// Through gRPC, alice owning the session and bob watching it.
#include <atomic>
#include <chrono>
#include <cstdio>
#include <condition_variable>
#include <mutex>
#include <optional>
#include <thread>

#include "tests/service/two_users.h"

namespace vpm::service::testing {
namespace {

using Clock = std::chrono::steady_clock;

// A Watch read on a thread of its own: frames counted, the end's status kept.
class WatchReader {
 public:
  WatchReader(v3::Vpm::Stub* stub, const std::string& token, const std::string& session_id) {
    context_.AddMetadata("authorization", std::string("Bearer ") + token);
    // Only so that a stream that never ends fails the test instead of
    // hanging it.
    context_.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
    v3::WatchRequest request;
    request.set_session_id(session_id);
    request.mutable_settings()->set_width(64);
    request.mutable_settings()->set_height(64);
    reader_ = stub->Watch(&context_, request);
    thread_ = std::thread([this] { Read(); });
  }
  ~WatchReader() {
    context_.TryCancel();
    thread_.join();
  }
  // Waits until `n` frames have arrived (false if the stream ended first).
  bool WaitForFrames(int n) {
    std::unique_lock lock(mutex_);
    changed_.wait(lock, [&] { return frames_ >= n || status_.has_value(); });
    return frames_ >= n;
  }
  int frames() const {
    std::lock_guard lock(mutex_);
    return frames_;
  }
  // The stream's status once it ends (nullopt if it is open after `wait`),
  // and when it ended.
  std::optional<grpc::Status> WaitForEnd(std::chrono::seconds wait) {
    std::unique_lock lock(mutex_);
    changed_.wait_for(lock, wait, [&] { return status_.has_value(); });
    return status_;
  }
  Clock::time_point ended_at() const {
    std::lock_guard lock(mutex_);
    return ended_at_;
  }

 private:
  void Read() {
    v3::Frame frame;
    while (reader_->Read(&frame)) {
      std::lock_guard lock(mutex_);
      ++frames_;
      changed_.notify_all();
    }
    grpc::Status status = reader_->Finish();
    std::lock_guard lock(mutex_);
    status_ = status;
    ended_at_ = Clock::now();
    changed_.notify_all();
  }

  grpc::ClientContext context_;
  std::unique_ptr<grpc::ClientReader<v3::Frame>> reader_;
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  int frames_ = 0;
  std::optional<grpc::Status> status_;
  Clock::time_point ended_at_;
  std::thread thread_;
};

class StreamAccessTest : public TwoUsersTest {
 protected:
  void SetUp() override {
    TwoUsersTest::SetUp();
    volume_ = LoadPhantom(kPhantom, kAliceToken);
    session_ = OpenSession(volume_.volume_id(), kAliceToken);
  }
  grpc::Status Share(const std::string& user, bool revoke) {
    v3::ShareSessionRequest request;
    request.set_session_id(session_.session_id());
    request.set_user(user);
    request.set_revoke(revoke);
    v3::SessionInfo info;
    return stub_->ShareSession(Context(kAliceToken).get(), request, &info);
  }
  grpc::Status SetCamera(double azimuth_deg) {
    v3::SetCameraRequest request;
    request.set_session_id(session_.session_id());
    request.mutable_camera()->set_azimuth_deg(azimuth_deg);
    v3::SetCameraResponse response;
    return stub_->SetCamera(Context(kAliceToken).get(), request, &response);
  }

  v3::VolumeInfo volume_;
  v3::SessionInfo session_;
};

TEST_F(StreamAccessTest, RevokeEndsAViewersWatchWhileFramesFlow) {
  ASSERT_TRUE(Share("bob", false).ok());
  WatchReader bob(stub_.get(), kBobToken, session_.session_id());
  ASSERT_TRUE(bob.WaitForFrames(1));
  // Alice keeps moving the camera, so that bob's stream has a new frame to
  // send all along, before and after the revoke.
  std::atomic<bool> driving{true};
  std::thread alice([&] {
    for (int i = 0; driving; ++i) {
      SetCamera(10.0 * (i % 36));
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  });
  const bool flowing = bob.WaitForFrames(bob.frames() + 3);
  const grpc::Status revoked = Share("bob", true);
  const Clock::time_point revoked_at = Clock::now();
  const int frames_at_revoke = bob.frames();
  const std::optional<grpc::Status> end = bob.WaitForEnd(std::chrono::seconds(10));
  // A while longer with the camera moving: a stream that had not ended
  // would get more frames.
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  driving = false;
  alice.join();

  ASSERT_TRUE(flowing) << "frames did not flow before the revoke";
  ASSERT_TRUE(revoked.ok()) << revoked.error_message();
  ASSERT_TRUE(end.has_value()) << "bob's Watch still open 10 s after the revoke, "
                               << bob.frames() - frames_at_revoke << " frames later";
  EXPECT_EQ(end->error_code(), grpc::PERMISSION_DENIED) << end->error_message();
  // At most the one write in flight when the revoke returned.
  const int after = bob.frames() - frames_at_revoke;
  EXPECT_LE(after, 1) << after << " frames reached bob after the revoke";
  const double ended_ms =
      std::chrono::duration<double, std::milli>(bob.ended_at() - revoked_at).count();
  RecordProperty("frames_after_revoke", after);
  RecordProperty("ended_after_revoke_ms", static_cast<int>(ended_ms));
  std::printf("bob: %d frames before the revoke, %d after; ended %.1f ms after it\n",
              frames_at_revoke, after, ended_ms);
}

TEST_F(StreamAccessTest, RevokeEndsAnIdleViewersWatch) {
  ASSERT_TRUE(Share("bob", false).ok());
  WatchReader bob(stub_.get(), kBobToken, session_.session_id());
  ASSERT_TRUE(bob.WaitForFrames(1));
  // Nothing changes in the session: no frame is due that could carry the
  // news; the revoke itself must end the stream.
  ASSERT_TRUE(Share("bob", true).ok());
  const std::optional<grpc::Status> end = bob.WaitForEnd(std::chrono::seconds(10));
  ASSERT_TRUE(end.has_value()) << "bob's idle Watch still open 10 s after the revoke";
  EXPECT_EQ(end->error_code(), grpc::PERMISSION_DENIED) << end->error_message();
}

TEST_F(StreamAccessTest, RevokeLeavesOtherViewersAndTheOwnerWatching) {
  ASSERT_TRUE(Share("bob", false).ok());
  WatchReader alice(stub_.get(), kAliceToken, session_.session_id());
  WatchReader bob(stub_.get(), kBobToken, session_.session_id());
  ASSERT_TRUE(alice.WaitForFrames(1));
  ASSERT_TRUE(bob.WaitForFrames(1));
  ASSERT_TRUE(Share("bob", true).ok());
  const std::optional<grpc::Status> end = bob.WaitForEnd(std::chrono::seconds(10));
  ASSERT_TRUE(end.has_value());
  EXPECT_EQ(end->error_code(), grpc::PERMISSION_DENIED);
  // Alice's own Watch goes on: it gets the frame of her next camera move.
  const int before = alice.frames();
  ASSERT_TRUE(SetCamera(40.0).ok());
  EXPECT_TRUE(alice.WaitForFrames(before + 1));
  EXPECT_FALSE(alice.WaitForEnd(std::chrono::seconds(0)).has_value());
}

TEST_F(StreamAccessTest, CloseSessionEndsTheOwnersAndTheViewersStreams) {
  ASSERT_TRUE(Share("bob", false).ok());
  WatchReader bob(stub_.get(), kBobToken, session_.session_id());
  auto context = Context(kAliceToken);
  auto interact = stub_->Interact(context.get());
  v3::InteractRequest first;
  first.set_session_id(session_.session_id());
  ASSERT_TRUE(interact->Write(first));
  v3::Frame frame;
  ASSERT_TRUE(interact->Read(&frame));
  ASSERT_TRUE(bob.WaitForFrames(1));

  v3::CloseSessionRequest close;
  close.set_session_id(session_.session_id());
  v3::CloseSessionResponse closed;
  ASSERT_TRUE(stub_->CloseSession(Context(kAliceToken).get(), close, &closed).ok());
  const std::optional<grpc::Status> end = bob.WaitForEnd(std::chrono::seconds(10));
  ASSERT_TRUE(end.has_value());
  EXPECT_EQ(end->error_code(), grpc::PERMISSION_DENIED) << end->error_message();
  while (interact->Read(&frame)) {
  }
  EXPECT_EQ(interact->Finish().error_code(), grpc::PERMISSION_DENIED);
}

}  // namespace
}  // namespace vpm::service::testing
