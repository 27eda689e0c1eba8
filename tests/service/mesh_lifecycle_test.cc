// Meshes on the server do not pile up: an equal BuildMesh or RefineMesh
// returns the held mesh, unpinned meshes are evicted least recently used at
// the cap, a mesh a session uses is pinned, and DeleteMesh frees one.
#include <string>

#include "tests/service/service_test_util.h"

namespace vpm::service::testing {
namespace {

class MeshLifecycleTest : public ServiceTest {
 protected:
  v3::BuildMeshRequest SmallBuild(const std::string& volume_id) {
    v3::BuildMeshRequest build;
    build.set_volume_id(volume_id);
    for (int a = 0; a < 3; ++a) build.mutable_params()->add_grid(8);
    build.mutable_params()->set_target(40);
    return build;
  }
  grpc::Status Build(const v3::BuildMeshRequest& build, v3::MeshInfo* mesh) {
    auto context = Context();
    return stub_->BuildMesh(context.get(), build, mesh);
  }
  grpc::Status Delete(const std::string& mesh_id) {
    v3::DeleteMeshRequest request;
    request.set_mesh_id(mesh_id);
    v3::DeleteMeshResponse response;
    auto context = Context();
    return stub_->DeleteMesh(context.get(), request, &response);
  }
  grpc::Status OpenOn(const v3::VolumeInfo& volume, const std::string& mesh_id,
                      v3::SessionInfo* session) {
    v3::OpenSessionRequest request;
    request.set_volume_id(volume.volume_id());
    request.set_mesh_id(mesh_id);
    auto context = Context();
    return stub_->OpenSession(context.get(), request, session);
  }
  grpc::Status Close(const std::string& session_id) {
    v3::CloseSessionRequest request;
    request.set_session_id(session_id);
    v3::CloseSessionResponse response;
    auto context = Context();
    return stub_->CloseSession(context.get(), request, &response);
  }
};

TEST_F(MeshLifecycleTest, EqualBuildAndRefineReturnTheHeldMesh) {
  const v3::VolumeInfo volume = LoadPhantom();
  const v3::BuildMeshRequest build = SmallBuild(volume.volume_id());
  v3::MeshInfo first, second;
  ASSERT_TRUE(Build(build, &first).ok());
  ASSERT_TRUE(Build(build, &second).ok());
  EXPECT_EQ(first.mesh_id(), second.mesh_id());

  v3::BuildMeshRequest other = build;
  other.mutable_params()->set_target(41);
  v3::MeshInfo third;
  ASSERT_TRUE(Build(other, &third).ok());
  EXPECT_NE(third.mesh_id(), first.mesh_id());

  v3::RefineMeshRequest refine;
  refine.set_mesh_id(first.mesh_id());
  *refine.mutable_point_mm() = AtPhysical(volume, 100, 100, 100);
  v3::MeshInfo refined_a, refined_b;
  auto c1 = Context();
  ASSERT_TRUE(stub_->RefineMesh(c1.get(), refine, &refined_a).ok());
  auto c2 = Context();
  ASSERT_TRUE(stub_->RefineMesh(c2.get(), refine, &refined_b).ok());
  EXPECT_EQ(refined_a.mesh_id(), refined_b.mesh_id());
  EXPECT_NE(refined_a.mesh_id(), first.mesh_id());
}

// 1,000 BuildMesh calls on one volume at the default cap (64 meshes), each
// refined at another point so that every one is a new mesh: none refused,
// the store never over its cap.
TEST_F(MeshLifecycleTest, ThousandBuildsOnOneVolumeAreNeverRefused) {
  const v3::VolumeInfo volume = LoadPhantom();
  v3::BuildMeshRequest build = SmallBuild(volume.volume_id());
  int refused = 0;
  std::string first_id;
  for (int i = 0; i < 1000; ++i) {
    *build.mutable_params()->mutable_refine_at_mm() =
        AtPhysical(volume, 10.0 + (i % 40) * 9.0, 10.0 + (i / 40) * 14.0, 150.0);
    v3::MeshInfo mesh;
    const grpc::Status status = Build(build, &mesh);
    if (i == 0) first_id = mesh.mesh_id();
    if (!status.ok()) {
      ++refused;
      ADD_FAILURE() << "call " << i << ": " << status.error_message();
      if (refused > 3) break;
    }
  }
  EXPECT_EQ(refused, 0);
  // The first mesh, least recently used, was evicted.
  v3::GetMeshRequest get;
  ASSERT_FALSE(first_id.empty());
  get.set_mesh_id(first_id);
  v3::GetMeshResponse got;
  auto context = Context();
  EXPECT_EQ(stub_->GetMesh(context.get(), get, &got).error_code(), grpc::NOT_FOUND);
}

TEST_F(MeshLifecycleTest, PinnedMeshSurvivesEvictionAndRefusesDelete) {
  ServerOptions options = SmallServerOptions();
  options.max_meshes = 2;
  server_->Shutdown(std::chrono::milliseconds(2000));
  StartServer(options);
  const v3::VolumeInfo volume = LoadPhantom();
  v3::BuildMeshRequest build = SmallBuild(volume.volume_id());
  v3::MeshInfo pinned;
  ASSERT_TRUE(Build(build, &pinned).ok());
  v3::SessionInfo session;
  ASSERT_TRUE(OpenOn(volume, pinned.mesh_id(), &session).ok());

  // Two more meshes through a cap of two: the unpinned one goes, the pinned stays.
  v3::MeshInfo b, c;
  build.mutable_params()->set_target(41);
  ASSERT_TRUE(Build(build, &b).ok());
  build.mutable_params()->set_target(42);
  ASSERT_TRUE(Build(build, &c).ok());
  v3::GetMeshRequest get;
  v3::GetMeshResponse got;
  get.set_mesh_id(pinned.mesh_id());
  auto c1 = Context();
  EXPECT_TRUE(stub_->GetMesh(c1.get(), get, &got).ok());
  get.set_mesh_id(b.mesh_id());
  auto c2 = Context();
  EXPECT_EQ(stub_->GetMesh(c2.get(), get, &got).error_code(), grpc::NOT_FOUND);

  const grpc::Status in_use = Delete(pinned.mesh_id());
  EXPECT_EQ(in_use.error_code(), grpc::FAILED_PRECONDITION);
  EXPECT_NE(in_use.error_message().find("session"), std::string::npos) << in_use.error_message();
  EXPECT_EQ(Delete("mesh-404").error_code(), grpc::NOT_FOUND);

  // With the cap held by a pinned mesh and c pinned too, a new mesh is refused,
  // saying what holds the cap.
  v3::SessionInfo second;
  ASSERT_TRUE(OpenOn(volume, c.mesh_id(), &second).ok());
  build.mutable_params()->set_target(43);
  v3::MeshInfo refused;
  const grpc::Status full = Build(build, &refused);
  EXPECT_EQ(full.error_code(), grpc::RESOURCE_EXHAUSTED);
  EXPECT_NE(full.error_message().find("sessions use every one"), std::string::npos)
      << full.error_message();

  // Closing the session unpins: the mesh can go.
  ASSERT_TRUE(Close(session.session_id()).ok());
  EXPECT_TRUE(Delete(pinned.mesh_id()).ok());
  get.set_mesh_id(pinned.mesh_id());
  auto c3 = Context();
  EXPECT_EQ(stub_->GetMesh(c3.get(), get, &got).error_code(), grpc::NOT_FOUND);
  EXPECT_TRUE(Build(build, &refused).ok());
}

}  // namespace
}  // namespace vpm::service::testing
