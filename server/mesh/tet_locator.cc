#include "server/mesh/tet_locator.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vpm {

namespace {

Status CheckInput(const std::vector<glm::dvec3>& positions,
                  const std::vector<std::array<int32_t, 4>>& tets,
                  const TetLocator::Options& options) {
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
  return absl::OkStatus();
}

}  // namespace

Result<TetLocator> TetLocator::Create(std::vector<glm::dvec3> positions,
                                      std::vector<std::array<int32_t, 4>> tets,
                                      const Options& options) {
  RETURN_IF_ERROR(CheckInput(positions, tets, options));
  TetLocator locator;
  locator.options_ = options;
  locator.positions_ = std::move(positions);
  locator.tets_ = std::move(tets);
  locator.PrepareTets();
  locator.SizeGrid();
  locator.FillBuckets();
  return locator;
}

void TetLocator::PrepareTets() {
  const auto& P = positions_;
  inverse_.resize(tets_.size());
  flat_.assign(tets_.size(), 0);
  glm::dvec3 lo(std::numeric_limits<double>::infinity());
  glm::dvec3 hi(-std::numeric_limits<double>::infinity());
  for (size_t t = 0; t < tets_.size(); ++t) {
    const auto& q = tets_[t];
    const glm::dmat3 m(P[q[1]] - P[q[0]], P[q[2]] - P[q[0]], P[q[3]] - P[q[0]]);
    const double det = glm::determinant(m);
    if (det == 0.0 || !std::isfinite(det)) {
      flat_[t] = 1;
    } else {
      inverse_[t] = glm::inverse(m);
    }
    for (int32_t v : q) {
      lo = glm::min(lo, P[v]);
      hi = glm::max(hi, P[v]);
    }
  }
  if (tets_.empty()) lo = hi = glm::dvec3(0.0);
  lo_mm_ = lo;
  hi_mm_ = hi;
}

void TetLocator::SizeGrid() {
  // Widened so that points found with weights >= -eps still fall inside.
  const glm::dvec3 size = hi_mm_ - lo_mm_;
  margin_mm_ = 4.0 * (options_.eps + 1e-12) * glm::length(size);
  lo_mm_ -= margin_mm_;
  hi_mm_ += margin_mm_;
  // Cubic buckets, about tets_per_bucket tets each.
  const double largest = std::max({size.x, size.y, size.z, 1e-300});
  const double bucket_count = std::clamp(
      static_cast<double>(tets_.size()) / options_.tets_per_bucket, 1.0, 16.0 * 1024 * 1024);
  const glm::dvec3 span = glm::max(hi_mm_ - lo_mm_, glm::dvec3(largest * 1e-6));
  const double edge = std::cbrt(span.x * span.y * span.z / bucket_count);
  for (int a = 0; a < 3; ++a) {
    buckets_[a] = std::clamp<int64_t>(static_cast<int64_t>(std::ceil(span[a] / edge)), 1, 512);
  }
  bucket_mm_ = std::max({span.x / buckets_[0], span.y / buckets_[1], span.z / buckets_[2]});
}

void TetLocator::FillBuckets() {
  // Two passes over the tets' bounding boxes: count, then fill (CSR), tets
  // in ascending order so the first hit of a query is the smallest index.
  auto bucket_range = [&](size_t t, std::array<int64_t, 3>& b0, std::array<int64_t, 3>& b1) {
    glm::dvec3 lo = positions_[tets_[t][0]], hi = lo;
    for (int32_t v : tets_[t]) {
      lo = glm::min(lo, positions_[v]);
      hi = glm::max(hi, positions_[v]);
    }
    for (int a = 0; a < 3; ++a) {
      const double b_lo = std::floor((lo[a] - margin_mm_ - lo_mm_[a]) / bucket_mm_);
      const double b_hi = std::floor((hi[a] + margin_mm_ - lo_mm_[a]) / bucket_mm_);
      b0[a] = std::clamp<int64_t>(static_cast<int64_t>(b_lo), 0, buckets_[a] - 1);
      b1[a] = std::clamp<int64_t>(static_cast<int64_t>(b_hi), 0, buckets_[a] - 1);
    }
  };
  const auto& nb = buckets_;
  bucket_begin_.assign(nb[0] * nb[1] * nb[2] + 1, 0);
  std::vector<int64_t> cursor;
  for (int pass = 0; pass < 2; ++pass) {
    if (pass == 1) {
      for (size_t b = 1; b < bucket_begin_.size(); ++b) bucket_begin_[b] += bucket_begin_[b - 1];
      bucket_tets_.resize(bucket_begin_.back());
      cursor.assign(bucket_begin_.begin(), bucket_begin_.end() - 1);
    }
    for (size_t t = 0; t < tets_.size(); ++t) {
      if (flat_[t]) continue;
      std::array<int64_t, 3> b0, b1;
      bucket_range(t, b0, b1);
      for (int64_t k = b0[2]; k <= b1[2]; ++k) {
        for (int64_t j = b0[1]; j <= b1[1]; ++j) {
          for (int64_t i = b0[0]; i <= b1[0]; ++i) {
            const int64_t b = i + nb[0] * (j + nb[1] * k);
            if (pass == 0) {
              ++bucket_begin_[b + 1];
            } else {
              bucket_tets_[cursor[b]++] = static_cast<int32_t>(t);
            }
          }
        }
      }
    }
  }
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
