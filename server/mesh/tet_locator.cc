#include "server/mesh/tet_locator.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vpm {

Result<TetLocator> TetLocator::Create(std::vector<glm::dvec3> positions,
                                      std::vector<std::array<int32_t, 4>> tets,
                                      const Options& options) {
  for (size_t v = 0; v < positions.size(); ++v) {
    const glm::dvec3& p = positions[v];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
      return absl::InvalidArgumentError(StrCat("TetLocator: position ", v, " is not finite"));
    }
  }
  const int64_t vertex_count = static_cast<int64_t>(positions.size());
  for (size_t t = 0; t < tets.size(); ++t) {
    for (int32_t v : tets[t]) {
      if (v < 0 || v >= vertex_count) {
        return absl::InvalidArgumentError(StrCat("TetLocator: tet ", t, " has vertex index ", v,
                                                 ", outside [0, ", vertex_count, ")"));
      }
    }
  }
  if (!(options.eps >= 0.0) || !(options.tets_per_bucket > 0.0)) {
    return absl::InvalidArgumentError("TetLocator: eps must be >= 0 and tets_per_bucket > 0");
  }

  TetLocator locator;
  locator.options_ = options;
  locator.positions_ = std::move(positions);
  locator.tets_ = std::move(tets);
  const auto& P = locator.positions_;
  const auto& T = locator.tets_;

  locator.inverse_.resize(T.size());
  locator.flat_.assign(T.size(), 0);
  glm::dvec3 lo(std::numeric_limits<double>::infinity());
  glm::dvec3 hi(-std::numeric_limits<double>::infinity());
  for (size_t t = 0; t < T.size(); ++t) {
    const glm::dmat3 m(P[T[t][1]] - P[T[t][0]], P[T[t][2]] - P[T[t][0]], P[T[t][3]] - P[T[t][0]]);
    const double det = glm::determinant(m);
    if (det == 0.0 || !std::isfinite(det)) {
      locator.flat_[t] = 1;
    } else {
      locator.inverse_[t] = glm::inverse(m);
    }
    for (int32_t v : T[t]) {
      lo = glm::min(lo, P[v]);
      hi = glm::max(hi, P[v]);
    }
  }
  if (T.empty()) lo = hi = glm::dvec3(0.0);

  // Buckets of about tets_per_bucket tets each, cubes of edge bucket_mm_.
  const glm::dvec3 size = hi - lo;
  const double diagonal = glm::length(size);
  const double margin = 4.0 * (options.eps + 1e-12) * diagonal;
  lo -= margin;
  hi += margin;
  const double largest = std::max({size.x, size.y, size.z, 1e-300});
  const double bucket_count =
      std::clamp(static_cast<double>(T.size()) / options.tets_per_bucket, 1.0, 16.0 * 1024 * 1024);
  const glm::dvec3 span = glm::max(hi - lo, glm::dvec3(largest * 1e-6));
  double edge = std::cbrt(span.x * span.y * span.z / bucket_count);
  for (int a = 0; a < 3; ++a) {
    locator.buckets_[a] =
        std::clamp<int64_t>(static_cast<int64_t>(std::ceil(span[a] / edge)), 1, 512);
  }
  edge = std::max(
      {span.x / locator.buckets_[0], span.y / locator.buckets_[1], span.z / locator.buckets_[2]});
  locator.lo_mm_ = lo;
  locator.hi_mm_ = hi;
  locator.bucket_mm_ = edge;

  // Two passes over the tets' bounding boxes: count, then fill (CSR), tets
  // in ascending order so the first hit of a query is the smallest index.
  const auto& nb = locator.buckets_;
  auto bucket_range = [&](size_t t, std::array<int64_t, 3>& b0, std::array<int64_t, 3>& b1) {
    glm::dvec3 tlo = P[T[t][0]], thi = P[T[t][0]];
    for (int32_t v : T[t]) {
      tlo = glm::min(tlo, P[v]);
      thi = glm::max(thi, P[v]);
    }
    for (int a = 0; a < 3; ++a) {
      b0[a] = std::clamp<int64_t>(
          static_cast<int64_t>(std::floor((tlo[a] - margin - lo[a]) / edge)), 0, nb[a] - 1);
      b1[a] = std::clamp<int64_t>(
          static_cast<int64_t>(std::floor((thi[a] + margin - lo[a]) / edge)), 0, nb[a] - 1);
    }
  };
  locator.bucket_begin_.assign(nb[0] * nb[1] * nb[2] + 1, 0);
  for (int pass = 0; pass < 2; ++pass) {
    std::vector<int64_t> cursor;
    if (pass == 1) {
      for (size_t b = 1; b < locator.bucket_begin_.size(); ++b) {
        locator.bucket_begin_[b] += locator.bucket_begin_[b - 1];
      }
      locator.bucket_tets_.resize(locator.bucket_begin_.back());
      cursor.assign(locator.bucket_begin_.begin(), locator.bucket_begin_.end() - 1);
    }
    for (size_t t = 0; t < T.size(); ++t) {
      if (locator.flat_[t]) continue;
      std::array<int64_t, 3> b0, b1;
      bucket_range(t, b0, b1);
      for (int64_t k = b0[2]; k <= b1[2]; ++k) {
        for (int64_t j = b0[1]; j <= b1[1]; ++j) {
          for (int64_t i = b0[0]; i <= b1[0]; ++i) {
            const int64_t b = i + nb[0] * (j + nb[1] * k);
            if (pass == 0) {
              ++locator.bucket_begin_[b + 1];
            } else {
              locator.bucket_tets_[cursor[b]++] = static_cast<int32_t>(t);
            }
          }
        }
      }
    }
  }
  return locator;
}

int64_t TetLocator::BucketOf(const glm::dvec3& p_mm) const {
  int64_t b[3];
  for (int a = 0; a < 3; ++a) {
    if (!(p_mm[a] >= lo_mm_[a] && p_mm[a] <= hi_mm_[a])) return -1;
    b[a] = std::clamp<int64_t>(static_cast<int64_t>(std::floor((p_mm[a] - lo_mm_[a]) / bucket_mm_)),
                               0, buckets_[a] - 1);
  }
  return b[0] + buckets_[0] * (b[1] + buckets_[1] * b[2]);
}

std::array<double, 4> TetLocator::Barycentric(int32_t tet, const glm::dvec3& p_mm) const {
  if (flat_[tet]) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    return {nan, nan, nan, nan};
  }
  const glm::dvec3 w = inverse_[tet] * (p_mm - positions_[tets_[tet][0]]);
  return {1.0 - w.x - w.y - w.z, w.x, w.y, w.z};
}

std::optional<TetLocator::Location> TetLocator::Locate(const glm::dvec3& p_mm) const {
  const int64_t bucket = BucketOf(p_mm);
  if (bucket < 0) return std::nullopt;
  const double floor_weight = -options_.eps;
  for (int64_t n = bucket_begin_[bucket]; n < bucket_begin_[bucket + 1]; ++n) {
    const int32_t t = bucket_tets_[n];
    const std::array<double, 4> w = Barycentric(t, p_mm);
    if (w[0] >= floor_weight && w[1] >= floor_weight && w[2] >= floor_weight &&
        w[3] >= floor_weight) {
      return Location{t, w};
    }
  }
  return std::nullopt;
}

}  // namespace vpm
