#include "server/phantom/phantom_shapes.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace vpm::phantom {
namespace {

constexpr double kHugeMm = 1.0e9;

class Ellipsoid final : public Shape {
 public:
  Ellipsoid(const glm::dvec3& center, const glm::dvec3& semi, const glm::dmat3& frame)
      : center_(center), semi_(semi), to_local_(glm::transpose(frame)) {
    // Half-extent of the rotated ellipsoid along world axis w:
    // sqrt(sum_c (frame[c][w] * semi[c])^2).
    glm::dvec3 half(0.0);
    for (int w = 0; w < 3; ++w) {
      double sum = 0.0;
      for (int c = 0; c < 3; ++c) sum += frame[c][w] * frame[c][w] * semi[c] * semi[c];
      half[w] = std::sqrt(sum);
    }
    bounds_ = {center - half, center + half};
  }
  Box3 Bounds() const override { return bounds_; }
  double Distance(const glm::dvec3& p) const override {
    // First-order distance (Quilez): exact on the surface, k0 = |q/r| level set.
    const glm::dvec3 q = to_local_ * (p - center_);
    const double k0 = glm::length(q / semi_);
    const double k1 = glm::length(q / (semi_ * semi_));
    if (k1 < 1e-12) return -std::min({semi_.x, semi_.y, semi_.z});
    return k0 * (k0 - 1.0) / k1;
  }

 private:
  glm::dvec3 center_;
  glm::dvec3 semi_;
  glm::dmat3 to_local_;
  Box3 bounds_;
};

struct Segment {
  glm::dvec3 a;
  glm::dvec3 ab;
  double inv_len2;  // 1 / |ab|^2, 0 for a point
  double radius_a;
  double radius_b;
  Box3 box;
};

double SegmentDistance(const Segment& s, const glm::dvec3& p) {
  const glm::dvec3 ap = p - s.a;
  const double t = std::clamp(glm::dot(ap, s.ab) * s.inv_len2, 0.0, 1.0);
  return glm::length(ap - t * s.ab) - (s.radius_a + t * (s.radius_b - s.radius_a));
}

class Tube final : public Shape {
 public:
  explicit Tube(const std::vector<std::vector<TubeNode>>& polylines) {
    for (const auto& line : polylines) {
      if (line.size() == 1) AddSegment(line[0], line[0]);
      for (size_t n = 0; n + 1 < line.size(); ++n) AddSegment(line[n], line[n + 1]);
    }
  }
  Box3 Bounds() const override { return bounds_; }
  double Distance(const glm::dvec3& p) const override {
    double d = kHugeMm;
    for (const Segment& s : segments_) d = std::min(d, SegmentDistance(s, p));
    return d;
  }

 protected:
  void RowDistanceInRange(const SampleRow& row, double reach_mm, IndexRange range,
                          std::span<float> out) const override {
    for (const Segment& s : segments_) {
      const Box3 box = s.box.Expanded(reach_mm);
      if (!box.CoversYZ(row.y_mm, row.z_mm)) continue;
      IndexRange r = RowRangeInBox(box, row, out.size());
      r.begin = std::max(r.begin, range.begin);
      r.end = std::min(r.end, range.end);
      for (size_t n = r.begin; n < r.end; ++n) {
        out[n] = std::min(out[n], static_cast<float>(SegmentDistance(s, row.Point(n))));
      }
    }
  }

 private:
  void AddSegment(const TubeNode& a, const TubeNode& b) {
    Segment s{a.point_mm, b.point_mm - a.point_mm, 0.0, a.radius_mm, b.radius_mm, {}};
    const double len2 = glm::dot(s.ab, s.ab);
    s.inv_len2 = len2 > 0.0 ? 1.0 / len2 : 0.0;
    const double r = std::max(a.radius_mm, b.radius_mm);
    s.box = {glm::min(a.point_mm, b.point_mm) - r, glm::max(a.point_mm, b.point_mm) + r};
    bounds_ = segments_.empty() ? s.box : BoxUnion(bounds_, s.box);
    segments_.push_back(s);
  }

  std::vector<Segment> segments_;
  Box3 bounds_;
};

class EllipticPrism final : public Shape {
 public:
  EllipticPrism(const glm::dvec2& center, const glm::dvec2& semi, double z_lo, double z_hi,
                double round)
      : center_(center), semi_(semi), z_lo_(z_lo), z_hi_(z_hi), round_(round) {}
  Box3 Bounds() const override {
    return {{center_.x - semi_.x, center_.y - semi_.y, z_lo_},
            {center_.x + semi_.x, center_.y + semi_.y, z_hi_}};
  }
  double Distance(const glm::dvec3& p) const override {
    // Rounded rim: distances of the prism shrunk by round_, then offset out.
    const double radial = EllipseDistance(glm::dvec2(p.x, p.y) - center_, semi_) + round_;
    const double axial = std::max(z_lo_ - p.z, p.z - z_hi_) + round_;
    const double outside = std::hypot(std::max(radial, 0.0), std::max(axial, 0.0));
    return outside + std::min(std::max(radial, axial), 0.0) - round_;
  }

 private:
  glm::dvec2 center_;
  glm::dvec2 semi_;
  double z_lo_;
  double z_hi_;
  double round_;
};

class HalfSpace final : public Shape {
 public:
  HalfSpace(const glm::dvec3& point, const glm::dvec3& normal) : point_(point), normal_(normal) {}
  Box3 Bounds() const override { return {glm::dvec3(-kHugeMm), glm::dvec3(kHugeMm)}; }
  double Distance(const glm::dvec3& p) const override { return glm::dot(p - point_, normal_); }

 private:
  glm::dvec3 point_;
  glm::dvec3 normal_;
};

enum class BooleanOp { kUnion, kIntersection, kDifference };

class Boolean final : public Shape {
 public:
  Boolean(BooleanOp op, ShapePtr a, ShapePtr b) : op_(op), a_(std::move(a)), b_(std::move(b)) {}
  Box3 Bounds() const override {
    switch (op_) {
      case BooleanOp::kUnion:
        return BoxUnion(a_->Bounds(), b_->Bounds());
      case BooleanOp::kIntersection:
        return BoxIntersection(a_->Bounds(), b_->Bounds());
      case BooleanOp::kDifference:
        break;
    }
    return a_->Bounds();
  }
  double Distance(const glm::dvec3& p) const override {
    return Combine(a_->Distance(p), b_->Distance(p));
  }

 protected:
  void RowDistanceInRange(const SampleRow& row, double reach_mm, IndexRange range,
                          std::span<float> out) const override {
    const size_t count = range.end - range.begin;
    const SampleRow sub = row.Shifted(range.begin);
    std::span<float> out_a = out.subspan(range.begin, count);
    a_->RowDistance(sub, reach_mm, out_a);
    std::vector<float> out_b(count);
    b_->RowDistance(sub, reach_mm, out_b);
    for (size_t n = 0; n < count; ++n) {
      out_a[n] = static_cast<float>(Combine(out_a[n], out_b[n]));
    }
  }

 private:
  double Combine(double a, double b) const {
    switch (op_) {
      case BooleanOp::kUnion:
        return std::min(a, b);
      case BooleanOp::kIntersection:
        return std::max(a, b);
      case BooleanOp::kDifference:
        break;
    }
    return std::max(a, -b);
  }

  BooleanOp op_;
  ShapePtr a_;
  ShapePtr b_;
};

class Inset final : public Shape {
 public:
  Inset(ShapePtr a, double inset) : a_(std::move(a)), inset_(inset) {}
  Box3 Bounds() const override { return a_->Bounds().Expanded(std::max(-inset_, 0.0)); }
  double Distance(const glm::dvec3& p) const override { return a_->Distance(p) + inset_; }

 protected:
  void RowDistanceInRange(const SampleRow& row, double reach_mm, IndexRange range,
                          std::span<float> out) const override {
    std::span<float> sub = out.subspan(range.begin, range.end - range.begin);
    // The child must be exact over (-reach - inset, reach - inset).
    a_->RowDistance(row.Shifted(range.begin), reach_mm + std::abs(inset_), sub);
    for (float& d : sub) d += static_cast<float>(inset_);
  }

 private:
  ShapePtr a_;
  double inset_;
};

}  // namespace

Box3 BoxUnion(const Box3& a, const Box3& b) { return {glm::min(a.lo, b.lo), glm::max(a.hi, b.hi)}; }

Box3 BoxIntersection(const Box3& a, const Box3& b) {
  return {glm::max(a.lo, b.lo), glm::min(a.hi, b.hi)};
}

IndexRange RowRangeInBox(const Box3& box, const SampleRow& row, size_t count) {
  const double first = std::ceil((box.lo.x - row.x0_mm) / row.dx_mm);
  const double last = std::floor((box.hi.x - row.x0_mm) / row.dx_mm);
  const double n = static_cast<double>(count);
  IndexRange r;
  r.begin = static_cast<size_t>(std::clamp(first, 0.0, n));
  r.end = static_cast<size_t>(std::clamp(last + 1.0, 0.0, n));
  return r;
}

void Shape::RowDistance(const SampleRow& row, double reach_mm, std::span<float> out) const {
  std::fill(out.begin(), out.end(), kFarMm);
  const Box3 box = Bounds().Expanded(reach_mm);
  if (!box.CoversYZ(row.y_mm, row.z_mm)) return;
  const IndexRange range = RowRangeInBox(box, row, out.size());
  if (!range.empty()) RowDistanceInRange(row, reach_mm, range, out);
}

void Shape::RowDistanceInRange(const SampleRow& row, double /*reach_mm*/, IndexRange range,
                               std::span<float> out) const {
  for (size_t n = range.begin; n < range.end; ++n) {
    out[n] = static_cast<float>(Distance(row.Point(n)));
  }
}

ShapePtr MakeEllipsoid(const glm::dvec3& center_mm, const glm::dvec3& semi_axes_mm,
                       const glm::dmat3& frame) {
  return std::make_shared<Ellipsoid>(center_mm, semi_axes_mm, frame);
}

ShapePtr MakeTube(const std::vector<std::vector<TubeNode>>& polylines) {
  return std::make_shared<Tube>(polylines);
}

ShapePtr MakeEllipticPrism(const glm::dvec2& center_mm, const glm::dvec2& semi_axes_mm,
                           double z_lo_mm, double z_hi_mm, double round_mm) {
  return std::make_shared<EllipticPrism>(center_mm, semi_axes_mm, z_lo_mm, z_hi_mm, round_mm);
}

ShapePtr MakeHalfSpace(const glm::dvec3& point_mm, const glm::dvec3& unit_normal) {
  return std::make_shared<HalfSpace>(point_mm, unit_normal);
}

ShapePtr MakeUnion(ShapePtr a, ShapePtr b) {
  return std::make_shared<Boolean>(BooleanOp::kUnion, std::move(a), std::move(b));
}

ShapePtr MakeIntersection(ShapePtr a, ShapePtr b) {
  return std::make_shared<Boolean>(BooleanOp::kIntersection, std::move(a), std::move(b));
}

ShapePtr MakeDifference(ShapePtr a, ShapePtr b) {
  return std::make_shared<Boolean>(BooleanOp::kDifference, std::move(a), std::move(b));
}

ShapePtr MakeInset(ShapePtr a, double inset_mm) {
  return std::make_shared<Inset>(std::move(a), inset_mm);
}

double EllipseDistance(const glm::dvec2& q_mm, const glm::dvec2& semi_mm) {
  const double k0 = glm::length(q_mm / semi_mm);
  const double k1 = glm::length(q_mm / (semi_mm * semi_mm));
  if (k1 < 1e-12) return -std::min(semi_mm.x, semi_mm.y);
  return k0 * (k0 - 1.0) / k1;
}

double PolylineLength(std::span<const glm::dvec3> points_mm) {
  double length = 0.0;
  for (size_t n = 1; n < points_mm.size(); ++n) {
    length += glm::length(points_mm[n] - points_mm[n - 1]);
  }
  return length;
}

glm::dvec3 PointAtArcLength(std::span<const glm::dvec3> points_mm, double s_mm) {
  if (points_mm.empty()) return glm::dvec3(0.0);
  for (size_t n = 1; n < points_mm.size(); ++n) {
    const double len = glm::length(points_mm[n] - points_mm[n - 1]);
    if (s_mm <= len && len > 0.0) {
      return points_mm[n - 1] + (std::max(s_mm, 0.0) / len) * (points_mm[n] - points_mm[n - 1]);
    }
    s_mm -= len;
  }
  return points_mm.back();
}

}  // namespace vpm::phantom
