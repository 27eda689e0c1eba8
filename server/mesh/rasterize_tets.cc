#include "server/mesh/rasterize_tets.h"

#include <algorithm>
#include <cmath>
#include <thread>

namespace vpm {
namespace {

// What one tet needs for scan conversion.
struct TetRaster {
  bool flat = true;
  glm::dvec3 p0{0.0};
  glm::dmat3 inverse{1.0};             // [p1-p0, p2-p0, p3-p0]^-1
  glm::dvec3 gradient{0.0};            // of the interpolant, value/mm
  double value0 = 0.0;                 // interpolant at p0
  std::array<int64_t, 3> lo{0, 0, 0};  // voxel index bounding box, inclusive
  std::array<int64_t, 3> hi{-1, -1, -1};
};

int64_t ClampToIndex(double x, int64_t lo, int64_t hi) {
  if (!(x >= static_cast<double>(lo))) return lo;  // also NaN
  if (x >= static_cast<double>(hi)) return hi;
  return static_cast<int64_t>(x);
}

TetRaster PrepareTet(const VolumeGeometry& g, const std::vector<glm::dvec3>& P,
                     const std::array<int32_t, 4>& t, const std::vector<double>& values) {
  TetRaster r;
  r.p0 = P[t[0]];
  const glm::dmat3 m(P[t[1]] - r.p0, P[t[2]] - r.p0, P[t[3]] - r.p0);
  const double det = glm::determinant(m);
  if (det == 0.0 || !std::isfinite(det)) return r;
  r.flat = false;
  r.inverse = glm::inverse(m);
  r.value0 = values[t[0]];
  const glm::dvec3 dv(values[t[1]] - r.value0, values[t[2]] - r.value0, values[t[3]] - r.value0);
  r.gradient = glm::transpose(r.inverse) * dv;
  glm::dvec3 lo = r.p0, hi = r.p0;
  for (int32_t v : t) {
    lo = glm::min(lo, P[v]);
    hi = glm::max(hi, P[v]);
  }
  for (int a = 0; a < 3; ++a) {
    // Slightly widened: the barycentric test decides, the box only bounds.
    const double slack = 1e-7;
    r.lo[a] = ClampToIndex(std::ceil(lo[a] / g.spacing_mm[a] - slack), 0, g.dims[a]);
    r.hi[a] = ClampToIndex(std::floor(hi[a] / g.spacing_mm[a] + slack), -1, g.dims[a] - 1);
  }
  return r;
}

// Rasterizes tets into slices [k_begin, k_end); returns the voxels visited.
int64_t RasterizeSlab(const VolumeGeometry& g, const std::vector<TetRaster>& rasters, double eps,
                      int64_t k_begin, int64_t k_end, std::vector<uint8_t>& visited,
                      const std::function<void(const VoxelRun&)>& visit) {
  const int64_t nx = g.dims[0], ny = g.dims[1];
  const glm::dvec3 s = g.spacing_mm;
  int64_t count = 0;
  for (size_t t = 0; t < rasters.size(); ++t) {
    const TetRaster& r = rasters[t];
    if (r.flat) continue;
    const int64_t k0 = std::max(r.lo[2], k_begin), k1 = std::min(r.hi[2] + 1, k_end);
    // Barycentric weights 1..3 along a row: a + b * i; weight 0 = 1 - sum.
    const glm::dvec3 b = r.inverse[0] * s.x;
    const double b0 = -(b.x + b.y + b.z);
    for (int64_t k = k0; k < k1; ++k) {
      for (int64_t j = r.lo[1]; j <= r.hi[1]; ++j) {
        const glm::dvec3 a = r.inverse * (glm::dvec3(0.0, j * s.y, k * s.z) - r.p0);
        const double a0 = 1.0 - (a.x + a.y + a.z);
        double lo = static_cast<double>(r.lo[0]), hi = static_cast<double>(r.hi[0]);
        const double as[4] = {a0, a.x, a.y, a.z}, bs[4] = {b0, b.x, b.y, b.z};
        for (int m = 0; m < 4; ++m) {
          const double bound = (-eps - as[m]) / bs[m];
          if (bs[m] > 0.0) {
            lo = std::max(lo, bound);
          } else if (bs[m] < 0.0) {
            hi = std::min(hi, bound);
          } else if (as[m] < -eps) {
            hi = -1.0;
          }
        }
        if (!(lo <= hi)) continue;
        const int64_t i_begin = ClampToIndex(std::ceil(lo), 0, nx);
        const int64_t i_end = ClampToIndex(std::floor(hi), -1, nx - 1) + 1;
        const int64_t row = nx * (j + ny * k);
        const glm::dvec3 x_begin(0.0, j * s.y, k * s.z);
        const double value_row = r.value0 + glm::dot(r.gradient, x_begin - r.p0);
        const double step = r.gradient.x * s.x;
        // Split into runs of voxels no earlier tet has taken.
        for (int64_t i = i_begin; i < i_end;) {
          while (i < i_end && visited[row + i]) ++i;
          const int64_t run_begin = i;
          while (i < i_end && !visited[row + i]) visited[row + i++] = 1;
          if (i == run_begin) continue;
          visit(VoxelRun{run_begin, i, j, k, static_cast<int32_t>(t),
                         value_row + step * static_cast<double>(run_begin), step});
          count += i - run_begin;
        }
      }
    }
  }
  return count;
}

}  // namespace

Result<int64_t> RasterizeTets(const VolumeGeometry& geometry,
                              const std::vector<glm::dvec3>& positions,
                              const std::vector<std::array<int32_t, 4>>& tets,
                              const std::vector<double>& vertex_values,
                              const RasterizeTetsOptions& options,
                              const std::function<void(const VoxelRun&)>& visit) {
  if (vertex_values.size() != positions.size()) {
    return absl::InvalidArgumentError(StrCat("RasterizeTets: ", vertex_values.size(),
                                             " vertex values for ", positions.size(), " vertices"));
  }
  const int64_t vertex_count = static_cast<int64_t>(positions.size());
  for (size_t t = 0; t < tets.size(); ++t) {
    for (int32_t v : tets[t]) {
      if (v < 0 || v >= vertex_count) {
        return absl::InvalidArgumentError(StrCat("RasterizeTets: tet ", t, " has vertex index ", v,
                                                 ", outside [0, ", vertex_count, ")"));
      }
    }
  }
  std::vector<TetRaster> rasters(tets.size());
  for (size_t t = 0; t < tets.size(); ++t) {
    rasters[t] = PrepareTet(geometry, positions, tets[t], vertex_values);
  }
  std::vector<uint8_t> visited(static_cast<size_t>(geometry.voxel_count()), 0);
  const int64_t nz = geometry.dims[2];
  const int threads = static_cast<int>(std::clamp<int64_t>(options.threads, 1, nz));
  std::vector<int64_t> counts(threads, 0);
  std::vector<std::thread> workers;
  for (int w = 0; w < threads; ++w) {
    const int64_t k_begin = nz * w / threads, k_end = nz * (w + 1) / threads;
    auto work = [&, w, k_begin, k_end] {
      counts[w] = RasterizeSlab(geometry, rasters, options.eps, k_begin, k_end, visited, visit);
    };
    if (w + 1 == threads) {
      work();  // the calling thread takes the last slab
    } else {
      workers.emplace_back(work);
    }
  }
  for (std::thread& worker : workers) worker.join();
  int64_t total = 0;
  for (int64_t c : counts) total += c;
  return total;
}

}  // namespace vpm
