#include "server/warp/backward_map_cpu.h"

#include "server/mesh/tet_locator.h"
#include "server/warp/check_map_inputs.h"
#include "server/common/parallel_chunks.h"

namespace vpm {

Result<BackwardMapValues> BackwardMapCpu(const glm::dvec3& extent_mm,
                                         const std::array<int64_t, 3>& map_dims,
                                         const std::vector<glm::dvec3>& rest_mm,
                                         const std::vector<glm::dvec3>& deformed_mm,
                                         const std::vector<std::array<int32_t, 4>>& tets,
                                         const BackwardMapCpuOptions& options) {
  RETURN_IF_ERROR(CheckMapMesh(rest_mm, deformed_mm, tets));
  RETURN_IF_ERROR(CheckMapGrid(extent_mm, map_dims, int64_t{1} << 20));
  ASSIGN_OR_RETURN(const TetLocator locator,
                   TetLocator::Create(deformed_mm, tets, {.eps = options.eps}));
  BackwardMapValues map;
  map.dims = map_dims;
  map.extent_mm = extent_mm;
  map.values.assign(static_cast<size_t>(map_dims[0] * map_dims[1] * map_dims[2]), glm::vec4(0.0f));
  ParallelSlices(map_dims[2], options.threads, [&](int64_t c) {
    for (int64_t b = 0; b < map_dims[1]; ++b) {
      for (int64_t a = 0; a < map_dims[0]; ++a) {
        const glm::dvec3 p = map.GridPointMm(a, b, c);
        const auto location = locator.Locate(p);
        if (!location) continue;
        const auto& q = tets[location->tet];
        glm::dvec3 rest(0.0);
        for (int i = 0; i < 4; ++i) rest += location->weights[i] * rest_mm[q[i]];
        map.values[map.Index(a, b, c)] = glm::vec4(glm::vec3(rest - p), 1.0f);
      }
    }
  });
  return map;
}

}  // namespace vpm
