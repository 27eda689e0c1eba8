// Auth, health, reflection, volumes (load, upload, get, list, delete, path
// rules, caps) and meshes.
#include <fstream>
#include <future>

#include <grpcpp/generic/generic_stub.h>

#include "proto/render_tf_convert.h"
#include "server/common/sha256.h"
#include "server/io/read_volume.h"
#include "server/io/write_nifti.h"
#include "server/raycast/render_preset_from_tf.h"
#include "server/service/case_view.h"
#include "server/service/loopback_address.h"
#include "server/service/proto_convert.h"
#include "tests/service/service_test_util.h"

namespace vpm::service::testing {
namespace {

namespace fs = std::filesystem;

grpc::Status GenericUnary(grpc::Channel* channel, const std::string& method,
                          const std::string& request_bytes, std::string* response_bytes) {
  grpc::GenericStub stub(channel->shared_from_this());
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(20));
  grpc::Slice slice(request_bytes);
  grpc::ByteBuffer request(&slice, 1);
  grpc::ByteBuffer response;
  std::promise<grpc::Status> done;
  stub.UnaryCall(&context, method, grpc::StubOptions(), &request, &response,
                 [&](grpc::Status s) { done.set_value(s); });
  grpc::Status status = done.get_future().get();
  std::vector<grpc::Slice> slices;
  if (status.ok() && response.Dump(&slices).ok()) {
    for (const auto& s : slices) response_bytes->append(reinterpret_cast<const char*>(s.begin()), s.size());
  }
  return status;
}

TEST_F(ServiceTest, Auth_RejectsMissingAndWrongToken) {
  v3::ListVolumesRequest request;
  v3::ListVolumesResponse response;
  auto none = Context("");
  EXPECT_EQ(stub_->ListVolumes(none.get(), request, &response).error_code(),
            grpc::UNAUTHENTICATED);
  auto wrong = Context("not-the-token");
  EXPECT_EQ(stub_->ListVolumes(wrong.get(), request, &response).error_code(),
            grpc::UNAUTHENTICATED);
  auto right = Context();
  EXPECT_TRUE(stub_->ListVolumes(right.get(), request, &response).ok());
}

TEST_F(ServiceTest, Health_AnswersServingWithoutToken) {
  std::string response;
  // HealthCheckRequest{service: ""} is empty; HealthCheckResponse{SERVING} is 08 01.
  grpc::Status status =
      GenericUnary(channel_.get(), "/grpc.health.v1.Health/Check", "", &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(response, std::string("\x08\x01", 2));
}

TEST_F(ServiceTest, Health_NotServingWhileDraining) {
  server_->context().draining = true;
  server_->Shutdown(std::chrono::milliseconds(100));
  std::string response;
  grpc::Status status =
      GenericUnary(channel_.get(), "/grpc.health.v1.Health/Check", "", &response);
  // Once drained the port is closed: either NOT_SERVING or unavailable.
  EXPECT_TRUE(!status.ok() || response == std::string("\x08\x02", 2));
  server_.reset();
}

TEST_F(ServiceTest, Reflection_ListsTheServiceWithoutToken) {
  grpc::GenericStub stub(channel_);
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(20));
  grpc::CompletionQueue cq;
  auto call = stub.PrepareCall(&context, "/grpc.reflection.v1alpha.ServerReflection/ServerReflectionInfo", &cq);
  void* tag = nullptr;
  bool ok = false;
  call->StartCall(reinterpret_cast<void*>(1));
  ASSERT_TRUE(cq.Next(&tag, &ok) && ok);
  // ServerReflectionRequest{list_services: ""}: field 7, length 0.
  grpc::Slice slice(std::string("\x3a\x00", 2));
  grpc::ByteBuffer request(&slice, 1);
  call->Write(request, reinterpret_cast<void*>(2));
  ASSERT_TRUE(cq.Next(&tag, &ok) && ok);
  grpc::ByteBuffer response;
  call->Read(&response, reinterpret_cast<void*>(3));
  ASSERT_TRUE(cq.Next(&tag, &ok) && ok);
  std::vector<grpc::Slice> slices;
  ASSERT_TRUE(response.Dump(&slices).ok());
  std::string bytes;
  for (const auto& s : slices) bytes.append(reinterpret_cast<const char*>(s.begin()), s.size());
  EXPECT_NE(bytes.find("vpm.v3.Vpm"), std::string::npos);
  context.TryCancel();
  grpc::Status status;
  call->Finish(&status, reinterpret_cast<void*>(4));
  cq.Next(&tag, &ok);
  cq.Shutdown();
  while (cq.Next(&tag, &ok)) {
  }
}

TEST_F(ServiceTest, Volumes_LoadGetListDelete) {
  v3::VolumeInfo info = LoadPhantom();
  ASSERT_EQ(info.dims_size(), 3);
  EXPECT_EQ(info.dims(0), 48);
  EXPECT_GT(info.landmarks_size(), 0);
  EXPECT_LT(info.min_value(), info.max_value());
  EXPECT_EQ(info.direction_size(), 9);

  v3::GetVolumeRequest get;
  get.set_volume_id(info.volume_id());
  v3::VolumeInfo got;
  auto c1 = Context();
  ASSERT_TRUE(stub_->GetVolume(c1.get(), get, &got).ok());
  EXPECT_EQ(got.source(), kPhantom);

  v3::ListVolumesResponse list;
  auto c2 = Context();
  ASSERT_TRUE(stub_->ListVolumes(c2.get(), {}, &list).ok());
  EXPECT_EQ(list.volumes_size(), 1);

  v3::DeleteVolumeRequest del;
  del.set_volume_id(info.volume_id());
  v3::DeleteVolumeResponse deleted;
  auto c3 = Context();
  ASSERT_TRUE(stub_->DeleteVolume(c3.get(), del, &deleted).ok());
  auto c4 = Context();
  EXPECT_EQ(stub_->GetVolume(c4.get(), get, &got).error_code(), grpc::NOT_FOUND);
  auto c5 = Context();
  EXPECT_EQ(stub_->DeleteVolume(c5.get(), del, &deleted).error_code(), grpc::NOT_FOUND);
}

TEST_F(ServiceTest, Volumes_LoadedOnceAndShared) {
  const v3::VolumeInfo first = LoadPhantom();
  const v3::VolumeInfo again = LoadPhantom();
  EXPECT_EQ(again.volume_id(), first.volume_id());
  const v3::VolumeInfo other = LoadPhantom(std::string(kPhantom) + "&seed=2");
  EXPECT_NE(other.volume_id(), first.volume_id());
  v3::ListVolumesResponse list;
  auto context = Context();
  ASSERT_TRUE(stub_->ListVolumes(context.get(), v3::ListVolumesRequest(), &list).ok());
  EXPECT_EQ(list.volumes_size(), 2);
}

// At the volume cap an idle volume is evicted to make room (a volume in use
// never is: resource_lifecycle_test.cc).
TEST_F(ServiceTest, Volumes_CapEvictsAnIdleVolume) {
  // Distinct sources (seeds): the same source twice is one volume.
  for (int i = 0; i < 4; ++i) {
    LoadPhantom(std::string(kPhantom) + "&seed=" + std::to_string(i + 1));
  }
  v3::LoadVolumeRequest request;
  request.set_source(std::string(kPhantom) + "&seed=99");
  v3::VolumeInfo info;
  auto context = Context();
  EXPECT_TRUE(stub_->LoadVolume(context.get(), request, &info).ok());
  EXPECT_EQ(server_->metrics().volumes_evicted(), 1.0);
}

TEST_F(ServiceTest, Volumes_BadSourceIsInvalidArgument) {
  for (const char* source : {"", "phantom:nosuchthing", "raw:/etc/passwd?dims=1,1,1&type=uint8"}) {
    v3::LoadVolumeRequest request;
    request.set_source(source);
    v3::VolumeInfo info;
    auto context = Context();
    EXPECT_EQ(stub_->LoadVolume(context.get(), request, &info).error_code(),
              grpc::INVALID_ARGUMENT)
        << source;
  }
}

class DataRootTest : public ServiceTest {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() / ("vpm-data-root-" + std::to_string(::getpid()));
    outside_ = fs::temp_directory_path() / ("vpm-outside-" + std::to_string(::getpid()));
    fs::remove_all(root_);
    fs::remove_all(outside_);
    fs::create_directories(root_ / "cases");
    fs::create_directories(outside_);
    auto volume = ReadVolume("phantom:abdomen?size=24", {});
    ASSERT_TRUE(volume.ok());
    ASSERT_TRUE(WriteNifti(*volume, root_ / "cases" / "small.nii.gz").ok());
    ASSERT_TRUE(WriteNifti(*volume, outside_ / "secret.nii.gz").ok());
    fs::create_symlink(outside_ / "secret.nii.gz", root_ / "cases" / "escape.nii.gz");
    fs::create_directory_symlink(outside_, root_ / "outdir");
    ServerOptions options = SmallServerOptions();
    options.data_root = root_.string();
    StartServer(options);
  }
  void TearDown() override {
    ServiceTest::TearDown();
    fs::remove_all(root_);
    fs::remove_all(outside_);
  }
  grpc::StatusCode Load(const std::string& source) {
    v3::LoadVolumeRequest request;
    request.set_source(source);
    v3::VolumeInfo info;
    auto context = Context();
    return stub_->LoadVolume(context.get(), request, &info).error_code();
  }
  fs::path root_, outside_;
};

TEST_F(DataRootTest, LoadVolume_ReadsInsideTheRoot) {
  EXPECT_EQ(Load("cases/small.nii.gz"), grpc::OK);
  // Another spelling of the same file is the same volume.
  EXPECT_EQ(Load("cases/./small.nii.gz"), grpc::OK);
  v3::ListVolumesResponse list;
  auto context = Context();
  ASSERT_TRUE(stub_->ListVolumes(context.get(), v3::ListVolumesRequest(), &list).ok());
  EXPECT_EQ(list.volumes_size(), 1);
}

// What the reader corrected reaches the client: the repo's real tilted CT
// series (tests/data/ct-philips-tilt) says it was resampled.
TEST_F(ServiceTest, LoadVolume_ReportsTheReadersCorrections) {
  server_->Shutdown(std::chrono::milliseconds(2000));
  ServerOptions options = SmallServerOptions();
  options.data_root = SourceData().string();
  StartServer(options);
  const v3::VolumeInfo info = LoadPhantom("ct-philips-tilt");
  std::string notes;
  for (const std::string& note : info.notes()) notes += note + "\n";
  EXPECT_NE(notes.find("gantry tilt 18.5 deg"), std::string::npos) << notes;
  EXPECT_NE(notes.find("resampled"), std::string::npos) << notes;
  v3::GetVolumeRequest get;
  get.set_volume_id(info.volume_id());
  v3::VolumeInfo again;
  ASSERT_TRUE(stub_->GetVolume(Context().get(), get, &again).ok());
  EXPECT_EQ(again.notes_size(), info.notes_size());
  // A phantom has nothing to report.
  EXPECT_EQ(LoadPhantom().notes_size(), 0);
}

TEST_F(DataRootTest, LoadVolume_RefusesTraversalAndSymlinkEscape) {
  EXPECT_EQ(Load("../vpm-outside-" + std::to_string(::getpid()) + "/secret.nii.gz"),
            grpc::INVALID_ARGUMENT);
  EXPECT_EQ(Load("cases/../../etc/passwd"), grpc::INVALID_ARGUMENT);
  EXPECT_EQ(Load((outside_ / "secret.nii.gz").string()), grpc::INVALID_ARGUMENT);
  EXPECT_EQ(Load("cases/escape.nii.gz"), grpc::PERMISSION_DENIED);
  EXPECT_EQ(Load("outdir/secret.nii.gz"), grpc::PERMISSION_DENIED);
  EXPECT_EQ(Load("cases/missing.nii.gz"), grpc::NOT_FOUND);
}

using UploadTest = ServiceTest;

TEST_F(UploadTest, UploadVolume_AcceptsChunkedFileWithChecksum) {
  const std::vector<uint8_t> bytes = NiftiBytes();
  v3::VolumeInfo info;
  grpc::Status status = Upload(bytes, int64_t(bytes.size()), Sha256::HexOf(bytes), 64 << 10, &info);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(info.dims(0), 40);
  EXPECT_EQ(info.source(), "upload:case.nii");
}

TEST_F(UploadTest, UploadVolume_RejectsChecksumMismatch) {
  const std::vector<uint8_t> bytes = NiftiBytes();
  std::string wrong(64, 'a');
  v3::VolumeInfo info;
  grpc::Status status = Upload(bytes, int64_t(bytes.size()), wrong, 64 << 10, &info);
  EXPECT_EQ(status.error_code(), grpc::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("sha256"), std::string::npos) << status.error_message();
}

TEST_F(UploadTest, UploadVolume_RejectsTruncatedStream) {
  std::vector<uint8_t> bytes = NiftiBytes();
  const std::string sha = Sha256::HexOf(bytes);
  const int64_t declared = int64_t(bytes.size());
  bytes.resize(bytes.size() / 2 / (64 << 10) * (64 << 10));
  v3::VolumeInfo info;
  grpc::Status status = Upload(bytes, declared, sha, 64 << 10, &info);
  EXPECT_EQ(status.error_code(), grpc::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("truncated"), std::string::npos) << status.error_message();
}

TEST_F(UploadTest, UploadVolume_RejectsBadChunksAndMissingHeader) {
  const std::vector<uint8_t> bytes = NiftiBytes();
  const std::string sha = Sha256::HexOf(bytes);
  v3::VolumeInfo info;
  EXPECT_EQ(Upload(bytes, int64_t(bytes.size()), sha, 1000, &info).error_code(),
            grpc::INVALID_ARGUMENT);  // under 64 KiB and not the last
  const std::vector<uint8_t> big(3 << 20, 0);
  EXPECT_EQ(Upload(big, int64_t(big.size()), Sha256::HexOf(big), 2 << 20, &info).error_code(),
            grpc::INVALID_ARGUMENT);  // over 1 MiB
  EXPECT_EQ(Upload(bytes, 100, sha, 64 << 10, &info).error_code(),
            grpc::INVALID_ARGUMENT);  // more than declared
  EXPECT_EQ(Upload(bytes, int64_t(bytes.size()), sha, 64 << 10, &info, false).error_code(),
            grpc::INVALID_ARGUMENT);  // no header
}

TEST_F(ServiceTest, Meshes_BuildGetRefine) {
  v3::VolumeInfo volume = LoadPhantom();
  v3::BuildMeshRequest build;
  build.set_volume_id(volume.volume_id());
  build.mutable_params()->add_grid(10);
  build.mutable_params()->add_grid(10);
  build.mutable_params()->add_grid(10);
  build.mutable_params()->set_target(80);
  v3::MeshInfo mesh;
  auto c1 = Context();
  grpc::Status status = stub_->BuildMesh(c1.get(), build, &mesh);
  ASSERT_TRUE(status.ok()) << status.error_message();
  // The target counts steps 1-4; boundary vertices (on the box faces) and
  // Steiner points (against slivers) come on top.
  EXPECT_EQ(mesh.stats().vertices(), 80 + mesh.stats().boundary() + mesh.stats().steiner());
  EXPECT_GT(mesh.stats().tets(), 0);

  v3::GetMeshRequest get;
  get.set_mesh_id(mesh.mesh_id());
  get.set_include_geometry(true);
  v3::GetMeshResponse got;
  auto c2 = Context();
  ASSERT_TRUE(stub_->GetMesh(c2.get(), get, &got).ok());
  EXPECT_EQ(got.vertices_size(), mesh.stats().vertices());
  EXPECT_EQ(got.tets_size(), mesh.stats().tets());

  v3::RefineMeshRequest refine;
  refine.set_mesh_id(mesh.mesh_id());
  *refine.mutable_point_mm() = Centre(volume);
  v3::MeshInfo refined;
  auto c3 = Context();
  status = stub_->RefineMesh(c3.get(), refine, &refined);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_NE(refined.mesh_id(), mesh.mesh_id());
  EXPECT_GT(refined.stats().refined(), 0);

  *refine.mutable_point_mm() = AtPhysical(volume, -50, 0, 0);
  auto c4 = Context();
  EXPECT_EQ(stub_->RefineMesh(c4.get(), refine, &refined).error_code(), grpc::OUT_OF_RANGE);
  refine.set_mesh_id("mesh-404");
  auto c5 = Context();
  EXPECT_EQ(stub_->RefineMesh(c5.get(), refine, &refined).error_code(), grpc::NOT_FOUND);
}

TEST_F(ServiceTest, Meshes_BadParamsAreInvalidArgument) {
  v3::VolumeInfo volume = LoadPhantom();
  v3::BuildMeshRequest build;
  build.set_volume_id(volume.volume_id());
  build.mutable_params()->add_grid(10);
  v3::MeshInfo mesh;
  auto c1 = Context();
  grpc::Status status = stub_->BuildMesh(c1.get(), build, &mesh);
  EXPECT_EQ(status.error_code(), grpc::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("params.grid"), std::string::npos);
  build.mutable_params()->clear_grid();
  // An enum value this server does not know (a newer client's) is refused.
  build.mutable_params()->set_footprint(static_cast<v3::Footprint>(7));
  auto c2 = Context();
  status = stub_->BuildMesh(c2.get(), build, &mesh);
  EXPECT_EQ(status.error_code(), grpc::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("params.footprint"), std::string::npos);
  build.mutable_params()->set_footprint(v3::FOOTPRINT_UNSPECIFIED);
  build.set_volume_id("vol-404");
  auto c3 = Context();
  EXPECT_EQ(stub_->BuildMesh(c3.get(), build, &mesh).error_code(), grpc::NOT_FOUND);
}

TEST(LoopbackAddress, OnlyAddressesThatStayOnThisMachine) {
  for (const char* local : {"127.0.0.1:50051", "127.1.2.3:0", "localhost:50051", "[::1]:50051",
                            "[::ffff:127.0.0.1]:1", "unix:/tmp/vpm.sock"}) {
    EXPECT_TRUE(IsLoopbackAddress(local)) << local;
  }
  for (const char* remote : {"0.0.0.0:50051", "[::]:50051", "10.0.0.5:50051", "example.org:50051",
                             "[::ffff:10.0.0.1]:1", "50051", ""}) {
    EXPECT_FALSE(IsLoopbackAddress(remote)) << remote;
  }
}

TEST(ProtoConvert, RenderSettingsEnumsMapAndUnknownValuesAreRefused) {
  auto read = ReadVolume("phantom:abdomen?size=16", VolumeLimits{});
  ASSERT_TRUE(read.ok()) << read.status();
  const Volume& volume = *read;
  v3::RenderSettings settings;
  auto defaults = ToStreamSettings(settings, volume, 1024);
  ASSERT_TRUE(defaults.ok()) << defaults.status();
  EXPECT_EQ(defaults->view.mode, RenderMode::kDvr);
  EXPECT_FALSE(defaults->png);
  settings.set_mode(v3::RENDER_MODE_MIP);
  settings.set_encoding(v3::ENCODING_PNG);
  auto chosen = ToStreamSettings(settings, volume, 1024);
  ASSERT_TRUE(chosen.ok()) << chosen.status();
  EXPECT_EQ(chosen->view.mode, RenderMode::kMip);
  EXPECT_TRUE(chosen->png);
  settings.set_mode(static_cast<v3::RenderMode>(9));
  auto bad_mode = ToStreamSettings(settings, volume, 1024);
  EXPECT_EQ(bad_mode.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(bad_mode.status().message().find("settings.mode"), std::string::npos);
  settings.set_mode(v3::RENDER_MODE_DVR);
  settings.set_encoding(static_cast<v3::Encoding>(5));
  auto bad_encoding = ToStreamSettings(settings, volume, 1024);
  EXPECT_EQ(bad_encoding.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(bad_encoding.status().message().find("settings.encoding"), std::string::npos);
}

// RenderSettings.interactive_quality becomes the view's (and so the
// renderer's: DeformableSceneTest.InteractiveQualityReachesTheRenderer);
// unset is the default; a value outside the enum names the field.
TEST(ProtoConvert, InteractiveQualityReachesTheView) {
  auto read = ReadVolume("phantom:abdomen?size=16", VolumeLimits{});
  ASSERT_TRUE(read.ok()) << read.status();
  v3::RenderSettings settings;
  auto defaults = ToStreamSettings(settings, *read, 1024);
  ASSERT_TRUE(defaults.ok()) << defaults.status();
  EXPECT_EQ(defaults->view.interactive_quality, kDefaultInteractiveQuality);
  for (auto [proto, quality] :
       {std::pair{v3::INTERACTIVE_QUALITY_FAST, InteractiveQuality::kFast},
        std::pair{v3::INTERACTIVE_QUALITY_BALANCED, InteractiveQuality::kBalanced},
        std::pair{v3::INTERACTIVE_QUALITY_SHARP, InteractiveQuality::kSharp}}) {
    settings.set_interactive_quality(proto);
    auto converted = ToStreamSettings(settings, *read, 1024);
    ASSERT_TRUE(converted.ok()) << converted.status();
    EXPECT_EQ(converted->view.interactive_quality, quality);
  }
  settings.set_interactive_quality(static_cast<v3::InteractiveQuality>(9));
  auto bad = ToStreamSettings(settings, *read, 1024);
  EXPECT_EQ(bad.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(bad.status().message().find("settings.interactive_quality"), std::string::npos);
  // Each client's own, like the frame size: not part of a case's view.
  settings.set_interactive_quality(v3::INTERACTIVE_QUALITY_SHARP);
  settings.set_preset("ct-bone");
  const v3::RenderSettings kept = CaseView(settings);
  EXPECT_EQ(kept.interactive_quality(), v3::INTERACTIVE_QUALITY_UNSPECIFIED);
  EXPECT_EQ(kept.preset(), "ct-bone");
}

// RenderSettings.render_tf (a transfer function a client read from a file)
// becomes the frame's preset, round trip through ToProto / FromProto;
// mip_window overrides the volume's window; bad values name the field.
TEST(ProtoConvert, RenderTfAndMipWindowReachTheView) {
  auto read = ReadVolume("phantom:abdomen?size=16", VolumeLimits{});
  ASSERT_TRUE(read.ok()) << read.status();
  const Volume& volume = *read;
  const RenderTransferFunction tf{"mine",
                                  {{-100.0, glm::dvec3(1, 0, 0)}, {300.0, glm::dvec3(1, 1, 1)}},
                                  {{0.0, 0.0}, {300.0, 0.4}},
                                  TfLighting{false, 0.3, 0.7, 0.1, 5.0}};
  EXPECT_EQ(FromProto(ToProto(tf)), tf);
  v3::RenderSettings settings;
  *settings.mutable_render_tf() = ToProto(tf);
  settings.mutable_mip_window()->set_width(500.0);
  settings.mutable_mip_window()->set_level(200.0);
  auto converted = ToStreamSettings(settings, volume, 1024);
  ASSERT_TRUE(converted.ok()) << converted.status();
  auto expected = RenderPresetFromTf(tf, volume);
  ASSERT_TRUE(expected.ok()) << expected.status();
  expected->mip_window = {200.0, 500.0};
  EXPECT_EQ(converted->view.preset, *expected);
  settings.mutable_mip_window()->set_width(0.0);
  auto bad_window = ToStreamSettings(settings, volume, 1024);
  EXPECT_NE(bad_window.status().message().find("settings.mip_window"), std::string::npos);
  settings.clear_mip_window();
  settings.mutable_render_tf()->mutable_opacities(1)->set_value(-500.0);  // unsorted
  auto bad_tf = ToStreamSettings(settings, volume, 1024);
  EXPECT_EQ(bad_tf.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(bad_tf.status().message().find("settings.render_tf"), std::string::npos);
  settings.set_preset("CT-Bone");
  EXPECT_FALSE(ToStreamSettings(settings, volume, 1024).ok());  // both
  settings.clear_render_tf();
  auto slicer = ToStreamSettings(settings, volume, 1024);
  ASSERT_TRUE(slicer.ok()) << slicer.status();
  EXPECT_EQ(slicer->view.preset.name, "CT-Bone");
}

}  // namespace
}  // namespace vpm::service::testing
