// Nothing a client does by ordinary use exhausts the server: idle volumes
// are evicted least recently used (and read again when named), a volume in
// use never is, and a refusal says what holds the room; sessions watched but
// driven by nobody are closed after --idle-watched-session-s; uploads count
// against the user's stream cap and the server's upload memory budget,
// and an upload that goes quiet ends with DEADLINE_EXCEEDED.
#include <thread>

#include "server/common/sha256.h"
#include "tests/service/service_test_util.h"

namespace vpm::service::testing {
namespace {

class ResourceLifecycleTest : public ServiceTest {
 protected:
  void SetUp() override { StartServer(Options(1)); }
  // idle_s: sessions without viewers (or driven by nobody) close after this.
  static ServerOptions Options(double idle_s) {
    ServerOptions options = SmallServerOptions();
    options.max_volumes = 2;
    options.idle_session_s = idle_s;
    options.idle_watched_session_s = idle_s;
    options.max_upload_memory_bytes = 3 << 20;
    options.upload_idle_s = 1;
    return options;
  }
  grpc::Status GetVolume(const std::string& id, v3::VolumeInfo* info) {
    v3::GetVolumeRequest request;
    request.set_volume_id(id);
    auto context = Context();
    return stub_->GetVolume(context.get(), request, info);
  }
  grpc::Status Load(const std::string& source, v3::VolumeInfo* info) {
    v3::LoadVolumeRequest request;
    request.set_source(source);
    auto context = Context();
    return stub_->LoadVolume(context.get(), request, info);
  }
};

TEST_F(ResourceLifecycleTest, IdleVolumesAreEvictedLeastRecentlyUsedAndReadAgain) {
  v3::VolumeInfo a, b, c, again;
  ASSERT_TRUE(Load("phantom:abdomen?size=32", &a).ok());
  ASSERT_TRUE(Load("phantom:abdomen?size=36", &b).ok());
  ASSERT_TRUE(GetVolume(a.volume_id(), &again).ok());  // a is now the more recent
  // At the cap of 2: b (least recently used, idle) makes room for c.
  grpc::Status loaded = Load("phantom:abdomen?size=40", &c);
  ASSERT_TRUE(loaded.ok()) << loaded.error_message();
  EXPECT_EQ(server_->metrics().volumes_evicted(), 1.0);
  // b's id still works: it is read again (evicting a, now the LRU one).
  v3::VolumeInfo b_again;
  ASSERT_TRUE(GetVolume(b.volume_id(), &b_again).ok());
  EXPECT_EQ(b_again.volume_id(), b.volume_id());
  EXPECT_EQ(b_again.dims(0), 36);
  EXPECT_EQ(server_->metrics().volumes_evicted(), 2.0);
  // A deleted id is gone for good, evicted or not.
  v3::DeleteVolumeRequest del;
  del.set_volume_id(a.volume_id());
  v3::DeleteVolumeResponse deleted;
  auto context = Context();
  ASSERT_TRUE(stub_->DeleteVolume(context.get(), del, &deleted).ok());
  EXPECT_EQ(GetVolume(a.volume_id(), &again).error_code(), grpc::NOT_FOUND);
}

TEST_F(ResourceLifecycleTest, VolumesInUseAreNeverEvictedAndTheRefusalSaysWhy) {
  // Sessions that never close by idleness: under a sanitizer opening two
  // takes longer than the fixture's 1 s, which would close the first.
  server_->Shutdown(std::chrono::milliseconds(1000));
  StartServer(Options(0));
  v3::VolumeInfo a, b, c;
  ASSERT_TRUE(Load("phantom:abdomen?size=32", &a).ok());
  ASSERT_TRUE(Load("phantom:abdomen?size=36", &b).ok());
  const v3::SessionInfo sa = OpenSession(a.volume_id());
  const v3::SessionInfo sb = OpenSession(b.volume_id());
  const grpc::Status refused = Load("phantom:abdomen?size=40", &c);
  EXPECT_EQ(refused.error_code(), grpc::RESOURCE_EXHAUSTED);
  EXPECT_NE(refused.error_message().find("session"), std::string::npos)
      << refused.error_message();
  EXPECT_EQ(server_->metrics().volumes_evicted(), 0.0);
  // Both sessions still work.
  v3::RenderRequest render;
  render.set_session_id(sa.session_id());
  render.mutable_settings()->set_width(32);
  render.mutable_settings()->set_height(32);
  v3::Frame frame;
  auto context = Context();
  EXPECT_TRUE(stub_->Render(context.get(), render, &frame).ok());
}

TEST_F(ResourceLifecycleTest, SessionWatchedButNeverDrivenIsClosed) {
  const v3::VolumeInfo volume = LoadPhantom("phantom:abdomen?size=32");
  const v3::SessionInfo session = OpenSession(volume.volume_id());
  v3::WatchRequest watch;
  watch.set_session_id(session.session_id());
  watch.mutable_settings()->set_width(32);
  watch.mutable_settings()->set_height(32);
  auto context = Context();
  auto reader = stub_->Watch(context.get(), watch);
  v3::Frame frame;
  ASSERT_TRUE(reader->Read(&frame));
  // Nobody drives it: within a few reaper rounds (1 s each) it is closed and
  // the Watch ends.
  while (reader->Read(&frame)) {
  }
  const grpc::Status ended = reader->Finish();
  EXPECT_EQ(ended.error_code(), grpc::FAILED_PRECONDITION) << ended.error_message();
  v3::ListSessionsRequest list;
  v3::ListSessionsResponse sessions;
  auto list_context = Context();
  ASSERT_TRUE(stub_->ListSessions(list_context.get(), list, &sessions).ok());
  EXPECT_EQ(sessions.sessions_size(), 0);
}


TEST_F(ResourceLifecycleTest, QuietUploadEndsWithDeadlineExceededAndFreesItsBudget) {
  // Memory is reserved as bytes arrive: the first upload holds the 2 MiB it
  // has sent of its 3 MiB.
  v3::VolumeInfo info;
  auto context = Context();
  auto writer = StartUpload(stub_.get(), context.get(), &info, 3 << 20, "quiet.nii");
  ASSERT_TRUE(SendChunk(*writer, 1 << 20));
  ASSERT_TRUE(SendChunk(*writer, 1 << 20));
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // its chunks are taken
  // While it holds 2 MiB of the 3 MiB budget, a second upload's second
  // MiB is refused.
  {
    v3::VolumeInfo info2;
    auto context2 = Context();
    auto writer2 = StartUpload(stub_.get(), context2.get(), &info2, 2 << 20, "quiet.nii");
    SendChunk(*writer2, 1 << 20);
    SendChunk(*writer2, 1 << 20);
    writer2->WritesDone();
    const grpc::Status refused = writer2->Finish();
    EXPECT_EQ(refused.error_code(), grpc::RESOURCE_EXHAUSTED) << refused.error_message();
    EXPECT_NE(refused.error_message().find("budget"), std::string::npos);
  }
  // The first sends nothing more: after --upload-idle-s (1 s) it is ended.
  const grpc::Status quiet = writer->Finish();
  EXPECT_EQ(quiet.error_code(), grpc::DEADLINE_EXCEEDED) << quiet.error_message();
  // Its budget is free again: a 2 MiB upload is taken whole (then fails on
  // its checksum, which is this test's stand-in for a whole file).
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  v3::VolumeInfo info3;
  auto context3 = Context();
  auto writer3 = StartUpload(stub_.get(), context3.get(), &info3, 2 << 20, "quiet.nii");
  SendChunk(*writer3, 1 << 20);
  SendChunk(*writer3, 1 << 20);
  writer3->WritesDone();
  const grpc::Status mismatch = writer3->Finish();
  EXPECT_EQ(mismatch.error_code(), grpc::INVALID_ARGUMENT) << mismatch.error_message();
  EXPECT_NE(mismatch.error_message().find("checksum"), std::string::npos)
      << mismatch.error_message();
}

TEST_F(ResourceLifecycleTest, UploadsCountAgainstTheUsersStreamCap) {
  // SmallServerOptions: 4 streams per user. Four quiet uploads hold them.
  std::vector<std::unique_ptr<grpc::ClientContext>> contexts;
  std::vector<std::unique_ptr<grpc::ClientWriter<v3::UploadVolumeRequest>>> writers;
  std::vector<v3::VolumeInfo> infos(5);
  for (int i = 0; i < 4; ++i) {
    contexts.push_back(Context());
    writers.push_back(StartUpload(stub_.get(), contexts.back().get(), &infos[i], 100, "quiet.nii"));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  auto context = Context();
  auto fifth = StartUpload(stub_.get(), context.get(), &infos[4], 100, "quiet.nii");
  fifth->WritesDone();
  const grpc::Status refused = fifth->Finish();
  EXPECT_EQ(refused.error_code(), grpc::RESOURCE_EXHAUSTED) << refused.error_message();
  for (auto& writer : writers) {
    writer->WritesDone();
    writer->Finish();
  }
}

}  // namespace
}  // namespace vpm::service::testing
