#include "server/measures/interpolate_on_mesh.h"

#include "server/measures/rasterize_tets.h"
#include "server/volume/sample_trilinear.h"

namespace vpm {

Result<std::vector<float>> InterpolateOnMesh(const Volume& volume, const ProxyMesh& mesh,
                                             float outside_value, int threads) {
  std::vector<glm::dvec3> positions(mesh.vertices.size());
  std::vector<double> values(mesh.vertices.size());
  for (size_t v = 0; v < positions.size(); ++v) {
    positions[v] = mesh.vertices[v].position_mm;
    values[v] = SampleTrilinear(volume, positions[v]);
  }
  std::vector<float> out(static_cast<size_t>(volume.geometry().voxel_count()), outside_value);
  const int64_t nx = volume.dims()[0], ny = volume.dims()[1];
  auto visit = [&](const VoxelRun& run) {
    float* row = out.data() + nx * (run.j + ny * run.k);
    for (int64_t i = run.i_begin; i < run.i_end; ++i) {
      row[i] = static_cast<float>(run.value_begin +
                                  run.value_step * static_cast<double>(i - run.i_begin));
    }
  };
  RasterizeTetsOptions options;
  options.threads = threads;
  RETURN_IF_ERROR(
      RasterizeTets(volume.geometry(), positions, mesh.tets, values, options, visit).status());
  return out;
}

}  // namespace vpm
