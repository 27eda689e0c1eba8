// An in-process vpm-server on 127.0.0.1 with an ephemeral port, a stub that
// carries the token, and small helpers shared by the service tests. The
// phantom is kept small (48^3) so that meshes and frames are quick on
// lavapipe.
#pragma once

#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>

#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include "server/io/read_volume.h"
#include "server/io/write_nifti.h"
#include "server/service/vpm_server.h"
#include "vpm/v3/vpm.grpc.pb.h"

namespace vpm::service::testing {

inline constexpr char kToken[] = "test-token";
inline constexpr char kPhantom[] = "phantom:abdomen?size=48";

inline ServerOptions SmallServerOptions() {
  ServerOptions o;
  o.listen = "127.0.0.1:0";
  o.token = kToken;
  o.max_volumes = 4;
  o.max_sessions = 3;
  o.max_streams_per_user = 4;
  o.still_delay_ms = 100;
  // Rungs at rest however fast the still (refine_at_rest_test also sets a
  // minimum).
  o.refine_min_still_ms = 0;
  o.max_frame_side = 512;
  // The mesh stays the one the session opened with, so that a test's
  // frames and displacements do not depend on when a background refinement
  // lands (refine_on_grab_test turns it on).
  o.refine_on_grab = false;
  return o;
}

// One Vulkan context for the whole test process, as in the server.
inline const gpu::GpuContext* SharedGpu() {
  static const gpu::GpuContext* gpu = [] {
    auto context = gpu::GpuContext::Create({});
    EXPECT_TRUE(context.ok()) << context.status();
    return context.ok() ? context->release() : nullptr;
  }();
  return gpu;
}

// tests/data of the source tree (ctest sets VPM_SOURCE_DIR; run by hand,
// this file's own path tells).
inline std::filesystem::path SourceData() {
  const char* source = std::getenv("VPM_SOURCE_DIR");
  return source != nullptr
             ? std::filesystem::path(source) / "tests" / "data"
             : std::filesystem::path(__FILE__).parent_path().parent_path() / "data";
}

// Starts an upload of a `total`-byte file named `file_name`: the header
// only (its checksum is never checked: the upload is not finished).
inline std::unique_ptr<grpc::ClientWriter<v3::UploadVolumeRequest>> StartUpload(
    v3::Vpm::Stub* stub, grpc::ClientContext* context, v3::VolumeInfo* info, int64_t total,
    const std::string& file_name) {
  auto writer = stub->UploadVolume(context, info);
  v3::UploadVolumeRequest header;
  header.mutable_header()->set_file_name(file_name);
  header.mutable_header()->set_total_bytes(total);
  header.mutable_header()->set_sha256_hex(std::string(64, 'a'));
  writer->Write(header);
  return writer;
}

// Sends `bytes` zero bytes of an upload; false once the stream is broken.
inline bool SendChunk(grpc::ClientWriter<v3::UploadVolumeRequest>& writer, int64_t bytes) {
  v3::UploadVolumeRequest chunk;
  chunk.set_chunk(std::string(static_cast<size_t>(bytes), '\0'));
  return writer.Write(chunk);
}

class ServiceTest : public ::testing::Test {
 protected:
  void StartServer(const ServerOptions& options) {
    auto server = VpmServer::Create(options, SharedGpu());
    ASSERT_TRUE(server.ok()) << server.status();
    server_ = *std::move(server);
    channel_ = grpc::CreateChannel("127.0.0.1:" + std::to_string(server_->port()),
                                   grpc::InsecureChannelCredentials());
    stub_ = v3::Vpm::NewStub(channel_);
  }
  void SetUp() override { StartServer(SmallServerOptions()); }
  void TearDown() override {
    if (server_) server_->Shutdown(std::chrono::milliseconds(2000));
  }

  // A client context with the token (or `token` when given) and a deadline.
  static std::unique_ptr<grpc::ClientContext> Context(const std::string& token = kToken,
                                                      int deadline_s = 120) {
    auto context = std::make_unique<grpc::ClientContext>();
    if (!token.empty()) context->AddMetadata("authorization", "Bearer " + token);
    context->set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(deadline_s));
    return context;
  }

  v3::VolumeInfo LoadPhantom(const std::string& source = kPhantom,
                             const std::string& token = kToken) {
    v3::LoadVolumeRequest request;
    request.set_source(source);
    v3::VolumeInfo info;
    auto context = Context(token);
    grpc::Status status = stub_->LoadVolume(context.get(), request, &info);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return info;
  }

  // A NIfTI file of a small phantom, as a client would upload it.
  static std::vector<uint8_t> NiftiBytes() {
    auto volume = ReadVolume("phantom:abdomen?size=40", {});
    EXPECT_TRUE(volume.ok());
    auto bytes = EncodeNifti(*volume);
    EXPECT_TRUE(bytes.ok());
    return *bytes;
  }
  // UploadVolume as `token`'s user: the header, then `bytes` in chunks of
  // `chunk` bytes.
  grpc::Status Upload(const std::vector<uint8_t>& bytes, int64_t declared, const std::string& sha,
                      size_t chunk, v3::VolumeInfo* info, bool header = true,
                      const std::string& token = kToken,
                      const std::string& file_name = "case.nii") {
    auto context = Context(token);
    auto writer = stub_->UploadVolume(context.get(), info);
    if (header) {
      v3::UploadVolumeRequest h;
      h.mutable_header()->set_file_name(file_name);
      h.mutable_header()->set_total_bytes(declared);
      h.mutable_header()->set_sha256_hex(sha);
      if (!writer->Write(h)) return writer->Finish();
    }
    for (size_t at = 0; at < bytes.size(); at += chunk) {
      v3::UploadVolumeRequest c;
      c.set_chunk(bytes.data() + at, std::min(chunk, bytes.size() - at));
      if (!writer->Write(c)) break;
    }
    writer->WritesDone();
    return writer->Finish();
  }

  v3::SessionInfo OpenSession(const std::string& volume_id, const std::string& token = kToken) {
    v3::OpenSessionRequest request;
    request.set_volume_id(volume_id);
    v3::SessionInfo info;
    auto context = Context(token);
    grpc::Status status = stub_->OpenSession(context.get(), request, &info);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return info;
  }

  static v3::Vec3 V(double x, double y, double z) {
    v3::Vec3 v;
    v.set_x(x);
    v.set_y(y);
    v.set_z(z);
    return v;
  }

  // The middle of the volume in physical voxel space (mm).
  // The world point (LPS mm, the API's frame) of physical voxel space point
  // (x, y, z) = index * spacing: origin + direction * p.
  static v3::Vec3 AtPhysical(const v3::VolumeInfo& info, double x, double y, double z) {
    const auto& d = info.direction();
    const double p[3] = {x, y, z};
    double w[3] = {info.origin_lps_mm().x(), info.origin_lps_mm().y(), info.origin_lps_mm().z()};
    for (int c = 0; c < 3; ++c) {
      for (int r = 0; r < 3; ++r) w[r] += d.size() == 9 ? d[3 * c + r] * p[c] : (r == c) * p[c];
    }
    return V(w[0], w[1], w[2]);
  }

  // The centre of the volume's box, world LPS mm (the API's frame): the
  // middle of its world axis-aligned box.
  static v3::Vec3 Centre(const v3::VolumeInfo& info) {
    return V((info.box_lo_lps_mm().x() + info.box_hi_lps_mm().x()) / 2,
             (info.box_lo_lps_mm().y() + info.box_hi_lps_mm().y()) / 2,
             (info.box_lo_lps_mm().z() + info.box_hi_lps_mm().z()) / 2);
  }

  std::unique_ptr<VpmServer> server_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v3::Vpm::Stub> stub_;
};

// A server with the small phantom loaded and a session open on it.
class PhantomSessionTest : public ServiceTest {
 protected:
  void SetUp() override {
    ServiceTest::SetUp();
    volume_ = LoadPhantom();
    session_ = OpenSession(volume_.volume_id());
    ASSERT_FALSE(session_.session_id().empty());
  }
  v3::VolumeInfo volume_;
  v3::SessionInfo session_;
};

}  // namespace vpm::service::testing
