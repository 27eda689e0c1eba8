#include "server/mesh/lattice_costs_rows.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>
#include <thread>
#include <vector>

#include "server/common/parallel_chunks.h"

namespace vpm {
namespace {

// TF of every stored int16 value s, at index s + 32768: the value the voxel
// holds is s + offset (voxel_values.h), evaluated in double, kept as float.
std::vector<float> Int16TfTable(const TransferFunction& tf, int32_t offset) {
  std::vector<float> table(65536);
  for (int32_t s = -32768; s <= 32767; ++s) {
    table[size_t(s + 32768)] = float(tf.Evaluate(double(s + offset)));
  }
  return table;
}

// TF of voxel n: from the table for int16 voxels, else evaluated.
struct TfOfInt16 {
  const float* table;
  const int16_t* stored;
  float operator()(int64_t n) const { return table[size_t(int32_t{stored[n]} + 32768)]; }
};

struct TfOfFloat {
  const TransferFunction* tf;
  const float* values;
  float operator()(int64_t n) const { return float(tf->Evaluate(values[n])); }
};

// Offsets (voxels) of the rows a voxel row (y, z) and its y and z
// neighbours lie on, clamped at the volume's faces (section 0).
struct RowOffsets {
  int64_t here, y_lo, y_hi, z_lo, z_hi;
};

RowOffsets RowsAround(const std::array<int64_t, 3>& n, int64_t y, int64_t z) {
  auto at = [&](int64_t yy, int64_t zz) { return n[0] * (yy + n[1] * zz); };
  return {at(y, z), at(std::max<int64_t>(y - 1, 0), z), at(std::min(y + 1, n[1] - 1), z),
          at(y, std::max<int64_t>(z - 1, 0)), at(y, std::min(z + 1, n[2] - 1))};
}

// TF and |grad I|^2 (value/mm)^2 of every voxel of one row, into tf_row and
// g2_row (nx floats each). The x neighbours of the first and last voxel are
// clamped; the loop between them has no branch, so it vectorises.
template <typename Voxels, typename TfOf>
void RowTerms(Voxels v, TfOf tf_of, int64_t nx, const RowOffsets& r, const glm::vec3& inv2s,
              float* tf_row, float* g2_row) {
  auto g2_at = [&](int64_t x, int64_t xl, int64_t xr) {
    const float gx = (v[r.here + xr] - v[r.here + xl]) * inv2s.x;
    const float gy = (v[r.y_hi + x] - v[r.y_lo + x]) * inv2s.y;
    const float gz = (v[r.z_hi + x] - v[r.z_lo + x]) * inv2s.z;
    return gx * gx + gy * gy + gz * gz;
  };
  for (int64_t x = 0; x < nx; ++x) tf_row[x] = tf_of(r.here + x);
  g2_row[0] = g2_at(0, 0, std::min<int64_t>(1, nx - 1));
  for (int64_t x = 1; x + 1 < nx; ++x) g2_row[x] = g2_at(x, x - 1, x + 1);
  if (nx > 1) g2_row[nx - 1] = g2_at(nx - 1, nx - 2, nx - 1);
}

// Whether the threads stop before their next cell layer: each polls the
// call's cancellation; the first status that is not OK is kept.
class LayerStop {
 public:
  explicit LayerStop(const CancelToken& cancel) : cancel_(cancel) {}
  bool Now() {
    if (stopped_.load(std::memory_order_relaxed)) return true;
    Status status = cancel_.Check();
    if (status.ok()) return false;
    std::lock_guard lock(mutex_);
    if (status_.ok()) status_ = std::move(status);
    stopped_ = true;
    return true;
  }
  Status status() {
    std::lock_guard lock(mutex_);
    return status_;
  }

 private:
  const CancelToken& cancel_;
  std::atomic<bool> stopped_{false};
  std::mutex mutex_;
  Status status_;
};

// The cell footprint (sum of TF, max |grad I|^2 per cell) of the cell
// layers [cz0, cz1), into sum and max_g2 (one entry per lattice vertex);
// returns early when `stop` says so.
template <typename Voxels, typename TfOf>
void CellLayers(const Volume& volume, const Lattice& lattice, Voxels v, TfOf tf_of, int64_t cz0,
                int64_t cz1, std::vector<double>& sum, std::vector<float>& max_g2,
                LayerStop& stop) {
  const auto& n = volume.dims();
  const auto& g = lattice.grid();
  const glm::dvec3& s = volume.spacing_mm();
  const glm::vec3 inv2s(float(1.0 / (2.0 * s.x)), float(1.0 / (2.0 * s.y)),
                        float(1.0 / (2.0 * s.z)));
  const size_t nx = static_cast<size_t>(n[0]);
  std::vector<float> tf_row(nx), g2_row(nx);
  std::vector<std::array<int64_t, 2>> x_ranges(static_cast<size_t>(g[0]));
  for (int64_t cx = 0; cx < g[0]; ++cx) x_ranges[size_t(cx)] = lattice.CellRange(0, cx);
  for (int64_t cz = cz0; cz < cz1; ++cz) {
    if (stop.Now()) return;
    const auto rz = lattice.CellRange(2, cz);
    for (int64_t cy = 0; cy < g[1]; ++cy) {
      const auto ry = lattice.CellRange(1, cy);
      const size_t cell0 = size_t(g[0] * (cy + g[1] * cz));
      for (int64_t z = rz[0]; z < rz[1]; ++z) {
        for (int64_t y = ry[0]; y < ry[1]; ++y) {
          RowTerms(v, tf_of, n[0], RowsAround(n, y, z), inv2s, tf_row.data(), g2_row.data());
          for (int64_t cx = 0; cx < g[0]; ++cx) {
            const auto [x0, x1] = x_ranges[size_t(cx)];
            double row_sum = 0.0;
            float row_max = 0.0f;
            for (int64_t x = x0; x < x1; ++x) {
              row_sum += tf_row[size_t(x)];
              row_max = std::max(row_max, g2_row[size_t(x)]);
            }
            sum[cell0 + size_t(cx)] += row_sum;
            max_g2[cell0 + size_t(cx)] = std::max(max_g2[cell0 + size_t(cx)], row_max);
          }
        }
      }
    }
  }
}

}  // namespace

Result<LatticeCosts> EvaluateLatticeCostsRows(const Volume& volume, const Lattice& lattice,
                                              const TransferFunction& tf, int threads,
                                              const CancelToken& cancel) {
  const int64_t count = lattice.size();
  const auto& g = lattice.grid();
  if (threads <= 0) threads = int(std::max(1u, std::thread::hardware_concurrency()));
  std::vector<double> sum(size_t(count), 0.0);
  std::vector<float> max_g2(size_t(count), 0.0f);
  const VoxelValues& voxels = volume.voxels();
  std::vector<float> table;
  if (voxels.is_int16()) table = Int16TfTable(tf, voxels.int16_offset());
  const int parts = int(std::clamp<int64_t>(threads, 1, g[2]));
  LayerStop stop(cancel);
  ParallelChunks(parts, g[2], [&](int64_t cz0, int64_t cz1, int) {
    voxels.Visit([&](auto v) {
      if constexpr (std::is_same_v<decltype(v), Int16Voxels>) {
        CellLayers(volume, lattice, v, TfOfInt16{table.data(), v.stored}, cz0, cz1, sum, max_g2,
                   stop);
      } else {
        CellLayers(volume, lattice, v, TfOfFloat{&tf, v.values}, cz0, cz1, sum, max_g2, stop);
      }
    });
  });
  RETURN_IF_ERROR(stop.status());
  LatticeCosts costs = LatticeCosts::Zeros(size_t(count));
  for (int64_t id = 0; id < count; ++id) {
    const auto c = lattice.Coords(id);
    const auto rx = lattice.CellRange(0, c[0]), ry = lattice.CellRange(1, c[1]);
    const auto rz = lattice.CellRange(2, c[2]);
    const double cells = double(rx[1] - rx[0]) * double(ry[1] - ry[0]) * double(rz[1] - rz[0]);
    costs.ci_cell[size_t(id)] = sum[size_t(id)] / cells;
    costs.g_cell[size_t(id)] = std::sqrt(double(max_g2[size_t(id)]));
    // The point footprint: one voxel each, as the reference computes it.
    const auto p = lattice.Voxel(id);
    costs.ci_point[size_t(id)] = tf.Evaluate(volume.At(p[0], p[1], p[2]));
    costs.g_point[size_t(id)] = GradientMagnitudeAtD(volume, p[0], p[1], p[2]);
  }
  return costs;
}

}  // namespace vpm
