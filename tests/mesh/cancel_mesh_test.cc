// A mesh build stops when its CancelToken says so: at the first poll for a
// token already cancelled, and within the 100 ms of a cancel that
// comes while step 2 or the Steiner rounds run. A token that never cancels
// changes nothing.
#include <atomic>
#include <chrono>
#include <cstdio>
#include <thread>

#include <gtest/gtest.h>

#include "server/common/cancel_token.h"
#include "server/mesh/build_proxy_mesh.h"
#include "server/mesh/decimate.h"
#include "server/mesh/tetrahedralize.h"
#include "tests/mesh/mesh_test_volumes.h"

namespace vpm {
namespace {

using Clock = std::chrono::steady_clock;

TEST(CancelMesh, CancelledTokenStopsEveryStage) {
  const Volume volume = testing::MakeBodyVolume();
  CancelToken::Source source;
  source.Cancel();
  const CancelToken cancelled = source.token();
  MeshParams params;
  params.grid = {12, 12, 12};
  params.target = 60;
  auto base = DecimateLattice(volume, params, {}, cancelled);
  EXPECT_EQ(base.status().code(), absl::StatusCode::kCancelled) << base.status();

  auto kept = DecimateLattice(volume, params);
  ASSERT_TRUE(kept.ok()) << kept.status();
  auto mesh = FinishProxyMesh(volume, *kept, params, cancelled);
  EXPECT_EQ(mesh.status().code(), absl::StatusCode::kCancelled) << mesh.status();

  ProxyMesh points;
  points.vertices = kept->vertices;
  EXPECT_EQ(Tetrahedralize(points, volume.geometry().extent_mm(), cancelled).code(),
            absl::StatusCode::kCancelled);
  EXPECT_TRUE(points.tets.empty());
}

TEST(CancelMesh, TokenThatNeverCancelsGivesTheSameMesh) {
  const Volume volume = testing::MakeBodyVolume();
  MeshParams params;
  params.grid = {12, 12, 12};
  params.target = 60;
  CancelToken::Source source;  // never cancelled
  auto plain = BuildProxyMesh(volume, params);
  auto polled = BuildProxyMesh(volume, params, {}, source.token());
  ASSERT_TRUE(plain.ok()) << plain.status();
  ASSERT_TRUE(polled.ok()) << polled.status();
  EXPECT_EQ(plain->tets, polled->tets);
  ASSERT_EQ(plain->vertices.size(), polled->vertices.size());
  for (size_t v = 0; v < plain->vertices.size(); ++v) {
    EXPECT_EQ(plain->vertices[v].position_mm, polled->vertices[v].position_mm);
  }
}

// Step 2 on an 80^3 lattice (half a million removals) cancelled 20 ms into
// its removal loop: it returns Cancelled
// within the bound of 100 ms of the cancel (asserted with a
// generous margin for loaded machines: 500 ms).
TEST(CancelMesh, DecimationStopsSoonAfterTheCancel) {
  DecimationInput input;
  const int64_t g = 80;
  for (int64_t k = 0; k < g; ++k)
    for (int64_t j = 0; j < g; ++j)
      for (int64_t i = 0; i < g; ++i) {
        input.positions.emplace_back(double(i), double(j), double(k));
        input.ci.push_back(double((i * 7 + j * 13 + k * 17) % 101) / 100.0);
        input.cg.push_back(double((i * 11 + j * 5 + k * 3) % 97) / 96.0);
      }
  DecimationParams params{.target = 250, .radius_mm = 2.0};
  CancelToken::Source source;
  std::atomic<int> polls{0};
  std::atomic<bool> started{false};
  Clock::time_point cancelled_at;
  // The first two polls are at the start and after the neighbour search;
  // the third is from the removal loop.
  const CancelToken token([&, inner = source.token()] {
    if (++polls >= 3) started = true;
    return inner.Check();
  });
  std::thread canceller([&] {
    while (!started) std::this_thread::yield();
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    cancelled_at = Clock::now();
    source.Cancel();
  });
  auto result = DecimateFast(input, params, token);
  const Clock::time_point returned_at = Clock::now();
  canceller.join();
  ASSERT_EQ(result.status().code(), absl::StatusCode::kCancelled)
      << "finished before the cancel; use a bigger lattice";
  const double late_ms = std::chrono::duration<double, std::milli>(returned_at - cancelled_at).count();
  std::printf("DecimateFast returned %.2f ms after the cancel\n", late_ms);
  EXPECT_LT(late_ms, 500.0);
}

}  // namespace
}  // namespace vpm
