// Every message bounded, and the small holes of issue 25 point 9: status
// messages cut to 1 KiB at the gRPC boundary, over-long request strings
// refused before use, a hostile transfer-function token, a NaN grab radius,
// an overflowing drag, file names too long for the file system, a full
// upload spool, and --hash-token's shortest token (users_test.cc).
#include <sys/resource.h>

#include <chrono>
#include <csignal>
#include <cmath>
#include <limits>

#include "server/common/sha256.h"
#include "server/service/grpc_status.h"
#include "tests/service/service_test_util.h"

namespace vpm::service::testing {
namespace {

using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

TEST(BoundedStatusMessage, CutsAtOneKibibyteOnACharacterBoundary) {
  EXPECT_EQ(BoundedStatusMessage("short"), "short");
  const std::string huge(70000, 'x');
  const std::string cut = BoundedStatusMessage(huge);
  EXPECT_LE(cut.size(), kMaxStatusMessageBytes);
  EXPECT_NE(cut.find("bytes cut"), std::string::npos) << cut;
  // Two-byte characters (U+00E9): the cut never splits one.
  std::string accents;
  while (accents.size() < 5000) accents += "\xC3\xA9";
  const std::string cut_accents = BoundedStatusMessage("xy" + accents);
  EXPECT_LE(cut_accents.size(), kMaxStatusMessageBytes);
  const size_t dots = cut_accents.find("...");
  ASSERT_NE(dots, std::string::npos);
  EXPECT_EQ(dots % 2, 0u) << "a character was cut in two";  // "xy" + whole pairs
  const grpc::Status status = ToGrpcStatus(absl::NotFoundError(huge));
  EXPECT_EQ(status.error_code(), grpc::NOT_FOUND);
  EXPECT_LE(status.error_message().size(), kMaxStatusMessageBytes);
}

using BoundsTest = ServiceTest;

// Issue 25 case 1 over gRPC: a 70,000-character id used to be echoed into a
// status whose trailers never went out, stalling the whole connection.
TEST_F(BoundsTest, GetSession_HugeIdIsAShortErrorAndTheChannelGoesOn) {
  v3::GetSessionRequest request;
  request.set_session_id(std::string(70000, 'A'));
  v3::SessionInfo info;
  const auto start = Clock::now();
  grpc::Status status = stub_->GetSession(Context(kToken, 10).get(), request, &info);
  EXPECT_LT(SecondsSince(start), 2.0);
  EXPECT_EQ(status.error_code(), grpc::INVALID_ARGUMENT) << status.error_message();
  EXPECT_LE(status.error_message().size(), kMaxStatusMessageBytes);
  EXPECT_NE(status.error_message().find("session_id: 70000 bytes"), std::string::npos)
      << status.error_message();
  EXPECT_EQ(status.error_message().find("AAAAAAAAAA"), std::string::npos);
  // The same channel still answers, at once.
  for (int i = 0; i < 3; ++i) {
    v3::ListVolumesResponse list;
    const auto again = Clock::now();
    EXPECT_TRUE(stub_->ListVolumes(Context(kToken, 10).get(), {}, &list).ok());
    EXPECT_LT(SecondsSince(again), 2.0);
  }
  // Streams check their strings too.
  v3::WatchRequest watch;
  watch.set_session_id(std::string(70000, 'B'));
  auto context = Context(kToken, 10);
  auto reader = stub_->Watch(context.get(), watch);
  v3::Frame frame;
  while (reader->Read(&frame)) {
  }
  grpc::Status watched = reader->Finish();
  EXPECT_EQ(watched.error_code(), grpc::INVALID_ARGUMENT);
  EXPECT_LE(watched.error_message().size(), kMaxStatusMessageBytes);
}

TEST_F(BoundsTest, LongStringsAreRefusedBeforeUse) {
  v3::LoadVolumeRequest load;
  load.set_source(std::string(20000, 'p'));
  v3::VolumeInfo info;
  grpc::Status status = stub_->LoadVolume(Context().get(), load, &info);
  EXPECT_EQ(status.error_code(), grpc::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("source: 20000 bytes"), std::string::npos)
      << status.error_message();
  v3::ShareSessionRequest share;
  share.set_session_id("ses-x");
  share.set_user(std::string(100000, 'u'));
  v3::SessionInfo session;
  status = stub_->ShareSession(Context().get(), share, &session);
  EXPECT_EQ(status.error_code(), grpc::INVALID_ARGUMENT);
  EXPECT_LE(status.error_message().size(), 200u) << status.error_message();
}

// Issue 25 case 1 through the web viewer: a .vp whose opacity line holds a
// 50,000-character token.
TEST_F(BoundsTest, ReadTransferFunction_HugeTokenGivesABoundedMessage) {
  v3::ReadTransferFunctionRequest request;
  request.set_file_name("x.vp");
  request.set_text("1\n0\n0\n0\n0\n1\n2 " + std::string(50000, '%') +
                   " 1\n2 0 1\n4 0 1 1 1\n");
  v3::RenderTransferFunction tf;
  const auto start = Clock::now();
  grpc::Status status = stub_->ReadTransferFunction(Context().get(), request, &tf);
  EXPECT_LT(SecondsSince(start), 2.0);
  EXPECT_EQ(status.error_code(), grpc::INVALID_ARGUMENT);
  EXPECT_LE(status.error_message().size(), 300u) << status.error_message().size();
  EXPECT_NE(status.error_message().find("50000 bytes"), std::string::npos)
      << status.error_message();
  EXPECT_NE(status.error_message().find("not a finite number"), std::string::npos);
}

// ENAMETOOLONG is the request's fault: INVALID_ARGUMENT, never INTERNAL.
TEST_F(BoundsTest, Upload_FileNameTooLongIsInvalidArgument) {
  const std::vector<uint8_t> bytes = NiftiBytes();
  auto context = Context();
  v3::VolumeInfo info;
  auto writer = stub_->UploadVolume(context.get(), &info);
  v3::UploadVolumeRequest header;
  header.mutable_header()->set_file_name(std::string(300, 'n') + ".nii");
  header.mutable_header()->set_total_bytes(int64_t(bytes.size()));
  header.mutable_header()->set_sha256_hex(Sha256::HexOf(bytes));
  writer->Write(header);
  v3::UploadVolumeRequest chunk;
  chunk.set_chunk(bytes.data(), bytes.size());
  writer->Write(chunk);
  writer->WritesDone();
  grpc::Status status = writer->Finish();
  EXPECT_EQ(status.error_code(), grpc::INVALID_ARGUMENT) << status.error_message();
  EXPECT_NE(status.error_message().find("file_name"), std::string::npos);
}

// A full spool is the server's shortage (RESOURCE_EXHAUSTED), not the
// user's malformed file. The spool is made full with RLIMIT_FSIZE: writes
// past 64 KiB fail with EFBIG, as ENOSPC would on a full disk.
TEST_F(BoundsTest, Upload_FullSpoolIsResourceExhausted) {
  const std::vector<uint8_t> bytes = NiftiBytes();
  ASSERT_GT(bytes.size(), 128u << 10);
  std::signal(SIGXFSZ, SIG_IGN);
  rlimit before{};
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &before), 0);
  rlimit small = before;
  small.rlim_cur = 64 << 10;
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &small), 0);
  v3::VolumeInfo info;
  grpc::Status status =
      Upload(bytes, int64_t(bytes.size()), Sha256::HexOf(bytes), 256 << 10, &info);
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &before), 0);
  EXPECT_EQ(status.error_code(), grpc::RESOURCE_EXHAUSTED) << status.error_message();
  EXPECT_NE(status.error_message().find("spool is full"), std::string::npos)
      << status.error_message();
  EXPECT_EQ(status.error_message().find("vpm-upload-"), std::string::npos)
      << status.error_message();
  // With room again, the same upload goes through.
  status = Upload(bytes, int64_t(bytes.size()), Sha256::HexOf(bytes), 256 << 10, &info);
  EXPECT_TRUE(status.ok()) << status.error_message();
}

// A malformed upload names the file as the user sent it, never the
// server's temporary folder.
TEST_F(BoundsTest, Upload_ErrorsDoNotRevealTemporaryPaths) {
  std::vector<uint8_t> bytes = NiftiBytes();
  bytes.resize(bytes.size() / 2);  // truncated
  v3::VolumeInfo info;
  grpc::Status status =
      Upload(bytes, int64_t(bytes.size()), Sha256::HexOf(bytes), 64 << 10, &info);
  EXPECT_EQ(status.error_code(), grpc::INVALID_ARGUMENT) << status.error_message();
  EXPECT_NE(status.error_message().find("case.nii"), std::string::npos) << status.error_message();
  EXPECT_EQ(status.error_message().find("vpm-upload-"), std::string::npos)
      << status.error_message();
  EXPECT_EQ(status.error_message().find(std::filesystem::temp_directory_path().string()),
            std::string::npos)
      << status.error_message();
}

class GrabBoundsTest : public ServiceTest {
 protected:
  void SetUp() override {
    ServiceTest::SetUp();
    volume_ = LoadPhantom();
    session_ = OpenSession(volume_.volume_id());
  }
  grpc::Status Send(const v3::ClientEvent& event) {
    v3::ManipulateRequest request;
    request.set_session_id(session_.session_id());
    *request.mutable_event() = event;
    v3::ManipulateResponse response;
    return stub_->Manipulate(Context().get(), request, &response);
  }
  grpc::Status Grab(double radius_mm) {
    v3::ClientEvent event;
    *event.mutable_grab()->mutable_point_mm() = Centre(volume_);
    event.mutable_grab()->set_radius_mm(radius_mm);
    return Send(event);
  }
  grpc::Status Drag(double dx_mm) {
    v3::ClientEvent event;
    *event.mutable_drag()->mutable_offset_mm() = V(dx_mm, 0, 0);
    return Send(event);
  }
  grpc::Status Pull(double fx_n) {
    v3::ClientEvent event;
    *event.mutable_pull()->mutable_force_n() = V(fx_n, 0, 0);
    return Send(event);
  }
  v3::VolumeInfo volume_;
  v3::SessionInfo session_;
};

TEST_F(GrabBoundsTest, NonFiniteOrHugeGrabRadiusIsInvalidArgument) {
  for (double radius : {std::numeric_limits<double>::quiet_NaN(),
                        std::numeric_limits<double>::infinity(),
                        -std::numeric_limits<double>::infinity(), -1.0, 1e300}) {
    grpc::Status status = Grab(radius);
    EXPECT_EQ(status.error_code(), grpc::INVALID_ARGUMENT) << radius << " " << status.error_message();
    EXPECT_NE(status.error_message().find("grab.radius_mm"), std::string::npos);
  }
  EXPECT_TRUE(Grab(0).ok());
  EXPECT_TRUE(Grab(8).ok());
}

// A drag or pull the model cannot follow is the request's fault.
TEST_F(GrabBoundsTest, OverflowingDragOrPullIsInvalidArgument) {
  ASSERT_TRUE(Grab(0).ok());
  for (double huge : {1e300, 1e30, 1e5}) {
    grpc::Status drag = Drag(huge);
    EXPECT_EQ(drag.error_code(), grpc::INVALID_ARGUMENT) << huge << " " << drag.error_message();
    grpc::Status pull = Pull(huge);
    EXPECT_EQ(pull.error_code(), grpc::INVALID_ARGUMENT) << huge << " " << pull.error_message();
  }
  // The session goes on.
  EXPECT_TRUE(Drag(2.0).ok());
}

}  // namespace
}  // namespace vpm::service::testing
