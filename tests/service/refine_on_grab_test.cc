// Refinement without asking (issue 26, point 6): a grab where the session's
// mesh is coarse refines it at the grabbed point by itself, built beside the
// running mesh; a later frame swaps it in with the manipulation replayed, so
// the drag goes on on the finer mesh without a jump.
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <thread>

#include "tests/service/service_test_util.h"

namespace vpm::service::testing {
namespace {

class RefineOnGrabTest : public ServiceTest {
 protected:
  void SetUp() override {
    state_dir_ = std::filesystem::temp_directory_path() /
                 ("vpm-refine-cases-" + std::to_string(::getpid()) + "-" +
                  ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(state_dir_);
    StartServer(Options());
    // The real abdominal CT (3 mm voxels), as a surgeon would grab it.
    volume_ = LoadPhantom("ct-abdomen-kidney/ct_abdomen.nii.gz");  // any source
    ASSERT_FALSE(volume_.volume_id().empty());
    session_ = OpenSession(volume_.volume_id());
    ASSERT_FALSE(session_.session_id().empty());
  }
  v3::ManipulateResponse Manipulate(const v3::ClientEvent& event) {
    v3::ManipulateRequest request;
    request.set_session_id(session_.session_id());
    *request.mutable_event() = event;
    v3::ManipulateResponse response;
    auto context = Context();
    const grpc::Status status = stub_->Manipulate(context.get(), request, &response);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return response;
  }
  v3::Frame Still() {
    v3::RenderRequest request;
    request.set_session_id(session_.session_id());
    request.mutable_settings()->set_width(64);
    request.mutable_settings()->set_height(64);
    v3::Frame frame;
    auto context = Context();
    const grpc::Status status = stub_->Render(context.get(), request, &frame);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return frame;
  }
  v3::MeshInfo Mesh(const std::string& id) {
    v3::GetMeshRequest request;
    request.set_mesh_id(id);
    v3::GetMeshResponse response;
    auto context = Context();
    EXPECT_TRUE(stub_->GetMesh(context.get(), request, &response).ok());
    return response.info();
  }
  void TearDown() override {
    ServiceTest::TearDown();
    std::filesystem::remove_all(state_dir_);
  }
  ServerOptions Options() const {
    ServerOptions options = SmallServerOptions();
    options.refine_on_grab = true;  // vpm-server's default
    options.state_dir = state_dir_.string();  // every session is a case
    const char* source = std::getenv("VPM_SOURCE_DIR");
    EXPECT_NE(source, nullptr) << "VPM_SOURCE_DIR: the repository (ctest sets it)";
    options.data_root = std::string(source ? source : ".") + "/tests/data";
    return options;
  }
  // Still frames until one runs on another mesh than `mesh_id` (the
  // refinement swapped in), at most 90 s.
  v3::Frame StillOnAnotherMesh(const std::string& mesh_id) {
    v3::Frame frame = Still();
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(90);
    while (frame.mesh_id() == mesh_id && std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
      frame = Still();
    }
    return frame;
  }
  std::filesystem::path state_dir_;
  v3::VolumeInfo volume_;
  v3::SessionInfo session_;
};

TEST_F(RefineOnGrabTest, AGrabRefinesTheMeshThereAndTheDragGoesOnWithoutAJump) {
  const v3::Frame rest = Still();
  const std::string coarse_id = rest.mesh_id();
  ASSERT_EQ(coarse_id, session_.mesh_id());
  EXPECT_EQ(Mesh(coarse_id).stats().refined(), 0);

  const v3::Vec3 kidney = V(79, -125.3, 358.3);  // the left kidney's centre, world LPS
  v3::ClientEvent grab;
  grab.set_sequence(1);
  *grab.mutable_grab()->mutable_point_mm() = kidney;
  Manipulate(grab);
  v3::ClientEvent drag;
  drag.set_sequence(2);
  *drag.mutable_drag()->mutable_offset_mm() = V(0, 0, 15);  // 15 mm superior, world LPS
  Manipulate(drag);
  const v3::Frame coarse = Still();
  ASSERT_GT(coarse.max_displacement_mm(), 1.0);

  // The refinement runs beside the session; a still frame swaps it in.
  const v3::Frame fine = StillOnAnotherMesh(coarse_id);
  ASSERT_NE(fine.mesh_id(), coarse_id) << "no refined mesh was swapped in within 90 s";
  const v3::MeshInfo refined = Mesh(fine.mesh_id());
  EXPECT_GT(refined.stats().refined(), 0);
  EXPECT_GT(refined.stats().vertices(), Mesh(coarse_id).stats().vertices());

  // The same grab and drag, replayed on the finer mesh: the tissue is where
  // it was (the largest displacement within 25% of the coarse mesh's), the
  // grab still held at the same point, nothing inverted.
  const double jump = std::abs(fine.max_displacement_mm() - coarse.max_displacement_mm());
  std::printf("refine on grab: %lld -> %lld vertices; max displacement %.3f -> %.3f mm\n",
              static_cast<long long>(Mesh(coarse_id).stats().vertices()),
              static_cast<long long>(refined.stats().vertices()), coarse.max_displacement_mm(),
              fine.max_displacement_mm());
  EXPECT_LT(jump, 0.25 * coarse.max_displacement_mm());
  EXPECT_EQ(fine.inverted_tets(), 0);
  ASSERT_TRUE(fine.has_grab_point_mm());
  EXPECT_NEAR(fine.grab_point_mm().z(), kidney.z(), 1e-6);

  // The drag goes on, on the new mesh.
  drag.set_sequence(3);
  *drag.mutable_drag()->mutable_offset_mm() = V(0, 0, 18);
  const v3::ManipulateResponse more = Manipulate(drag);
  EXPECT_GT(more.max_displacement_mm(), fine.max_displacement_mm());
  EXPECT_EQ(Still().mesh_id(), fine.mesh_id());

  // A second grab at the same place asks for nothing new.
  v3::ClientEvent release;
  release.set_sequence(4);
  release.mutable_release();
  Manipulate(release);
  grab.set_sequence(5);
  Manipulate(grab);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  EXPECT_EQ(Still().mesh_id(), fine.mesh_id());
}

// The swap is part of the case: after a restart the case reopens on the
// refined mesh, rebuilt where the swap was, with the same deformation.
TEST_F(RefineOnGrabTest, ACaseReopensOnTheRefinedMeshWithTheSameDeformation) {
  ASSERT_FALSE(session_.case_id().empty());
  const std::string coarse_id = session_.mesh_id();
  v3::ClientEvent grab;
  *grab.mutable_grab()->mutable_point_mm() = V(79, -125.3, 358.3);  // the left kidney
  Manipulate(grab);
  v3::ClientEvent drag;
  *drag.mutable_drag()->mutable_offset_mm() = V(0, 0, 9);
  Manipulate(drag);
  const v3::Frame fine = StillOnAnotherMesh(coarse_id);
  ASSERT_NE(fine.mesh_id(), coarse_id) << "no refined mesh was swapped in within 90 s";
  // More drags after the swap, one left to the bounded steps.
  *drag.mutable_drag()->mutable_offset_mm() = V(0, 0, 15);
  Manipulate(drag);
  *drag.mutable_drag()->mutable_offset_mm() = V(2, 0, 17);
  Manipulate(drag);
  const v3::Frame before = Still();
  ASSERT_GT(before.max_displacement_mm(), 5.0);

  server_->Shutdown(std::chrono::milliseconds(2000));
  server_.reset();
  StartServer(Options());
  v3::OpenCaseRequest open;
  open.set_case_id(session_.case_id());
  v3::SessionInfo reopened;
  const grpc::Status status = stub_->OpenCase(Context().get(), open, &reopened);
  ASSERT_TRUE(status.ok()) << status.error_message();
  session_ = reopened;
  EXPECT_GT(Mesh(reopened.mesh_id()).stats().refined(), 0) << "the case reopened on the coarse mesh";
  const v3::Frame after = Still();
  std::printf("refined case reopened: largest displacement %.6f -> %.6f mm\n",
              before.max_displacement_mm(), after.max_displacement_mm());
  EXPECT_NEAR(after.max_displacement_mm(), before.max_displacement_mm(), 1e-3);
  // Reopened on the refined mesh, the session asks for no new refinement
  // at the same place.
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  EXPECT_EQ(Still().mesh_id(), reopened.mesh_id());
}

}  // namespace
}  // namespace vpm::service::testing
