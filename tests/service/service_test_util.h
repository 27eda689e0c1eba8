// An in-process vpm-server on 127.0.0.1 with an ephemeral port, a stub that
// carries the token, and small helpers shared by the service tests. The
// phantom is kept small (48^3) so that meshes and frames are quick on
// lavapipe.
#pragma once

#include <chrono>
#include <filesystem>
#include <memory>
#include <string>

#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include "server/io/read_volume.h"
#include "server/io/write_nifti.h"
#include "server/service/vpm_server.h"
#include "vpm/v2/vpm.grpc.pb.h"

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
  o.max_frame_side = 512;
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

class ServiceTest : public ::testing::Test {
 protected:
  void StartServer(const ServerOptions& options) {
    auto server = VpmServer::Create(options, SharedGpu());
    ASSERT_TRUE(server.ok()) << server.status();
    server_ = *std::move(server);
    channel_ = grpc::CreateChannel("127.0.0.1:" + std::to_string(server_->port()),
                                   grpc::InsecureChannelCredentials());
    stub_ = v2::Vpm::NewStub(channel_);
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

  v2::VolumeInfo LoadPhantom(const std::string& source = kPhantom,
                             const std::string& token = kToken) {
    v2::LoadVolumeRequest request;
    request.set_source(source);
    v2::VolumeInfo info;
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
                      size_t chunk, v2::VolumeInfo* info, bool header = true,
                      const std::string& token = kToken) {
    auto context = Context(token);
    auto writer = stub_->UploadVolume(context.get(), info);
    if (header) {
      v2::UploadVolumeRequest h;
      h.mutable_header()->set_file_name("case.nii");
      h.mutable_header()->set_total_bytes(declared);
      h.mutable_header()->set_sha256_hex(sha);
      if (!writer->Write(h)) return writer->Finish();
    }
    for (size_t at = 0; at < bytes.size(); at += chunk) {
      v2::UploadVolumeRequest c;
      c.set_chunk(bytes.data() + at, std::min(chunk, bytes.size() - at));
      if (!writer->Write(c)) break;
    }
    writer->WritesDone();
    return writer->Finish();
  }

  v2::SessionInfo OpenSession(const std::string& volume_id, const std::string& token = kToken) {
    v2::OpenSessionRequest request;
    request.set_volume_id(volume_id);
    v2::SessionInfo info;
    auto context = Context(token);
    grpc::Status status = stub_->OpenSession(context.get(), request, &info);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return info;
  }

  static v2::Vec3 V(double x, double y, double z) {
    v2::Vec3 v;
    v.set_x(x);
    v.set_y(y);
    v.set_z(z);
    return v;
  }

  // The middle of the volume in physical voxel space (mm).
  static v2::Vec3 Centre(const v2::VolumeInfo& info) {
    return V((info.dims(0) - 1) * info.spacing_mm().x() / 2,
             (info.dims(1) - 1) * info.spacing_mm().y() / 2,
             (info.dims(2) - 1) * info.spacing_mm().z() / 2);
  }

  std::unique_ptr<VpmServer> server_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v2::Vpm::Stub> stub_;
};

}  // namespace vpm::service::testing
