// Step 1 on the GPU against the CPU reference (double precision).
#include <gtest/gtest.h>

#include "server/mesh/lattice_costs.h"
#include "server/mesh/lattice_costs_gpu.h"
#include "tests/gpu/gpu_test_context.h"
#include "tests/mesh/mesh_test_volumes.h"

namespace vpm {
namespace {

using testing::GpuTest;

// Tolerances: Ci (mean of TF in [0,1]) within 1e-5 absolute: float sums of a
// few thousand terms; g within 1e-5 of the largest g (float differences).
TEST_F(GpuTest, LatticeCostsGpu_MatchesCpuReferenceForBothFootprints) {
  const Volume v = testing::MakeBodyVolume({50, 41, 33}, {0.9, 1.2, 1.6});
  auto gpu_volume = GpuVolume::Upload(context(), v);
  ASSERT_TRUE(gpu_volume.ok());
  // Kernels are specialized per TF point count: the default (8 points) and a
  // 4-point TF with a step at 150 HU (a zero-width segment).
  const auto step_tf = TransferFunction::Create({{-300, 0}, {0, 0.5}, {150, 0.5}, {150, 1.0}});
  ASSERT_TRUE(step_tf.ok()) << step_tf.status();
  const std::vector<TransferFunction> tfs{TransferFunction::CtSoftTissue(), *step_tf};
  // The default budget evaluates these lattices in one chunk; 4 KiB of row
  // partials forces one chunk per cell layer (the path of very large lattices).
  for (const size_t budget : {LatticeCostsGpu::kDefaultPartialsBudgetBytes, size_t{4096}}) {
    auto op = LatticeCostsGpu::Create(context(), budget);
    ASSERT_TRUE(op.ok()) << op.status();
    for (const std::array<int64_t, 3> grid :
         {std::array<int64_t, 3>{7, 9, 5}, std::array<int64_t, 3>{50, 41, 33},
          std::array<int64_t, 3>{1, 1, 1}}) {
      auto lattice = Lattice::Create(v.geometry(), grid);
      ASSERT_TRUE(lattice.ok());
      for (const TransferFunction& tf : tfs) {
        auto gpu = op->Evaluate(*gpu_volume, *lattice, tf);
        ASSERT_TRUE(gpu.ok()) << gpu.status();
        const LatticeCosts cpu = EvaluateLatticeCostsCpu(v, *lattice, tf);
        for (Footprint f : {Footprint::kCell, Footprint::kPoint}) {
          const double g_max = *std::max_element(cpu.g(f).begin(), cpu.g(f).end());
          ASSERT_GT(g_max, 0.0);
          for (int64_t id = 0; id < lattice->size(); ++id) {
            const std::string where =
                StrCat(FootprintName(f), " id ", id, " budget ", budget, " tf ", tf.ToString());
            ASSERT_NEAR(gpu->ci(f)[id], cpu.ci(f)[id], 1e-5) << where;
            ASSERT_NEAR(gpu->g(f)[id], cpu.g(f)[id], 1e-5 * g_max) << where;
          }
        }
      }
    }
  }
}

}  // namespace
}  // namespace vpm
