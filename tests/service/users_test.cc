// Users and ownership: the users file and its errors, --token-file, every
// call knowing its user, sessions and uploads belonging to their creator
// (another's session, upload, mesh on an upload or load progress id is
// NOT_FOUND, exactly as a missing one; ids are random), sharing a session to watch, shared volumes
// of the data root and phantoms, per-user stream caps and per-user metrics.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <string>
#include <thread>

#include "server/common/sha256.h"
#include "server/service/server_flags.h"
#include "server/service/users_file.h"
#include "tests/service/service_test_util.h"

namespace vpm::service::testing {
namespace {

namespace fs = std::filesystem;

constexpr char kAlice[] = "alice-secret-token";
constexpr char kBob[] = "bob-secret-token";
constexpr char kCarol[] = "carol-secret-token";

std::string WriteFile(const fs::path& path, const std::string& text) {
  std::ofstream(path) << text;
  return path.string();
}

TEST(UsersFile, ParsesNamesHashesCommentsAndBlankLines) {
  const std::string text = "# the planners\n\nalice " + HashToken(kAlice) + "\r\n" +
                           "  bob\t" + HashToken(kBob) + "  \n";
  auto users = ParseUsersFile(text, "users.txt");
  ASSERT_TRUE(users.ok()) << users.status();
  ASSERT_EQ(users->size(), 2u);
  EXPECT_EQ((*users)[0].name, "alice");
  EXPECT_EQ((*users)[0].token_sha256_hex, HashToken(kAlice));
  EXPECT_EQ((*users)[1].name, "bob");
}

TEST(UsersFile, HashIsTheSha256OfTheToken) {
  // FIPS 180-2's "abc" example.
  EXPECT_EQ(HashToken("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  auto line = UsersFileLine("alice", kAlice);
  ASSERT_TRUE(line.ok()) << line.status();
  EXPECT_EQ(*line, "alice " + HashToken(kAlice));
  EXPECT_FALSE(UsersFileLine("al ice", kAlice).ok());
  EXPECT_FALSE(UsersFileLine("alice", "").ok());
}

TEST(UsersFile, HashTokenRefusesTokensUnder16CharactersWithoutEchoingThem) {
  auto short_line = UsersFileLine("alice", "abcdefghijklmno");  // 15
  ASSERT_FALSE(short_line.ok());
  EXPECT_EQ(short_line.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(short_line.status().message().find("at least 16"), std::string::npos)
      << short_line.status();
  EXPECT_EQ(short_line.status().message().find("abcdefghijklmno"), std::string::npos);
  EXPECT_FALSE(UsersFileLine("alice", "x").ok());
  EXPECT_TRUE(UsersFileLine("alice", "abcdefghijklmnop").ok());  // 16
}

TEST(UsersFile, BadLinesNameTheLineAndTheFault) {
  const std::string hash = HashToken(kAlice);
  struct Case {
    std::string text;
    std::string expect;  // in the message
  };
  const std::vector<Case> cases = {
      {"alice\n", "line 1: 1 fields, not 2"},
      {"# ok\nalice " + hash + " extra\n", "line 2: unknown permission 'extra'"},
      {"alice " + std::string(kAlice) + "\n", "64 hexadecimal digits"},
      {"alice " + hash.substr(1) + "\n", "64 hexadecimal digits"},
      {"al/ice " + hash + "\n", "only letters, digits"},
      {"alice " + hash + "\nalice " + HashToken(kBob) + "\n", "line 2: user 'alice' given twice"},
      {"alice " + hash + "\nbob " + hash + "\n", "line 2: user 'bob' has the token of an earlier"},
      {"# nobody\n\n", "no users"},
  };
  for (const Case& c : cases) {
    auto users = ParseUsersFile(c.text, "users.txt");
    ASSERT_FALSE(users.ok()) << c.text;
    EXPECT_EQ(users.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(users.status().message().find(c.expect), std::string::npos)
        << users.status().message() << " should say " << c.expect;
    EXPECT_NE(users.status().message().find("users.txt"), std::string::npos);
  }
}

class UsersTest : public ServiceTest {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("vpm-users-test-" + std::to_string(getpid()));
    fs::create_directories(dir_);
    users_file_ = WriteFile(dir_ / "users.txt", "alice " + HashToken(kAlice) + "\nbob " +
                                                    HashToken(kBob) + "\ncarol " +
                                                    HashToken(kCarol) + "\n");
    ServerOptions o = SmallServerOptions();
    o.token.clear();
    o.users_file = users_file_;
    o.max_sessions = 6;
    o.max_streams_per_user = 2;
    StartServer(o);
  }
  void TearDown() override {
    ServiceTest::TearDown();
    fs::remove_all(dir_);
  }

  grpc::Status Manipulate(const std::string& token, const std::string& session_id) {
    v3::ManipulateRequest request;
    request.set_session_id(session_id);
    request.mutable_event()->mutable_camera()->set_azimuth_deg(30);
    v3::ManipulateResponse response;
    return stub_->Manipulate(Context(token).get(), request, &response);
  }
  grpc::Status GetSession(const std::string& token, const std::string& session_id,
                          v3::SessionInfo* info) {
    v3::GetSessionRequest request;
    request.set_session_id(session_id);
    return stub_->GetSession(Context(token).get(), request, info);
  }
  grpc::Status Share(const std::string& token, const std::string& session_id,
                     const std::string& user, bool revoke = false) {
    v3::ShareSessionRequest request;
    request.set_session_id(session_id);
    request.set_user(user);
    request.set_revoke(revoke);
    v3::SessionInfo info;
    return stub_->ShareSession(Context(token).get(), request, &info);
  }
  // A Watch as `token`'s user: the status it ends with after `frames`
  // frames (or before the first), OK when it delivered them.
  grpc::Status Watch(const std::string& token, const std::string& session_id, int frames = 1) {
    v3::WatchRequest request;
    request.set_session_id(session_id);
    request.mutable_settings()->set_width(64);
    request.mutable_settings()->set_height(64);
    auto context = Context(token);
    auto reader = stub_->Watch(context.get(), request);
    v3::Frame frame;
    for (int i = 0; i < frames; ++i) {
      if (!reader->Read(&frame)) return reader->Finish();
    }
    context->TryCancel();
    reader->Finish();
    return grpc::Status::OK;
  }
  // Waits (up to 20 s) until the server has released every stream slot of
  // `user`: a cancelled stream frees its slot when the server's OnDone runs,
  // which a sanitizer can delay past the client's Finish; a new stream of a
  // user at the cap of 2 would then be RESOURCE_EXHAUSTED.
  bool UserStreamsReleased(const std::string& user) {
    const std::string zero = "vpm_user_streams{user=\"" + user + "\"} 0";
    const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (server_->metrics().Scrape().find(zero) == std::string::npos) {
      if (std::chrono::steady_clock::now() > end) return false;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return true;
  }
  grpc::Status Interact(const std::string& token, const std::string& session_id) {
    auto context = Context(token);
    auto stream = stub_->Interact(context.get());
    v3::InteractRequest first;
    first.set_session_id(session_id);
    stream->Write(first);
    v3::Frame frame;
    if (stream->Read(&frame)) {
      context->TryCancel();
      stream->Finish();
      return grpc::Status::OK;
    }
    return stream->Finish();
  }

  fs::path dir_;
  std::string users_file_;
};

TEST_F(UsersTest, EveryUserSignsInWithTheirOwnTokenAndNoOtherToken) {
  v3::ListVolumesResponse response;
  EXPECT_TRUE(stub_->ListVolumes(Context(kAlice).get(), {}, &response).ok());
  EXPECT_TRUE(stub_->ListVolumes(Context(kBob).get(), {}, &response).ok());
  EXPECT_EQ(stub_->ListVolumes(Context(kToken).get(), {}, &response).error_code(),
            grpc::UNAUTHENTICATED);  // no --token: no user `default`
  EXPECT_EQ(stub_->ListVolumes(Context(HashToken(kAlice)).get(), {}, &response).error_code(),
            grpc::UNAUTHENTICATED);  // the hash is not the token
  EXPECT_EQ(server_->metrics().requests("ListVolumes", "OK", "alice"), 1);
  EXPECT_EQ(server_->metrics().requests("ListVolumes", "OK", "bob"), 1);
  EXPECT_EQ(server_->metrics().requests("ListVolumes", "UNAUTHENTICATED", "unauthenticated"), 2);
}

TEST_F(UsersTest, AnotherUsersSessionIsNotFoundLikeAMissingOne) {
  const v3::VolumeInfo volume = LoadPhantom(kPhantom, kAlice);
  const v3::SessionInfo session = OpenSession(volume.volume_id(), kAlice);
  EXPECT_EQ(session.owner(), "alice");
  v3::SessionInfo info;
  EXPECT_TRUE(GetSession(kAlice, session.session_id(), &info).ok());
  EXPECT_TRUE(Manipulate(kAlice, session.session_id()).ok());

  EXPECT_EQ(Manipulate(kBob, session.session_id()).error_code(), grpc::NOT_FOUND);
  EXPECT_EQ(GetSession(kBob, session.session_id(), &info).error_code(), grpc::NOT_FOUND);
  EXPECT_EQ(Watch(kBob, session.session_id()).error_code(), grpc::NOT_FOUND);
  EXPECT_EQ(Interact(kBob, session.session_id()).error_code(), grpc::NOT_FOUND);
  v3::SetCameraRequest camera;
  camera.set_session_id(session.session_id());
  v3::SetCameraResponse camera_response;
  EXPECT_EQ(stub_->SetCamera(Context(kBob).get(), camera, &camera_response).error_code(),
            grpc::NOT_FOUND);
  v3::RenderRequest render;
  render.set_session_id(session.session_id());
  v3::Frame frame;
  EXPECT_EQ(stub_->Render(Context(kBob).get(), render, &frame).error_code(),
            grpc::NOT_FOUND);
  v3::CloseSessionRequest close;
  close.set_session_id(session.session_id());
  v3::CloseSessionResponse close_response;
  EXPECT_EQ(stub_->CloseSession(Context(kBob).get(), close, &close_response).error_code(),
            grpc::NOT_FOUND);
  EXPECT_EQ(Share(kBob, session.session_id(), "bob").error_code(), grpc::NOT_FOUND);
  // One answer for "not yours" and "not there": the same code and text.
  grpc::Status not_yours = GetSession(kBob, session.session_id(), &info);
  grpc::Status not_there = GetSession(kBob, "ses-00000000-0123456789abcdef0123456789abcdef", &info);
  EXPECT_EQ(not_yours.error_code(), grpc::NOT_FOUND);
  EXPECT_EQ(not_there.error_code(), grpc::NOT_FOUND);
  EXPECT_EQ(not_yours.error_message(), not_there.error_message());

  v3::ListSessionsResponse listed;
  ASSERT_TRUE(stub_->ListSessions(Context(kBob).get(), {}, &listed).ok());
  EXPECT_EQ(listed.sessions_size(), 0);
  ASSERT_TRUE(stub_->ListSessions(Context(kAlice).get(), {}, &listed).ok());
  EXPECT_EQ(listed.sessions_size(), 1);

  // Alice's session survived all of it.
  EXPECT_TRUE(Watch(kAlice, session.session_id()).ok());
  EXPECT_GE(server_->metrics().requests("Manipulate", "NOT_FOUND", "bob"), 1);
  const std::string metrics = server_->metrics().Scrape();
  EXPECT_NE(metrics.find("vpm_user_sessions{user=\"alice\"} 1"), std::string::npos) << metrics;
  EXPECT_NE(metrics.find("vpm_requests_total{code=\"NOT_FOUND\",method=\"Manipulate\","
                         "user=\"bob\"} 1"),
            std::string::npos)
      << metrics;
}

TEST_F(UsersTest, SharingLetsAViewerWatchButNotDeform) {
  const v3::VolumeInfo volume = LoadPhantom(kPhantom, kAlice);
  const v3::SessionInfo session = OpenSession(volume.volume_id(), kAlice);
  EXPECT_EQ(Share(kAlice, session.session_id(), "nobody").error_code(), grpc::INVALID_ARGUMENT);
  EXPECT_EQ(Share(kAlice, session.session_id(), "alice").error_code(), grpc::INVALID_ARGUMENT);
  ASSERT_TRUE(Share(kAlice, session.session_id(), "bob").ok());

  v3::SessionInfo info;
  ASSERT_TRUE(GetSession(kBob, session.session_id(), &info).ok());
  EXPECT_EQ(info.owner(), "alice");
  EXPECT_EQ(info.shared_with_size(), 0);  // the list is the owner's to see
  ASSERT_TRUE(GetSession(kAlice, session.session_id(), &info).ok());
  ASSERT_EQ(info.shared_with_size(), 1);
  EXPECT_EQ(info.shared_with(0), "bob");

  EXPECT_TRUE(Watch(kBob, session.session_id()).ok());
  v3::RenderRequest render;
  render.set_session_id(session.session_id());
  render.mutable_settings()->set_width(64);
  render.mutable_settings()->set_height(64);
  v3::Frame frame;
  EXPECT_TRUE(stub_->Render(Context(kBob).get(), render, &frame).ok());
  EXPECT_EQ(Manipulate(kBob, session.session_id()).error_code(), grpc::PERMISSION_DENIED);
  EXPECT_EQ(Interact(kBob, session.session_id()).error_code(), grpc::PERMISSION_DENIED);
  // Carol was not asked.
  EXPECT_EQ(Watch(kCarol, session.session_id()).error_code(), grpc::NOT_FOUND);

  ASSERT_TRUE(Share(kAlice, session.session_id(), "bob", /*revoke=*/true).ok());
  ASSERT_TRUE(UserStreamsReleased("bob")) << server_->metrics().Scrape();
  EXPECT_EQ(Watch(kBob, session.session_id()).error_code(), grpc::NOT_FOUND);
}

// True when `id` is `prefix`, 8 lowercase hex digits (the server's tag), a
// dash and 32 lowercase hex digits (128 random bits). std::regex is avoided:
// GCC 12's <regex> trips -Werror=maybe-uninitialized under the sanitizers.
bool IsRandomId(const std::string& id, const std::string& prefix) {
  auto hex = [](const std::string& s) {
    return std::all_of(s.begin(), s.end(),
                       [](char c) { return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'); });
  };
  const size_t n = prefix.size();
  return id.size() == n + 8 + 1 + 32 && id.compare(0, n, prefix) == 0 && id[n + 8] == '-' &&
         hex(id.substr(n, 8)) && hex(id.substr(n + 9));
}

// An answer to Bob about Alice's object is exactly a missing one's (code
// and message), so he cannot tell that hers exist.
void ExpectSameAsMissing(const grpc::Status& theirs, const grpc::Status& missing) {
  EXPECT_EQ(theirs.error_code(), grpc::NOT_FOUND) << theirs.error_message();
  EXPECT_EQ(theirs.error_code(), missing.error_code());
  EXPECT_EQ(theirs.error_message(), missing.error_message());
}

constexpr char kMadeUpVolume[] = "vol-00000000-00000000000000000000000000000000";
constexpr char kMadeUpMesh[] = "mesh-00000000-00000000000000000000000000000000";

TEST_F(UsersTest, UploadedVolumesBelongToTheUploader) {
  const std::vector<uint8_t> bytes = NiftiBytes();
  v3::VolumeInfo volume;
  ASSERT_TRUE(Upload(bytes, int64_t(bytes.size()), Sha256::HexOf(bytes), 64 << 10, &volume, true,
                     kAlice)
                  .ok());
  EXPECT_EQ(volume.owner(), "alice");
  // Ids are random: they tell nothing of how many volumes or meshes exist.
  EXPECT_TRUE(IsRandomId(volume.volume_id(), "vol-")) << volume.volume_id();
  v3::GetVolumeRequest get;
  v3::VolumeInfo info;
  get.set_volume_id(kMadeUpVolume);
  const grpc::Status missing_volume = stub_->GetVolume(Context(kBob).get(), get, &info);
  get.set_volume_id(volume.volume_id());
  ExpectSameAsMissing(stub_->GetVolume(Context(kBob).get(), get, &info), missing_volume);
  v3::ListVolumesResponse listed;
  ASSERT_TRUE(stub_->ListVolumes(Context(kBob).get(), {}, &listed).ok());
  EXPECT_EQ(listed.volumes_size(), 0);
  v3::BuildMeshRequest build;
  v3::MeshInfo mesh;
  build.set_volume_id(kMadeUpVolume);
  const grpc::Status missing_build = stub_->BuildMesh(Context(kBob).get(), build, &mesh);
  build.set_volume_id(volume.volume_id());
  ExpectSameAsMissing(stub_->BuildMesh(Context(kBob).get(), build, &mesh), missing_build);
  v3::OpenSessionRequest open;
  v3::SessionInfo session;
  open.set_volume_id(kMadeUpVolume);
  const grpc::Status missing_open = stub_->OpenSession(Context(kBob).get(), open, &session);
  open.set_volume_id(volume.volume_id());
  ExpectSameAsMissing(stub_->OpenSession(Context(kBob).get(), open, &session), missing_open);
  v3::DeleteVolumeRequest del;
  v3::DeleteVolumeResponse deleted;
  del.set_volume_id(kMadeUpVolume);
  const grpc::Status missing_delete = stub_->DeleteVolume(Context(kBob).get(), del, &deleted);
  del.set_volume_id(volume.volume_id());
  ExpectSameAsMissing(stub_->DeleteVolume(Context(kBob).get(), del, &deleted), missing_delete);
  EXPECT_TRUE(stub_->DeleteVolume(Context(kAlice).get(), del, &deleted).ok());
}

TEST_F(UsersTest, AMeshIsOutOfOtherUsersReach) {
  const std::vector<uint8_t> bytes = NiftiBytes();
  v3::VolumeInfo volume;
  ASSERT_TRUE(
      Upload(bytes, int64_t(bytes.size()), Sha256::HexOf(bytes), 64 << 10, &volume, true, kAlice)
          .ok());
  v3::BuildMeshRequest build;
  build.set_volume_id(volume.volume_id());
  v3::MeshInfo mesh;
  ASSERT_TRUE(stub_->BuildMesh(Context(kAlice).get(), build, &mesh).ok());
  EXPECT_TRUE(IsRandomId(mesh.mesh_id(), "mesh-")) << mesh.mesh_id();
  v3::GetMeshRequest get_mesh;
  v3::GetMeshResponse got_mesh;
  get_mesh.set_mesh_id(kMadeUpMesh);
  const grpc::Status missing_mesh = stub_->GetMesh(Context(kBob).get(), get_mesh, &got_mesh);
  get_mesh.set_mesh_id(mesh.mesh_id());
  ExpectSameAsMissing(stub_->GetMesh(Context(kBob).get(), get_mesh, &got_mesh), missing_mesh);
  v3::DeleteMeshRequest delete_mesh;
  v3::DeleteMeshResponse deleted_mesh;
  delete_mesh.set_mesh_id(kMadeUpMesh);
  const grpc::Status missing_mesh_delete =
      stub_->DeleteMesh(Context(kBob).get(), delete_mesh, &deleted_mesh);
  delete_mesh.set_mesh_id(mesh.mesh_id());
  ExpectSameAsMissing(stub_->DeleteMesh(Context(kBob).get(), delete_mesh, &deleted_mesh),
                      missing_mesh_delete);
  v3::OpenSessionRequest open;
  v3::SessionInfo session;
  open.set_mesh_id(mesh.mesh_id());
  ExpectSameAsMissing(stub_->OpenSession(Context(kBob).get(), open, &session), missing_mesh);
}

// A load's progress id is its user's: Bob polling Alice's id gets what an
// id nobody used gets, and may use the same id for a load of his own.
TEST_F(UsersTest, LoadProgressIdsArePerUser) {
  v3::LoadVolumeRequest load;
  load.set_source(kPhantom);
  load.set_progress_id("shared-id");
  v3::VolumeInfo info;
  ASSERT_TRUE(stub_->LoadVolume(Context(kAlice).get(), load, &info).ok());
  v3::GetLoadProgressRequest poll;
  v3::LoadProgress progress;
  poll.set_progress_id("shared-id");
  ASSERT_TRUE(stub_->GetLoadProgress(Context(kAlice).get(), poll, &progress).ok());
  EXPECT_TRUE(progress.done());
  const grpc::Status bobs = stub_->GetLoadProgress(Context(kBob).get(), poll, &progress);
  poll.set_progress_id("never-used");
  const grpc::Status missing = stub_->GetLoadProgress(Context(kBob).get(), poll, &progress);
  EXPECT_EQ(bobs.error_code(), grpc::NOT_FOUND);
  EXPECT_EQ(missing.error_code(), grpc::NOT_FOUND);
  std::string expected = missing.error_message();  // the same text, naming his id
  expected.replace(expected.find("never-used"), 10, "shared-id");
  EXPECT_EQ(bobs.error_message(), expected);
  ASSERT_TRUE(stub_->LoadVolume(Context(kBob).get(), load, &info).ok());
}

TEST_F(UsersTest, SharedVolumesAreReadByAllAndDeletedOnlyByTheirSoleLoader) {
  const v3::VolumeInfo by_alice = LoadPhantom(kPhantom, kAlice);
  EXPECT_EQ(by_alice.owner(), "");
  // Bob reads and uses it without loading it...
  v3::GetVolumeRequest get;
  get.set_volume_id(by_alice.volume_id());
  v3::VolumeInfo info;
  EXPECT_TRUE(stub_->GetVolume(Context(kBob).get(), get, &info).ok());
  const v3::SessionInfo bobs = OpenSession(by_alice.volume_id(), kBob);
  EXPECT_EQ(bobs.owner(), "bob");
  v3::CloseSessionRequest close;
  close.set_session_id(bobs.session_id());
  v3::CloseSessionResponse closed;
  ASSERT_TRUE(stub_->CloseSession(Context(kBob).get(), close, &closed).ok());
  // ...but may not delete what he did not load.
  v3::DeleteVolumeRequest del;
  del.set_volume_id(by_alice.volume_id());
  v3::DeleteVolumeResponse deleted;
  EXPECT_EQ(stub_->DeleteVolume(Context(kBob).get(), del, &deleted).error_code(),
            grpc::PERMISSION_DENIED);
  // Once Bob loads it too, neither may delete it alone.
  const v3::VolumeInfo by_bob = LoadPhantom(kPhantom, kBob);
  EXPECT_EQ(by_bob.volume_id(), by_alice.volume_id());
  EXPECT_EQ(stub_->DeleteVolume(Context(kAlice).get(), del, &deleted).error_code(),
            grpc::PERMISSION_DENIED);
  // A phantom Carol alone loaded is hers to delete.
  const v3::VolumeInfo by_carol = LoadPhantom("phantom:abdomen?size=40", kCarol);
  del.set_volume_id(by_carol.volume_id());
  EXPECT_TRUE(stub_->DeleteVolume(Context(kCarol).get(), del, &deleted).ok());
}

TEST_F(UsersTest, StreamCapIsPerUser) {
  const v3::VolumeInfo volume = LoadPhantom(kPhantom, kAlice);
  const v3::SessionInfo alices = OpenSession(volume.volume_id(), kAlice);
  const v3::SessionInfo bobs = OpenSession(volume.volume_id(), kBob);
  // Alice fills her two stream slots (every user here shares one address).
  std::vector<std::unique_ptr<grpc::ClientContext>> contexts;
  std::vector<std::unique_ptr<grpc::ClientReader<v3::Frame>>> readers;
  v3::WatchRequest request;
  request.set_session_id(alices.session_id());
  request.mutable_settings()->set_width(64);
  request.mutable_settings()->set_height(64);
  for (int i = 0; i < 2; ++i) {
    contexts.push_back(Context(kAlice));
    readers.push_back(stub_->Watch(contexts.back().get(), request));
    v3::Frame frame;
    ASSERT_TRUE(readers.back()->Read(&frame));
  }
  EXPECT_EQ(Watch(kAlice, alices.session_id()).error_code(), grpc::RESOURCE_EXHAUSTED);
  // An upload is a stream of its user too.
  const std::vector<uint8_t> nifti = NiftiBytes();
  const std::string sha = Sha256::HexOf(nifti);
  v3::VolumeInfo uploaded;
  const grpc::Status refused = Upload(nifti, int64_t(nifti.size()), sha, 64 << 10,
                                      &uploaded, true, kAlice);
  EXPECT_EQ(refused.error_code(), grpc::RESOURCE_EXHAUSTED) << refused.error_message();
  // Bob's streams are counted apart.
  EXPECT_TRUE(Watch(kBob, bobs.session_id()).ok());
  const grpc::Status bobs_upload = Upload(nifti, int64_t(nifti.size()), sha,
                                          64 << 10, &uploaded, true, kBob);
  EXPECT_TRUE(bobs_upload.ok()) << bobs_upload.error_message();
  const std::string metrics = server_->metrics().Scrape();
  EXPECT_NE(metrics.find("vpm_user_streams{user=\"alice\"} 2"), std::string::npos) << metrics;
  for (size_t i = 0; i < readers.size(); ++i) {
    contexts[i]->TryCancel();
    readers[i]->Finish();
  }
}

// Fair shares are per user: a burst of Alice's Render calls fills her lane
// of the render pool, and Bob's one call is taken in turn with it, not after
// it. Counted, not timed: how many of Alice's calls finished while Bob's
// waited (all those still queued with one queue for everybody; the few in
// the workers' hands with a lane per user).
TEST_F(UsersTest, OneUsersRenderBurstDoesNotQueueAnotherUser) {
  const v3::VolumeInfo volume = LoadPhantom(kPhantom, kAlice);
  const v3::SessionInfo alices = OpenSession(volume.volume_id(), kAlice);
  const v3::SessionInfo bobs = OpenSession(volume.volume_id(), kBob);
  v3::RenderRequest request;
  request.mutable_settings()->set_width(512);
  request.mutable_settings()->set_height(512);
  request.set_session_id(alices.session_id());
  constexpr int kBurst = 40;  // under the lane cap of 64
  std::atomic<int> alice_done{0}, alice_ok{0};
  std::vector<std::unique_ptr<grpc::ClientContext>> contexts;
  std::vector<v3::Frame> frames(kBurst);
  for (int i = 0; i < kBurst; ++i) {
    contexts.push_back(Context(kAlice));
    stub_->async()->Render(contexts.back().get(), &request, &frames[i],
                           [&](grpc::Status status) {
                             alice_ok += status.ok();
                             ++alice_done;
                           });
  }
  // Her calls are queued once the first has come back.
  while (alice_done == 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  request.set_session_id(bobs.session_id());
  v3::Frame bobs_frame;
  const int done_when_bob_asked = alice_done.load();
  const grpc::Status bob = stub_->Render(Context(kBob).get(), request, &bobs_frame);
  const int done_when_bob_got = alice_done.load();
  ASSERT_TRUE(bob.ok()) << bob.error_message();
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (alice_done < kBurst && std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  std::printf("Alice's renders finished: %d of %d when Bob asked, %d when he got his frame\n",
              done_when_bob_asked, kBurst, done_when_bob_got);
  EXPECT_EQ(alice_ok.load(), kBurst);
  ASSERT_LE(done_when_bob_asked, kBurst / 2) << "the burst ran out before Bob asked: no test";
  EXPECT_LE(done_when_bob_got - done_when_bob_asked, 6);
}

TEST_F(UsersTest, SessionCapIsPerUser) {
  server_->Shutdown(std::chrono::milliseconds(2000));
  ServerOptions o = SmallServerOptions();
  o.token.clear();
  o.users_file = users_file_;
  o.max_sessions = 6;
  o.max_sessions_per_user = 2;
  StartServer(o);
  const v3::VolumeInfo volume = LoadPhantom(kPhantom, kAlice);
  OpenSession(volume.volume_id(), kAlice);
  OpenSession(volume.volume_id(), kAlice);
  v3::OpenSessionRequest open;
  open.set_volume_id(volume.volume_id());
  v3::SessionInfo info;
  grpc::Status third = stub_->OpenSession(Context(kAlice).get(), open, &info);
  EXPECT_EQ(third.error_code(), grpc::RESOURCE_EXHAUSTED);
  EXPECT_NE(third.error_message().find("per user"), std::string::npos) << third.error_message();
  EXPECT_TRUE(stub_->OpenSession(Context(kBob).get(), open, &info).ok());
}

// One user at their caps leaves the others room only while each per-user
// cap is below its server-wide one: vpm-server warns at start otherwise.
TEST(UsersServer, WarnsOfPerUserCapsNotBelowTheServers) {
  EXPECT_TRUE(FairShareWarnings(ServerOptions{}).empty());
  ServerOptions options;
  options.max_volumes = 4;
  options.max_volumes_per_user = 4;
  options.max_meshes = 8;
  options.max_meshes_per_user = 16;
  const std::vector<std::string> warnings = FairShareWarnings(options);
  ASSERT_EQ(warnings.size(), 2u);
  EXPECT_NE(warnings[0].find("--max-volumes-per-user 4 is not below --max-volumes 4"),
            std::string::npos)
      << warnings[0];
  EXPECT_NE(warnings[1].find("--max-meshes-per-user"), std::string::npos) << warnings[1];
}

TEST(UsersServer, StartupErrorsAreClear) {
  const fs::path dir = fs::temp_directory_path() / ("vpm-users-start-" + std::to_string(getpid()));
  fs::create_directories(dir);
  auto start = [&](ServerOptions o) { return VpmServer::Create(o, SharedGpu()).status(); };
  ServerOptions o = SmallServerOptions();
  o.token.clear();

  o.users_file = WriteFile(dir / "bad.txt", "alice " + HashToken(kAlice) + "\nbob not-a-hash\n");
  Status bad = start(o);
  EXPECT_EQ(bad.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(bad.message().find("line 2"), std::string::npos) << bad;

  o.users_file = (dir / "missing.txt").string();
  EXPECT_NE(start(o).message().find("cannot read"), std::string::npos);

  o.users_file = WriteFile(dir / "users.txt", "alice " + HashToken(kAlice) + "\n");
  o.no_auth = true;
  EXPECT_NE(start(o).message().find("--no-auth and --users"), std::string::npos);
  o.no_auth = false;

  o.token = kAlice;  // the default user may not reuse a user's token
  EXPECT_NE(start(o).message().find("token of user 'alice'"), std::string::npos);
  o.token.clear();

  o.users_file.clear();
  o.token_file = WriteFile(dir / "empty-token", " \n");
  EXPECT_NE(start(o).message().find("empty"), std::string::npos);
  o.token_file = WriteFile(dir / "token", "file-token\n");
  o.token = "also-given";
  EXPECT_NE(start(o).message().find("not both"), std::string::npos);
  fs::remove_all(dir);
}

TEST(UsersServer, TokenFileGivesTheDefaultUsersToken) {
  const fs::path dir = fs::temp_directory_path() / ("vpm-token-file-" + std::to_string(getpid()));
  fs::create_directories(dir);
  ServerOptions o = SmallServerOptions();
  o.token.clear();
  o.token_file = WriteFile(dir / "token", "  file-token\n");
  auto server = VpmServer::Create(o, SharedGpu());
  ASSERT_TRUE(server.ok()) << server.status();
  auto stub = v3::Vpm::NewStub(grpc::CreateChannel(
      "127.0.0.1:" + std::to_string((*server)->port()), grpc::InsecureChannelCredentials()));
  v3::ListVolumesResponse response;
  auto context = [](const std::string& token) {
    auto c = std::make_unique<grpc::ClientContext>();
    c->AddMetadata("authorization", "Bearer " + token);
    return c;
  };
  EXPECT_TRUE(stub->ListVolumes(context("file-token").get(), {}, &response).ok());
  EXPECT_EQ(stub->ListVolumes(context("  file-token").get(), {}, &response).error_code(),
            grpc::UNAUTHENTICATED);
  EXPECT_EQ((*server)->metrics().requests("ListVolumes", "OK", "default"), 1);
  (*server)->Shutdown(std::chrono::milliseconds(1000));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace vpm::service::testing
