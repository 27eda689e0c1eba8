#include "server/measures/reconstruction_error.h"

#include <cmath>
#include <vector>

#include "server/measures/rasterize_tets.h"
#include "server/volume/sample_trilinear.h"
#include "server/measures/tf_positive_set.h"

namespace vpm {
namespace {

struct SliceSums {
  double squared_all = 0.0;
  double squared_tf_positive = 0.0;
  int64_t tf_positive = 0;
};

}  // namespace

Result<ReconstructionError> MeasureReconstructionError(const Volume& volume, const ProxyMesh& mesh,
                                                       const TransferFunction& tf,
                                                       const ReconstructionErrorOptions& options) {
  std::vector<glm::dvec3> positions(mesh.vertices.size());
  std::vector<double> values(mesh.vertices.size());
  for (size_t v = 0; v < positions.size(); ++v) {
    positions[v] = mesh.vertices[v].position_mm;
    values[v] = SampleTrilinear(volume, positions[v]);
  }
  const int64_t nx = volume.dims()[0], ny = volume.dims()[1];
  const VoxelValues& voxels = volume.voxels();
  std::vector<SliceSums> slices(static_cast<size_t>(volume.dims()[2]));
  const TfPositiveSet tf_positive(tf);
  auto visit = [&](const VoxelRun& run) {
    const int64_t row = nx * (run.j + ny * run.k);
    double squared_all = 0.0, squared_tf_positive = 0.0;
    int64_t tf_positive_count = 0;
    for (int64_t i = run.i_begin; i < run.i_end; ++i) {
      const double interpolated =
          run.value_begin + run.value_step * static_cast<double>(i - run.i_begin);
      const float value = voxels[row + i];
      const double error = static_cast<double>(value) - interpolated;
      squared_all += error * error;
      if (tf_positive.Contains(value)) {
        squared_tf_positive += error * error;
        ++tf_positive_count;
      }
    }
    SliceSums& sums = slices[run.k];
    sums.squared_all += squared_all;
    sums.squared_tf_positive += squared_tf_positive;
    sums.tf_positive += tf_positive_count;
  };
  RasterizeTetsOptions raster_options;
  raster_options.threads = options.threads;
  ASSIGN_OR_RETURN(const int64_t inside, RasterizeTets(volume.geometry(), positions, mesh.tets,
                                                       values, raster_options, visit));
  ReconstructionError result;
  double squared_all = 0.0, squared_tf_positive = 0.0;
  for (const SliceSums& s : slices) {
    squared_all += s.squared_all;
    squared_tf_positive += s.squared_tf_positive;
    result.voxels_tf_positive += s.tf_positive;
  }
  result.voxels_all = inside;
  result.voxels_outside_mesh = volume.geometry().voxel_count() - inside;
  if (inside > 0) result.rmse_all = std::sqrt(squared_all / static_cast<double>(inside));
  if (result.voxels_tf_positive > 0) {
    result.rmse_tf_positive =
        std::sqrt(squared_tf_positive / static_cast<double>(result.voxels_tf_positive));
  }
  return result;
}

}  // namespace vpm
