// Step 1 on the GPU against the CPU reference (double precision).
#include <algorithm>
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "server/mesh/build_proxy_mesh.h"
#include "server/mesh/lattice_costs.h"
#include "server/mesh/lattice_costs_gpu.h"
#include "tests/gpu/gpu_test_context.h"
#include "tests/mesh/mesh_test_volumes.h"
#include "tests/volume/int16_twin.h"

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

namespace vpm {
namespace {

using testing::GpuTest;

// The same body volume as int16 (its values rounded to integers) and as
// float: step 1 on the GPU gives the same costs for both, and matches the
// CPU reference within the tolerances above.
TEST_F(GpuTest, LatticeCostsGpu_Int16VolumeEqualsFloatVolume) {
  const Volume body = testing::MakeBodyVolume({50, 41, 33}, {0.9, 1.2, 1.6});
  const auto [int16, floats] = testing::MakeInt16Twin(body);
  auto gpu16 = GpuVolume::Upload(context(), int16);
  auto gpu32 = GpuVolume::Upload(context(), floats);
  ASSERT_TRUE(gpu16.ok() && gpu32.ok());
  auto op = LatticeCostsGpu::Create(context());
  ASSERT_TRUE(op.ok()) << op.status();
  auto lattice = Lattice::Create(body.geometry(), {12, 10, 9});
  ASSERT_TRUE(lattice.ok());
  const TransferFunction tf = TransferFunction::CtSoftTissue();
  auto a = op->Evaluate(*gpu16, *lattice, tf);
  auto b = op->Evaluate(*gpu32, *lattice, tf);
  ASSERT_TRUE(a.ok() && b.ok());
  const LatticeCosts cpu = EvaluateLatticeCostsCpu(int16, *lattice, tf);
  for (Footprint f : {Footprint::kCell, Footprint::kPoint}) {
    EXPECT_EQ(a->ci(f), b->ci(f));
    EXPECT_EQ(a->g(f), b->g(f));
    const double g_max = *std::max_element(cpu.g(f).begin(), cpu.g(f).end());
    for (int64_t id = 0; id < lattice->size(); ++id) {
      ASSERT_NEAR(a->ci(f)[id], cpu.ci(f)[id], 1e-5) << id;
      ASSERT_NEAR(a->g(f)[id], cpu.g(f)[id], 1e-5 * g_max) << id;
    }
  }
}

// The mesh's stats say where step 1 ran: on a CPU device (lavapipe) the
// native rows, not the Vulkan kernels; on a GPU the kernels; without a
// device the CPU reference. `vpm mesh` prints this label.
TEST_F(GpuTest, DecimateLattice_SaysWhereStep1Ran) {
  const Volume body = testing::MakeBodyVolume({40, 36, 30}, {1.0, 1.0, 1.5});
  auto gpu_volume = GpuVolume::Upload(context(), body);
  ASSERT_TRUE(gpu_volume.ok()) << gpu_volume.status();
  auto op = LatticeCostsGpu::Create(context());
  ASSERT_TRUE(op.ok()) << op.status();
  MeshParams params;
  params.grid = {10, 9, 8};
  params.target = 80;
  auto on_device = DecimateLattice(body, params, MeshGpu{&*gpu_volume, &*op});
  auto reference = DecimateLattice(body, params);
  ASSERT_TRUE(on_device.ok() && reference.ok());
  EXPECT_EQ(on_device->stats.evaluated_on,
            context().is_cpu_device() ? kStep1OnCpuRows : kStep1OnGpu)
      << context().device_name();
  EXPECT_EQ(reference->stats.evaluated_on, kStep1OnCpuReference);
}

// A volume of more voxels than the texel-buffer limit of one voxel per
// texel (2^27 on lavapipe and NVIDIA): 1024 x 1024 x 129 int16 voxels, 4 per
// texel, read to the last slab, which differs from the rest.
TEST_F(GpuTest, GpuVolume_ReadsVolumesPastOneVoxelPerTexelLimit) {
  const uint64_t limit = context().limits().maxTexelBufferElements;
  std::printf("maxTexelBufferElements %llu, maxStorageBufferRange %u, device '%s'\n",
              static_cast<unsigned long long>(limit), context().limits().maxStorageBufferRange,
              context().device_name().c_str());
  VolumeGeometry g;
  g.dims = {1024, 1024, 129};
  std::vector<int16_t> stored(static_cast<size_t>(g.voxel_count()), -1000);
  const int64_t last_slab = (g.dims[2] - 1) * g.dims[0] * g.dims[1];
  for (int64_t n = last_slab + g.dims[0] * 512; n < g.voxel_count(); ++n) stored[n] = 60;
  VolumeLimits limits;
  limits.max_volume_bytes = int64_t{1} << 31;
  const Volume v = *Volume::Create(g, *VoxelValues::Int16(std::move(stored), 0), limits);
  // Past the limit wherever it is 2^27 (lavapipe, NVIDIA); a device with a
  // larger one still reads the whole volume correctly below.
  if (limit <= (uint64_t{1} << 27)) {
    ASSERT_GT(uint64_t(v.geometry().voxel_count()), limit);
  }
  auto gpu_volume = GpuVolume::Upload(context(), v);
  ASSERT_TRUE(gpu_volume.ok()) << gpu_volume.status();
  auto op = LatticeCostsGpu::Create(context());
  ASSERT_TRUE(op.ok()) << op.status();
  auto lattice = Lattice::Create(v.geometry(), {4, 4, 3});
  ASSERT_TRUE(lattice.ok());
  const TransferFunction tf = TransferFunction::CtSoftTissue();
  auto gpu = op->Evaluate(*gpu_volume, *lattice, tf);
  ASSERT_TRUE(gpu.ok()) << gpu.status();
  const LatticeCosts cpu = EvaluateLatticeCostsCpu(v, *lattice, tf);
  // Only the last slab (voxels past 2^27) holds edges, 1060 HU along y and
  // along z: the largest gradient, 530 * sqrt(2) HU/mm where they meet,
  // comes from there alone.
  double g_max = 0.0;
  for (int64_t id = 0; id < lattice->size(); ++id) {
    ASSERT_NEAR(gpu->ci(Footprint::kCell)[id], cpu.ci(Footprint::kCell)[id], 1e-5) << id;
    ASSERT_NEAR(gpu->g(Footprint::kCell)[id], cpu.g(Footprint::kCell)[id], 1e-3) << id;
    g_max = std::max(g_max, double(gpu->g(Footprint::kCell)[id]));
  }
  EXPECT_NEAR(g_max, 530.0 * std::sqrt(2.0), 1.0);
}

}  // namespace
}  // namespace vpm
