#include "server/warp/warp_volume_cpu.h"

#include <cmath>

#include "server/volume/sample_trilinear.h"
#include "server/mesh/tet_locator.h"
#include "server/warp/check_map_inputs.h"
#include "server/common/parallel_chunks.h"

namespace vpm {
namespace {

// Fills a volume of the source's geometry with rest(x) sampled at every voxel.
template <typename RestOf>
Result<Volume> Resample(const Volume& source, int threads, const RestOf& rest_of) {
  const VolumeGeometry& g = source.geometry();
  std::vector<float> values(static_cast<size_t>(g.voxel_count()));
  ParallelSlices(g.dims[2], threads, [&](int64_t k) {
    for (int64_t j = 0; j < g.dims[1]; ++j) {
      for (int64_t i = 0; i < g.dims[0]; ++i) {
        const glm::dvec3 x = g.IndexToPhysical(glm::dvec3(i, j, k));
        values[source.LinearIndex(i, j, k)] =
            static_cast<float>(SampleTrilinear(source, rest_of(x)));
      }
    }
  });
  ASSIGN_OR_RETURN(Volume warped, Volume::Create(g, std::move(values), UnboundedVolumeLimits()));
  warped.set_source(source.source() + " (warped)");
  return warped;
}

}  // namespace

Result<Volume> WarpVolumeCpu(const Volume& source, const BackwardMapValues& map, int threads) {
  const glm::dvec3 extent = source.geometry().extent_mm();
  RETURN_IF_ERROR(CheckMapGrid(extent, map.dims, int64_t{1} << 20));
  for (int a = 0; a < 3; ++a) {
    if (!(std::abs(map.extent_mm[a] - extent[a]) <= 1e-9 * extent[a])) {
      return absl::InvalidArgumentError(StrCat("warp: the map covers ", map.extent_mm[a],
                                               " mm on axis ", a, ", the volume ", extent[a]));
    }
  }
  if (map.values.size() != static_cast<size_t>(map.dims[0] * map.dims[1] * map.dims[2])) {
    return absl::InvalidArgumentError("warp: the map's value count does not match its dims");
  }
  return Resample(source, threads,
                  [&](const glm::dvec3& x) { return x + glm::dvec3(map.Sample(x)); });
}

Result<Volume> WarpVolumeExactCpu(const Volume& source, const std::vector<glm::dvec3>& rest_mm,
                                  const std::vector<glm::dvec3>& deformed_mm,
                                  const std::vector<std::array<int32_t, 4>>& tets,
                                  const BackwardMapCpuOptions& options) {
  RETURN_IF_ERROR(CheckMapMesh(rest_mm, deformed_mm, tets));
  ASSIGN_OR_RETURN(const TetLocator locator,
                   TetLocator::Create(deformed_mm, tets, {.eps = options.eps}));
  return Resample(source, options.threads, [&](const glm::dvec3& x) {
    const auto location = locator.Locate(x);
    if (!location) return x;
    const auto& q = tets[location->tet];
    glm::dvec3 rest(0.0);
    for (int i = 0; i < 4; ++i) rest += location->weights[i] * rest_mm[q[i]];
    return rest;
  });
}

}  // namespace vpm
