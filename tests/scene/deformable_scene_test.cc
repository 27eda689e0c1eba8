// The deformable scene's two ways of keeping the backward map: updated at
// every step (offline tools, benchmarks) or deferred to the next frame (the
// server's sessions). Deferring must change when the work happens, never
// the picture: after the same events both scenes show the same frame, and a
// burst of steps costs one map update. Casting a prepared frame while the
// next step's FEM runs must not change either frame.
#include "server/scene/deformable_scene.h"

#include <thread>

#include <gtest/gtest.h>

#include "server/measures/compare_meshes.h"
#include "server/raycast/render_presets.h"
#include "tests/gpu/gpu_test_context.h"
#include "tests/scene/sphere_rod_scene.h"

namespace vpm {
namespace {

class DeformableSceneTest : public testing::GpuTest {
 protected:
  void SetUp() override {
    GpuTest::SetUp();
    auto scene = testing::MakeSphereRodScene(context());
    ASSERT_TRUE(scene.ok()) << scene.status();
    case_ = std::move(*scene);
    auto mesh = BuildRegularMesh(case_->volume, 216);
    ASSERT_TRUE(mesh.ok()) << mesh.status();
    mesh_ = std::move(*mesh);
  }

  // move_tolerance_mm: the interactive map's by default; 0 gives frames
  // that do not depend on how many map updates a drag took.
  std::unique_ptr<DeformableScene> Scene(bool defer, double move_tolerance_mm = -1.0) {
    DeformableScene::Options options;
    options.map.map_dims = {24, 24, 24};
    if (move_tolerance_mm >= 0.0) options.map.move_tolerance_mm = move_tolerance_mm;
    options.defer_map_update = defer;
    auto scene = DeformableScene::Create(context(), case_->volume, case_->gpu_volume,
                                         *case_->renderer, mesh_, options);
    EXPECT_TRUE(scene.ok()) << scene.status();
    return scene.ok() ? std::move(*scene) : nullptr;
  }

  SceneView View() const {
    SceneView view;
    view.camera = Camera::ForVolume(case_->volume.geometry());
    view.camera.Orbit(25.0, 15.0);
    view.preset = *MakeRenderPreset("ct-vessels", case_->volume);
    view.width = view.height = 64;
    return view;
  }

  glm::dvec3 Centre() const { return 0.5 * case_->volume.geometry().extent_mm(); }

  std::unique_ptr<testing::SphereRodScene> case_;
  ProxyMesh mesh_;
};

// The interactive map (move tolerance 0.05 mm) holds the vertices that a
// drag step moves less than that, and its frames stay those of the exact
// map within 1/255 on average and 8/255 at any pixel.
TEST_F(DeformableSceneTest, InteractiveMapToleranceKeepsTheFrames) {
  auto exact = Scene(false, 0.0);
  auto interactive = Scene(false);
  ASSERT_TRUE(exact && interactive);
  int64_t exact_processed = 0, interactive_processed = 0;
  for (DeformableScene* scene : {exact.get(), interactive.get()}) {
    ASSERT_TRUE(scene->Grab(Centre(), 12.0).ok());
    for (int s = 1; s <= 6; ++s) {
      auto step = scene->Drag({0.0, 0.3 * s, 1.0 * s});
      ASSERT_TRUE(step.ok()) << step.status();
      (scene == exact.get() ? exact_processed : interactive_processed) += step->processed_tets;
    }
  }
  EXPECT_LE(interactive_processed, exact_processed);
  auto a = exact->Render(View());
  auto b = interactive->Render(View());
  ASSERT_TRUE(a.ok() && b.ok());
  const auto diff = testing::CompareRgba(a->rgba, b->rgba);
  EXPECT_LE(diff.mean_abs, 1.0 / 255) << "max " << diff.max_abs;
  EXPECT_LE(diff.max_abs, 8.0 / 255) << "mean " << diff.mean_abs;
}

// With an exact map (no move tolerance): one update for three drag steps
// holds vertices where three updates would not, within the tolerance.
TEST_F(DeformableSceneTest, DeferredMapGivesTheSameFramesAsImmediateUpdates) {
  auto immediate = Scene(false, 0.0);
  auto deferred = Scene(true, 0.0);
  ASSERT_TRUE(immediate && deferred);
  auto rest = immediate->Render(View());
  ASSERT_TRUE(rest.ok()) << rest.status();
  for (DeformableScene* scene : {immediate.get(), deferred.get()}) {
    ASSERT_TRUE(scene->Grab(Centre(), 12.0).ok());
    for (double dz : {2.0, 4.0, 6.0}) {
      auto step = scene->Drag({0.0, 1.0, dz});
      ASSERT_TRUE(step.ok()) << step.status();
      // Immediate steps include the map update; deferred ones do not.
      if (scene == immediate.get()) {
        EXPECT_GT(step->warp_ms, 0.0);
      } else {
        EXPECT_EQ(step->warp_ms, 0.0);
      }
    }
  }
  SceneStepTimings immediate_sync, deferred_sync;
  auto a = immediate->Render(View(), &immediate_sync);
  auto b = deferred->Render(View(), &deferred_sync);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_EQ(immediate_sync.warp_ms, 0.0);  // its map was current
  EXPECT_GT(deferred_sync.warp_ms, 0.0);   // one update for the three steps
  EXPECT_GT(deferred_sync.moved_tets, 0);
  const auto moved = testing::CompareRgba(a->rgba, rest->rgba);
  EXPECT_GT(moved.max_abs, 0.1) << "the drag should show in the frame";
  const auto same = testing::CompareRgba(a->rgba, b->rgba);
  EXPECT_EQ(same.max_abs, 0.0) << "mean " << same.mean_abs;

  // A second frame with nothing new needs no update.
  SceneStepTimings again;
  ASSERT_TRUE(deferred->Render(View(), &again).ok());
  EXPECT_EQ(again.warp_ms, 0.0);

  // Release, then a new grab and drag before any frame: one update again.
  for (DeformableScene* scene : {immediate.get(), deferred.get()}) {
    ASSERT_TRUE(scene->Release().ok());
    ASSERT_TRUE(scene->Grab(Centre() + glm::dvec3(3.0, 0.0, 0.0), 12.0).ok());
    ASSERT_TRUE(scene->Drag({-4.0, 0.0, 0.0}).ok());
  }
  a = immediate->Render(View());
  b = deferred->Render(View(), &deferred_sync);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_GT(deferred_sync.warp_ms, 0.0);
  EXPECT_EQ(testing::CompareRgba(a->rgba, b->rgba).max_abs, 0.0);

  // Release alone: back to the rest frame exactly.
  ASSERT_TRUE(deferred->Release().ok());
  b = deferred->Render(View());
  ASSERT_TRUE(b.ok());
  EXPECT_EQ(testing::CompareRgba(b->rgba, rest->rgba).max_abs, 0.0);
}

// Undeformed frames skip the map (the identity there) and show exactly what
// a cast through it shows; a drag brings the map back, a release removes it.
TEST_F(DeformableSceneTest, UndeformedFramesSkipTheIdentityMap) {
  auto scene = Scene(false);
  ASSERT_TRUE(scene);
  EXPECT_TRUE(scene->map_is_identity());
  auto rest = scene->Render(View());
  ASSERT_TRUE(rest.ok()) << rest.status();
  RenderRequest through_map;
  through_map.camera = View().camera;
  through_map.preset = View().preset;
  through_map.width = through_map.height = 64;
  through_map.volume = &case_->gpu_volume;
  through_map.backward_map = &scene->backward_map().image();
  auto mapped = case_->renderer->Render(through_map);
  ASSERT_TRUE(mapped.ok()) << mapped.status();
  EXPECT_EQ(testing::CompareRgba(rest->rgba, mapped->rgba).max_abs, 0.0);

  ASSERT_TRUE(scene->Grab(Centre(), 12.0).ok());
  EXPECT_TRUE(scene->map_is_identity()) << "a grab alone moves nothing";
  ASSERT_TRUE(scene->Drag({0.0, 1.0, 4.0}).ok());
  EXPECT_FALSE(scene->map_is_identity());
  auto dragged = scene->Render(View());
  ASSERT_TRUE(dragged.ok());
  EXPECT_GT(testing::CompareRgba(dragged->rgba, rest->rgba).max_abs, 0.1);
  ASSERT_TRUE(scene->Release().ok());
  EXPECT_TRUE(scene->map_is_identity());
  auto released = scene->Render(View());
  ASSERT_TRUE(released.ok());
  EXPECT_EQ(testing::CompareRgba(released->rgba, rest->rgba).max_abs, 0.0);
}

// Overlap: the next step's FEM runs while a prepared frame is cast. The
// frame shows the state it was prepared from, exactly as one rendered in
// order, and the next frame shows the step that ran meanwhile.
TEST_F(DeformableSceneTest, FemDuringAPreparedFrameChangesNeitherFrame) {
  auto in_order = Scene(true);
  auto overlapped = Scene(true);
  ASSERT_TRUE(in_order && overlapped);
  for (DeformableScene* scene : {in_order.get(), overlapped.get()}) {
    ASSERT_TRUE(scene->Grab(Centre(), 12.0).ok());
    ASSERT_TRUE(scene->Drag({0.0, 1.0, 2.0}).ok());
  }
  auto first = in_order->Render(View());
  ASSERT_TRUE(first.ok()) << first.status();
  ASSERT_TRUE(in_order->Drag({0.0, 1.0, 5.0}).ok());
  auto second = in_order->Render(View());
  ASSERT_TRUE(second.ok()) << second.status();
  ASSERT_GT(testing::CompareRgba(first->rgba, second->rgba).max_abs, 0.1)
      << "the second step should show";

  auto request = overlapped->PrepareRender(View());
  ASSERT_TRUE(request.ok()) << request.status();
  Result<Frame> cast = absl::InternalError("not cast");
  std::thread caster([&] { cast = overlapped->RenderPrepared(*request); });
  auto step = overlapped->Drag({0.0, 1.0, 5.0});
  caster.join();
  ASSERT_TRUE(step.ok()) << step.status();
  ASSERT_TRUE(cast.ok()) << cast.status();
  EXPECT_EQ(testing::CompareRgba(cast->rgba, first->rgba).max_abs, 0.0);
  auto next = overlapped->Render(View());
  ASSERT_TRUE(next.ok()) << next.status();
  EXPECT_EQ(testing::CompareRgba(next->rgba, second->rgba).max_abs, 0.0);
}

// SceneView::interactive_quality reaches the request (InteractiveCastFor)
// and the renderer: fast and balanced cast half the rays per axis, sharp
// all of them, auto as the device's choice (sharp on a discrete GPU, fast
// on lavapipe); stills cast all whatever it says.
TEST_F(DeformableSceneTest, InteractiveQualityReachesTheRenderer) {
  auto scene = Scene(true);
  ASSERT_TRUE(scene);
  ASSERT_TRUE(scene->Grab(Centre(), 12.0).ok());
  ASSERT_TRUE(scene->Drag({0.0, 1.0, 2.0}).ok());
  const InteractiveQuality chosen = scene->auto_interactive_quality();
  EXPECT_EQ(chosen,
            context().is_discrete_gpu() ? InteractiveQuality::kSharp : InteractiveQuality::kFast);
  for (InteractiveQuality quality : {InteractiveQuality::kFast, InteractiveQuality::kBalanced,
                                     InteractiveQuality::kSharp, InteractiveQuality::kAuto}) {
    SceneView view = View();
    view.quality = RenderQuality::kInteractive;
    view.interactive_quality = quality;
    auto request = scene->PrepareRender(view);
    ASSERT_TRUE(request.ok()) << request.status();
    if (quality == InteractiveQuality::kAuto) quality = chosen;
    const InteractiveCast expected = InteractiveCastFor(quality);
    EXPECT_EQ(request->interactive.divisor, expected.divisor);
    EXPECT_EQ(request->interactive.still_step_multiple, expected.still_step_multiple);
    EXPECT_EQ(request->interactive.upscale_filter, expected.upscale_filter);
    auto frame = scene->RenderPrepared(*request);
    ASSERT_TRUE(frame.ok()) << frame.status();
    EXPECT_EQ(frame->width, 64);
    EXPECT_EQ(frame->render_width, quality == InteractiveQuality::kSharp ? 64 : 32);
    view.quality = RenderQuality::kStill;
    auto still = scene->Render(view);
    ASSERT_TRUE(still.ok()) << still.status();
    EXPECT_EQ(still->render_width, 64);
  }
}

}  // namespace
}  // namespace vpm

namespace vpm {
namespace {

// The history a refinement replays (DeformableScene::history, Rebuilt): a
// release that does not keep drops its grab, a kept one stays with its last
// drag only, Reset clears it; rebuilt on the same mesh, the scene holds the
// tissue where the running one does, with the grab still held.
TEST_F(DeformableSceneTest, RebuiltReplaysTheHistoryToTheSamePositions) {
  auto scene = Scene(true);
  ASSERT_TRUE(scene);
  const glm::dvec3 centre = Centre();
  ASSERT_TRUE(scene->Grab(centre, 12.0).ok());
  ASSERT_TRUE(scene->Drag({0.0, 2.0, 0.0}).ok());
  ASSERT_TRUE(scene->Release(false).ok());
  EXPECT_TRUE(scene->history().empty());

  ASSERT_TRUE(scene->Pin(centre + glm::dvec3(0.0, 0.0, -10.0), 0.0).ok());
  ASSERT_TRUE(scene->Grab(centre + glm::dvec3(0.0, 0.0, 8.0), 8.0).ok());
  for (double dy : {1.0, 2.0, 3.0}) ASSERT_TRUE(scene->Drag({0.0, dy, 0.0}).ok());
  ASSERT_TRUE(scene->Release(true).ok());
  ASSERT_TRUE(scene->Grab(centre, 12.0).ok());
  ASSERT_TRUE(scene->Drag({0.0, 0.0, 4.0}).ok());
  ASSERT_TRUE(scene->Settle(kSettleSolves).ok());
  // pin, grab, its last drag, kept release, grab, drag.
  ASSERT_EQ(scene->history().size(), 6u);
  EXPECT_EQ(scene->history()[2].vector, glm::dvec3(0.0, 3.0, 0.0));
  EXPECT_TRUE(scene->history()[3].keep);

  auto rebuilt = scene->Rebuilt(scene->mesh());
  ASSERT_TRUE(rebuilt.ok()) << rebuilt.status();
  ASSERT_TRUE((*rebuilt)->GrabPointMm().has_value());
  EXPECT_EQ(*(*rebuilt)->GrabPointMm(), centre);
  const std::vector<glm::dvec3> a = scene->Positions(), b = (*rebuilt)->Positions();
  ASSERT_EQ(a.size(), b.size());
  double worst = 0.0, largest = 0.0;
  for (size_t v = 0; v < a.size(); ++v) {
    worst = std::max(worst, glm::distance(a[v], b[v]));
    largest = std::max(largest, glm::distance(a[v], scene->mesh().vertices[v].position_mm));
  }
  EXPECT_GT(largest, 1.0);
  // The running scene reached its drags in several events, the rebuilt one
  // in one each, both settled: the same state within 2% of the motion.
  EXPECT_LT(worst, 0.02 * largest) << "largest displacement " << largest;

  ASSERT_TRUE(scene->Reset().ok());
  EXPECT_TRUE(scene->history().empty());
}

}  // namespace
}  // namespace vpm
