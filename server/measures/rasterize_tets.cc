#include "server/measures/rasterize_tets.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "server/common/parallel_chunks.h"

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
  std::array<glm::dvec3, 4> corners;  // mm
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
  for (int c = 0; c < 4; ++c) r.corners[c] = P[t[c]];
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

// The index interval [i_begin, i_end) of row (j, k) whose centres are in the
// tet: each barycentric weight is linear along the row, a + b * i >= -eps.
std::pair<int64_t, int64_t> RowInterval(const TetRaster& r, const glm::dvec3& s, int64_t nx,
                                        int64_t j, int64_t k, double eps) {
  const glm::dvec3 a = r.inverse * (glm::dvec3(0.0, j * s.y, k * s.z) - r.p0);
  const glm::dvec3 b = r.inverse[0] * s.x;
  const double as[4] = {1.0 - (a.x + a.y + a.z), a.x, a.y, a.z};
  const double bs[4] = {-(b.x + b.y + b.z), b.x, b.y, b.z};
  double lo = static_cast<double>(r.lo[0]), hi = static_cast<double>(r.hi[0]);
  for (int m = 0; m < 4; ++m) {
    if (bs[m] > 0.0) {
      lo = std::max(lo, (-eps - as[m]) / bs[m]);
    } else if (bs[m] < 0.0) {
      hi = std::min(hi, (-eps - as[m]) / bs[m]);
    } else if (as[m] < -eps) {
      return {0, 0};
    }
  }
  if (!(lo <= hi)) return {0, 0};
  return {ClampToIndex(std::ceil(lo), 0, nx), ClampToIndex(std::floor(hi), -1, nx - 1) + 1};
}

// The rows j that the tet's section by the plane z = z_mm may cover, from
// the section polygon's y extent; widened a little, since the barycentric
// test in RowInterval decides. Empty when first > last.
std::pair<int64_t, int64_t> SectionRows(const TetRaster& r, double z_mm, double sy, int64_t ny) {
  static constexpr int kEdges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
  const auto& p = r.corners;
  double z_lo = p[0].z, z_hi = p[0].z;
  for (const glm::dvec3& c : p) {
    z_lo = std::min(z_lo, c.z);
    z_hi = std::max(z_hi, c.z);
  }
  // Corners this close to the plane count as on it.
  const double near = 1e-9 * (z_hi - z_lo) + 1e-15 * std::abs(z_mm);
  double y_lo = INFINITY, y_hi = -INFINITY;
  for (const glm::dvec3& c : p) {
    if (std::abs(c.z - z_mm) <= near) {
      y_lo = std::min(y_lo, c.y);
      y_hi = std::max(y_hi, c.y);
    }
  }
  for (const auto& e : kEdges) {
    const glm::dvec3& a = p[e[0]];
    const glm::dvec3& b = p[e[1]];
    const double da = a.z - z_mm, db = b.z - z_mm;
    if ((da < -near && db > near) || (da > near && db < -near)) {
      const double y = a.y + (b.y - a.y) * (da / (da - db));
      y_lo = std::min(y_lo, y);
      y_hi = std::max(y_hi, y);
    }
  }
  if (!(y_lo <= y_hi)) return {0, -1};
  const double slack = 1e-7;
  return {std::max(r.lo[1], ClampToIndex(std::ceil(y_lo / sy - slack), 0, ny)),
          std::min(r.hi[1], ClampToIndex(std::floor(y_hi / sy + slack), -1, ny - 1))};
}

// Tets listed per slice k (CSR), ascending within each slice.
struct SliceLists {
  std::vector<int64_t> begin;  // nz + 1
  std::vector<int32_t> tets;
};

SliceLists ListTetsPerSlice(const std::vector<TetRaster>& rasters, int64_t nz) {
  SliceLists lists;
  lists.begin.assign(nz + 1, 0);
  for (const TetRaster& r : rasters) {
    if (r.flat) continue;
    for (int64_t k = r.lo[2]; k <= r.hi[2]; ++k) ++lists.begin[k + 1];
  }
  for (int64_t k = 0; k < nz; ++k) lists.begin[k + 1] += lists.begin[k];
  lists.tets.resize(lists.begin[nz]);
  std::vector<int64_t> cursor(lists.begin.begin(), lists.begin.end() - 1);
  for (size_t t = 0; t < rasters.size(); ++t) {
    const TetRaster& r = rasters[t];
    if (r.flat) continue;
    for (int64_t k = r.lo[2]; k <= r.hi[2]; ++k) lists.tets[cursor[k]++] = static_cast<int32_t>(t);
  }
  return lists;
}

// Rasterizes slices [k_begin, k_end) row by row, so that the callback walks
// memory in order; returns the voxels visited.
int64_t RasterizeSlab(const VolumeGeometry& g, const std::vector<TetRaster>& rasters,
                      const SliceLists& slices, double eps, int64_t k_begin, int64_t k_end,
                      const std::function<void(const VoxelRun&)>& visit) {
  const int64_t nx = g.dims[0], ny = g.dims[1];
  const glm::dvec3 s = g.spacing_mm;
  // Row r's voxel i is taken when taken[i] == r + 1 (no clearing per row).
  std::vector<int64_t> taken(nx, 0);
  int64_t row_serial = 0;
  std::vector<int64_t> row_begin(ny + 1);
  std::vector<int32_t> row_tets;
  std::vector<std::pair<int64_t, int64_t>> rows;  // per tet of the slice: its rows
  int64_t count = 0;
  for (int64_t k = k_begin; k < k_end; ++k) {
    // The slice's tets listed per row j, ascending (CSR).
    const int64_t first = slices.begin[k], last = slices.begin[k + 1];
    rows.resize(last - first);
    std::fill(row_begin.begin(), row_begin.end(), 0);
    for (int64_t n = first; n < last; ++n) {
      rows[n - first] = SectionRows(rasters[slices.tets[n]], k * s.z, s.y, ny);
      for (int64_t j = rows[n - first].first; j <= rows[n - first].second; ++j) ++row_begin[j + 1];
    }
    for (int64_t j = 0; j < ny; ++j) row_begin[j + 1] += row_begin[j];
    row_tets.resize(row_begin[ny]);
    std::vector<int64_t> cursor(row_begin.begin(), row_begin.end() - 1);
    for (int64_t n = first; n < last; ++n) {
      for (int64_t j = rows[n - first].first; j <= rows[n - first].second; ++j) {
        row_tets[cursor[j]++] = slices.tets[n];
      }
    }
    for (int64_t j = 0; j < ny; ++j) {
      const int64_t serial = ++row_serial;
      for (int64_t n = row_begin[j]; n < row_begin[j + 1]; ++n) {
        const TetRaster& r = rasters[row_tets[n]];
        const auto [i_begin, i_end] = RowInterval(r, s, nx, j, k, eps);
        const double value_row =
            r.value0 + glm::dot(r.gradient, glm::dvec3(0.0, j * s.y, k * s.z) - r.p0);
        const double step = r.gradient.x * s.x;
        // Split into runs of voxels no smaller tet has taken.
        for (int64_t i = i_begin; i < i_end;) {
          while (i < i_end && taken[i] == serial) ++i;
          const int64_t run_begin = i;
          while (i < i_end && taken[i] != serial) taken[i++] = serial;
          if (i == run_begin) continue;
          visit(VoxelRun{run_begin, i, j, k, row_tets[n],
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
  const int64_t nz = geometry.dims[2];
  const SliceLists slices = ListTetsPerSlice(rasters, nz);
  const int threads = static_cast<int>(std::clamp<int64_t>(options.threads, 1, nz));
  std::vector<int64_t> counts(threads, 0);
  ParallelChunks(threads, nz, [&](int64_t k_begin, int64_t k_end, int part) {
    counts[part] = RasterizeSlab(geometry, rasters, slices, options.eps, k_begin, k_end, visit);
  });
  int64_t total = 0;
  for (int64_t c : counts) total += c;
  return total;
}

}  // namespace vpm
