// A fair share of everything shared: alice at her caps leaves bob fully
// served. Upload memory is reserved as bytes arrive (idle headers hold
// nothing) and capped per user; a trickling upload is ended; uploaded
// volumes are capped per owner, and so are the shared volumes a user's
// sessions keep loaded; the upload spool's disk is shared per user; a
// user's calls run on at most all workers but one; a user's sessions cannot
// pin every mesh slot. (Per-user streams,
// sessions and queued jobs: users_test.cc.)
#include <chrono>
#include <cstdio>
#include <condition_variable>
#include <mutex>
#include <thread>

#include "server/common/sha256.h"
#include "tests/service/two_users.h"

namespace vpm::service::testing {
namespace {

using Clock = std::chrono::steady_clock;


class FairShareTest : public TwoUsersTest {
 protected:
  void SetUp() override {}  // each test starts its server with its caps
  grpc::Status UploadAs(const std::string& token, v3::VolumeInfo* info) {
    const std::vector<uint8_t> bytes = NiftiBytes();
    return Upload(bytes, int64_t(bytes.size()), Sha256::HexOf(bytes), 64 << 10, info, true,
                  token);
  }
  grpc::Status LoadAs(const std::string& token, const std::string& source) {
    v3::LoadVolumeRequest request;
    request.set_source(source);
    v3::VolumeInfo info;
    return stub_->LoadVolume(Context(token).get(), request, &info);
  }
};

// The case 3: two idle 1 GiB upload headers of alice's, then bob's
// 125 KB upload (a 40^3 NIfTI). Before, the headers reserved the whole
// 2 GiB budget and bob was refused.
TEST_F(FairShareTest, IdleUploadHeadersHoldNoMemory) {
  StartWithUsers(SmallServerOptions());  // the default 1 GiB uploads, 2 GiB budget
  std::vector<std::unique_ptr<grpc::ClientContext>> contexts;
  std::vector<std::unique_ptr<grpc::ClientWriter<v3::UploadVolumeRequest>>> writers;
  std::vector<v3::VolumeInfo> infos(2);
  for (int i = 0; i < 2; ++i) {
    contexts.push_back(Context(kAliceToken));
    writers.push_back(
        StartUpload(stub_.get(), contexts.back().get(), &infos[i], int64_t{1} << 30, "held.nii"));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // the headers are taken
  v3::VolumeInfo bobs;
  const grpc::Status status = UploadAs(kBobToken, &bobs);
  EXPECT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(bobs.owner(), "bob");
  for (auto& context : contexts) context->TryCancel();
  for (auto& writer : writers) writer->Finish();
}

// Alice's uploads in flight reach her share of upload memory: her next
// chunk is refused, and bob's upload is taken whole.
TEST_F(FairShareTest, UploadMemoryIsSharedPerUser) {
  ServerOptions options = SmallServerOptions();
  options.max_upload_memory_bytes = 1 << 20;
  options.max_upload_memory_bytes_per_user = 512 << 10;
  StartWithUsers(options);
  // A header over her share is refused at once.
  {
    auto context = Context(kAliceToken);
    v3::VolumeInfo info;
    auto writer = StartUpload(stub_.get(), context.get(), &info, 600 << 10, "held.nii");
    writer->WritesDone();
    const grpc::Status refused = writer->Finish();
    EXPECT_EQ(refused.error_code(), grpc::RESOURCE_EXHAUSTED) << refused.error_message();
  }
  // Two uploads of 400 KiB: the first sends all of its bytes, the second
  // passes her 512 KiB share at its second chunk.
  auto first_context = Context(kAliceToken);
  v3::VolumeInfo first_info;
  auto first = StartUpload(stub_.get(), first_context.get(), &first_info, 400 << 10, "held.nii");
  ASSERT_TRUE(SendChunk(*first, 256 << 10));
  ASSERT_TRUE(SendChunk(*first, 144 << 10));
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // the chunks are taken
  auto second_context = Context(kAliceToken);
  v3::VolumeInfo second_info;
  auto second = StartUpload(stub_.get(), second_context.get(), &second_info, 400 << 10, "held.nii");
  SendChunk(*second, 64 << 10);
  SendChunk(*second, 128 << 10);
  second->WritesDone();
  const grpc::Status over = second->Finish();
  EXPECT_EQ(over.error_code(), grpc::RESOURCE_EXHAUSTED) << over.error_message();
  EXPECT_NE(over.error_message().find("share"), std::string::npos) << over.error_message();

  v3::VolumeInfo bobs;
  const grpc::Status status = UploadAs(kBobToken, &bobs);
  EXPECT_TRUE(status.ok()) << status.error_message();
  first_context->TryCancel();
  first->Finish();
}

// The spool's disk, like upload memory: every byte an upload takes will be
// written to the spool when it ends, so it is reserved as it arrives and
// capped per user. Alice's uploads in flight reach her share of the spool:
// her next chunk is refused, and bob's upload is taken whole (memory caps
// here are far above the spool's, so only the spool can refuse).
TEST_F(FairShareTest, UploadSpoolIsSharedPerUser) {
  ServerOptions options = SmallServerOptions();
  options.max_upload_memory_bytes = 64 << 20;
  options.max_upload_memory_bytes_per_user = 64 << 20;
  options.max_upload_spool_bytes = 1 << 20;
  options.max_upload_spool_bytes_per_user = 512 << 10;
  StartWithUsers(options);
  {
    // A header over her share of the spool is refused at once.
    auto context = Context(kAliceToken);
    v3::VolumeInfo info;
    auto writer = StartUpload(stub_.get(), context.get(), &info, 600 << 10, "held.nii");
    writer->WritesDone();
    const grpc::Status refused = writer->Finish();
    EXPECT_EQ(refused.error_code(), grpc::RESOURCE_EXHAUSTED) << refused.error_message();
    EXPECT_NE(refused.error_message().find("spool"), std::string::npos) << refused.error_message();
  }
  auto first_context = Context(kAliceToken);
  v3::VolumeInfo first_info;
  auto first = StartUpload(stub_.get(), first_context.get(), &first_info, 400 << 10, "held.nii");
  ASSERT_TRUE(SendChunk(*first, 256 << 10));
  ASSERT_TRUE(SendChunk(*first, 144 << 10));
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // the chunks are taken
  auto second_context = Context(kAliceToken);
  v3::VolumeInfo second_info;
  auto second = StartUpload(stub_.get(), second_context.get(), &second_info, 400 << 10, "held.nii");
  SendChunk(*second, 64 << 10);
  SendChunk(*second, 128 << 10);
  second->WritesDone();
  const grpc::Status over = second->Finish();
  EXPECT_EQ(over.error_code(), grpc::RESOURCE_EXHAUSTED) << over.error_message();
  EXPECT_NE(over.error_message().find("upload spool"), std::string::npos) << over.error_message();
  std::printf("alice's second upload: %s\n", over.error_message().c_str());

  v3::VolumeInfo bobs;
  const grpc::Status status = UploadAs(kBobToken, &bobs);
  EXPECT_TRUE(status.ok()) << status.error_message();
  first_context->TryCancel();
  first->Finish();
}

// A chunk every 400 ms never leaves the upload idle for --upload-idle-s
// (1 s), but its average is far under --upload-min-bytes-per-s: it is
// ended, so a trickle cannot hold memory for ever.
TEST_F(FairShareTest, TricklingUploadIsEnded) {
  ServerOptions options = SmallServerOptions();
  options.upload_idle_s = 1;
  options.upload_min_bytes_per_s = 1 << 20;
  StartWithUsers(options);
  auto context = Context(kAliceToken, 30);
  v3::VolumeInfo info;
  auto writer = StartUpload(stub_.get(), context.get(), &info, 8 << 20, "held.nii");
  int chunks = 0;
  while (chunks < 40 && SendChunk(*writer, 64 << 10)) {
    ++chunks;
    std::this_thread::sleep_for(std::chrono::milliseconds(400));
  }
  const grpc::Status ended = writer->Finish();
  EXPECT_EQ(ended.error_code(), grpc::DEADLINE_EXCEEDED) << ended.error_message();
  EXPECT_LT(chunks, 40) << "the trickle was never ended";
  std::printf("trickle ended after %d chunks: %s\n", chunks, ended.error_message().c_str());
}

// The case 4: alice uploads small volumes until refused (20 tries;
// the server holds 16, and uploads are never evicted): only
// --max-volumes-per-user of them are taken, and bob's LoadVolume and
// UploadVolume are served.
TEST_F(FairShareTest, UploadedVolumesAreCappedPerOwner) {
  ServerOptions options = SmallServerOptions();
  options.max_volumes = 16;
  options.max_volumes_per_user = 4;
  StartWithUsers(options);
  int taken = 0, refused = 0;
  for (int i = 0; i < 20; ++i) {
    v3::VolumeInfo info;
    const grpc::Status status = UploadAs(kAliceToken, &info);
    if (status.ok()) {
      ++taken;
    } else {
      EXPECT_EQ(status.error_code(), grpc::RESOURCE_EXHAUSTED) << status.error_message();
      ++refused;
    }
  }
  EXPECT_EQ(taken, 4);
  EXPECT_EQ(refused, 16);
  const grpc::Status loaded = LoadAs(kBobToken, "phantom:abdomen?size=16");
  EXPECT_TRUE(loaded.ok()) << loaded.error_message();
  v3::VolumeInfo bobs;
  const grpc::Status uploaded = UploadAs(kBobToken, &bobs);
  EXPECT_TRUE(uploaded.ok()) << uploaded.error_message();
}

// Running jobs per user: alice's two long builds (not cancelled) take one
// of the two request workers only; bob's LoadVolume runs on the other at
// once instead of waiting for a build to end.
TEST_F(FairShareTest, OneUsersLongCallsLeaveAWorkerFree) {
  ServerOptions options = SmallServerOptions();
  options.request_threads = 2;
  StartWithUsers(options);
  v3::VolumeInfo volume;
  {
    v3::LoadVolumeRequest request;
    request.set_source("phantom:abdomen?size=96");
    ASSERT_TRUE(stub_->LoadVolume(Context(kAliceToken).get(), request, &volume).ok());
  }
  std::vector<std::unique_ptr<grpc::ClientContext>> contexts;
  std::vector<v3::MeshInfo> infos(2);
  std::mutex mutex;
  std::condition_variable done;
  int finished = 0;
  for (int i = 0; i < 2; ++i) {
    v3::BuildMeshRequest request;
    request.set_volume_id(volume.volume_id());
    for (int a = 0; a < 3; ++a) request.mutable_params()->add_grid(60);
    request.mutable_params()->set_target(4000 + i);
    contexts.push_back(Context(kAliceToken));
    stub_->async()->BuildMesh(contexts.back().get(), &request, &infos[i], [&](grpc::Status) {
      std::lock_guard lock(mutex);
      ++finished;
      done.notify_all();
    });
  }
  // Both calls have arrived (one runs, one waits in alice's lane).
  const auto arrived_by = Clock::now() + std::chrono::seconds(30);
  while (server_->metrics().unary_in_flight() < 2 && Clock::now() < arrived_by) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  const auto start = Clock::now();
  const grpc::Status loaded = LoadAs(kBobToken, "phantom:abdomen?size=16");
  const double waited_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
  EXPECT_TRUE(loaded.ok()) << loaded.error_message();
  std::printf("bob's LoadVolume waited %.1f ms beside alice's two builds\n", waited_ms);
  EXPECT_LT(waited_ms, 1000.0);
  {
    std::lock_guard lock(mutex);
    EXPECT_EQ(finished, 0) << "the builds ended before bob's call; use a bigger lattice";
  }
  for (auto& context : contexts) context->TryCancel();
  std::unique_lock lock(mutex);
  done.wait_for(lock, std::chrono::seconds(60), [&] { return finished == 2; });
}

// Mesh slots: a mesh is pinned only by the sessions on it, and a user's
// sessions are capped (--max-sessions-per-user, under --max-meshes), so
// alice at her session cap with more meshes built than the server holds
// leaves bob room: her unpinned meshes are evicted for his build.
TEST_F(FairShareTest, MeshSlotsLeaveRoomForAnotherUser) {
  ServerOptions options = SmallServerOptions();
  options.max_meshes = 3;
  options.max_sessions = 6;
  options.max_sessions_per_user = 2;
  StartWithUsers(options);
  v3::VolumeInfo volume;
  {
    v3::LoadVolumeRequest request;
    request.set_source("phantom:abdomen?size=32");
    ASSERT_TRUE(stub_->LoadVolume(Context(kAliceToken).get(), request, &volume).ok());
  }
  auto build = [&](const std::string& token, int64_t target, v3::MeshInfo* info) {
    v3::BuildMeshRequest request;
    request.set_volume_id(volume.volume_id());
    request.mutable_params()->set_target(target);
    return stub_->BuildMesh(Context(token).get(), request, info);
  };
  // Alice: three meshes (the server's whole room), two pinned by her two
  // sessions, and a third session refused.
  std::vector<v3::MeshInfo> alices(3);
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(build(kAliceToken, 40 + i, &alices[i]).ok());
  for (int i = 0; i < 3; ++i) {
    v3::OpenSessionRequest open;
    open.set_mesh_id(alices[i].mesh_id());
    v3::SessionInfo session;
    const grpc::Status status = stub_->OpenSession(Context(kAliceToken).get(), open, &session);
    EXPECT_EQ(status.ok(), i < 2) << status.error_message();
  }
  v3::MeshInfo bobs;
  const grpc::Status status = build(kBobToken, 50, &bobs);
  EXPECT_TRUE(status.ok()) << status.error_message();
}

// The case 4 through sessions: a shared volume (a phantom here, or
// a file of the data root) that a user's session keeps loaded cannot be
// evicted, so it takes one of that user's volume slots. Alice loads the
// server's four volumes and opens sessions on them: two are taken
// (--max-volumes-per-user 2), and bob's LoadVolume of a fifth volume and his
// UploadVolume are served. Before, her four sessions held every slot and
// bob got "the server's volumes are all in use".
TEST_F(FairShareTest, SessionsOnSharedVolumesTakeTheirOwnersSlots) {
  ServerOptions options = SmallServerOptions();
  options.max_volumes = 4;
  options.max_volumes_per_user = 2;
  options.max_sessions = 16;
  options.max_sessions_per_user = 8;
  StartWithUsers(options);
  int opened = 0;
  std::string refusal;
  for (int i = 0; i < 4; ++i) {
    v3::LoadVolumeRequest load;
    load.set_source("phantom:abdomen?size=" + std::to_string(24 + i));
    v3::VolumeInfo volume;
    ASSERT_TRUE(stub_->LoadVolume(Context(kAliceToken).get(), load, &volume).ok());
    v3::OpenSessionRequest open;
    open.set_volume_id(volume.volume_id());
    v3::SessionInfo session;
    const grpc::Status status = stub_->OpenSession(Context(kAliceToken).get(), open, &session);
    if (status.ok()) {
      ++opened;
      // A second session on a volume she holds takes no new slot.
      ASSERT_TRUE(stub_->OpenSession(Context(kAliceToken).get(), open, &session).ok());
    } else {
      EXPECT_EQ(status.error_code(), grpc::RESOURCE_EXHAUSTED) << status.error_message();
      refusal = status.error_message();
    }
  }
  EXPECT_EQ(opened, 2);
  EXPECT_NE(refusal.find("--max-volumes-per-user"), std::string::npos) << refusal;
  std::printf("alice's third volume: %s\n", refusal.c_str());
  // Her uploads count against the same slots.
  v3::VolumeInfo upload;
  EXPECT_EQ(UploadAs(kAliceToken, &upload).error_code(), grpc::RESOURCE_EXHAUSTED);

  const grpc::Status loaded = LoadAs(kBobToken, "phantom:abdomen?size=32");
  EXPECT_TRUE(loaded.ok()) << loaded.error_message();
  v3::VolumeInfo bobs;
  const grpc::Status uploaded = UploadAs(kBobToken, &bobs);
  EXPECT_TRUE(uploaded.ok()) << uploaded.error_message();
}

// Mesh slots per user, whatever the session cap: alice's sessions may pin
// --max-meshes-per-user meshes (here 2 of the server's 3, with a session
// cap of 8); a session on a third mesh is refused, and bob's build is
// served (her unpinned mesh is evicted for it).
TEST_F(FairShareTest, SessionsPinAtMostTheirOwnersMeshSlots) {
  ServerOptions options = SmallServerOptions();
  options.max_meshes = 3;
  options.max_meshes_per_user = 2;
  options.max_sessions = 16;
  options.max_sessions_per_user = 8;
  StartWithUsers(options);
  v3::VolumeInfo volume;
  {
    v3::LoadVolumeRequest request;
    request.set_source("phantom:abdomen?size=32");
    ASSERT_TRUE(stub_->LoadVolume(Context(kAliceToken).get(), request, &volume).ok());
  }
  auto build = [&](const std::string& token, int64_t target, v3::MeshInfo* info) {
    v3::BuildMeshRequest request;
    request.set_volume_id(volume.volume_id());
    request.mutable_params()->set_target(target);
    return stub_->BuildMesh(Context(token).get(), request, info);
  };
  std::vector<v3::MeshInfo> alices(3);
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(build(kAliceToken, 40 + i, &alices[i]).ok());
  std::string refusal;
  for (int i = 0; i < 3; ++i) {
    v3::OpenSessionRequest open;
    open.set_mesh_id(alices[i].mesh_id());
    v3::SessionInfo session;
    const grpc::Status status = stub_->OpenSession(Context(kAliceToken).get(), open, &session);
    EXPECT_EQ(status.ok(), i < 2) << status.error_message();
    if (!status.ok()) refusal = status.error_message();
  }
  EXPECT_NE(refusal.find("--max-meshes-per-user"), std::string::npos) << refusal;
  v3::MeshInfo bobs;
  const grpc::Status status = build(kBobToken, 50, &bobs);
  EXPECT_TRUE(status.ok()) << status.error_message();
}

}  // namespace
}  // namespace vpm::service::testing
