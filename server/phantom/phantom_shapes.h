// Signed-distance shapes for the synthetic phantoms, in world mm (LPS).
//
// A shape's signed distance is negative inside, zero on the surface, in mm.
// Spheres, capsules, half-spaces and their Boolean combinations are exact (up
// to the usual min/max approximations of Booleans); ellipses and ellipsoids
// use a first-order approximation that is exact on the surface and within a
// few percent inside a few mm of it, which is what partial-volume blending and
// shells (cortex, wall) of up to ~6 mm need.
//
// Shapes are evaluated one voxel row at a time (constant y and z), so that
// each shape can cull what it holds (tube segments) once per row.
#pragma once

#include <memory>
#include <span>
#include <vector>

#include <glm/glm.hpp>

namespace vpm::phantom {

// What a shape writes where it is further than `reach_mm` outside (culled).
inline constexpr float kFarMm = 1.0e6f;

// Axis-aligned box, world mm.
struct Box3 {
  glm::dvec3 lo{0.0};
  glm::dvec3 hi{0.0};

  Box3 Expanded(double mm) const { return {lo - mm, hi + mm}; }
  bool CoversYZ(double y_mm, double z_mm) const {
    return y_mm >= lo.y && y_mm <= hi.y && z_mm >= lo.z && z_mm <= hi.z;
  }
};
Box3 BoxUnion(const Box3& a, const Box3& b);
Box3 BoxIntersection(const Box3& a, const Box3& b);

// A row of sample points (x0_mm + n * dx_mm, y_mm, z_mm), n in [0, count).
struct SampleRow {
  double x0_mm = 0.0;
  double dx_mm = 1.0;
  double y_mm = 0.0;
  double z_mm = 0.0;

  glm::dvec3 Point(size_t n) const { return {x0_mm + static_cast<double>(n) * dx_mm, y_mm, z_mm}; }
  SampleRow Shifted(size_t n) const {
    return {x0_mm + static_cast<double>(n) * dx_mm, dx_mm, y_mm, z_mm};
  }
};

// Half-open range [begin, end) of row indices whose points lie in `box` (x).
struct IndexRange {
  size_t begin = 0;
  size_t end = 0;
  bool empty() const { return begin >= end; }
};
IndexRange RowRangeInBox(const Box3& box, const SampleRow& row, size_t count);

class Shape {
 public:
  virtual ~Shape() = default;

  // A box (world mm) outside which the signed distance is positive.
  virtual Box3 Bounds() const = 0;
  // Signed distance (mm) at a world point (mm).
  virtual double Distance(const glm::dvec3& p) const = 0;

  // out[n] = signed distance at row.Point(n), exact (as Distance) where its
  // magnitude is under reach_mm. Beyond, only the side is kept: any value
  // >= reach_mm outside (kFarMm where the shape culls), <= -reach_mm inside.
  // Callers pass the largest distance magnitude they use.
  void RowDistance(const SampleRow& row, double reach_mm, std::span<float> out) const;

 protected:
  // RowDistance restricted to out[range] (points inside Bounds + reach);
  // the default evaluates Distance point by point.
  virtual void RowDistanceInRange(const SampleRow& row, double reach_mm, IndexRange range,
                                  std::span<float> out) const;
};
using ShapePtr = std::shared_ptr<const Shape>;

// Ellipsoid with semi-axes (mm) along the columns of `frame` (orthonormal,
// world unit vectors), centred at `center_mm`.
ShapePtr MakeEllipsoid(const glm::dvec3& center_mm, const glm::dvec3& semi_axes_mm,
                       const glm::dmat3& frame = glm::dmat3(1.0));

// One node of a tube: a centreline point (mm) and the radius there (mm).
struct TubeNode {
  glm::dvec3 point_mm{0.0};
  double radius_mm = 1.0;
};
// Union of round tubes along polylines (capsules between consecutive nodes,
// radius interpolated linearly along each segment). Each polyline needs at
// least one node (a single node is a sphere).
ShapePtr MakeTube(const std::vector<std::vector<TubeNode>>& polylines);

// Prism along z with an elliptical cross-section: semi-axes (mm) around
// centre (x, y) mm, between z_lo_mm and z_hi_mm, its rim rounded with radius
// round_mm (0: sharp).
ShapePtr MakeEllipticPrism(const glm::dvec2& center_mm, const glm::dvec2& semi_axes_mm,
                           double z_lo_mm, double z_hi_mm, double round_mm);

// Half-space of points p with dot(p - point_mm, unit_normal) < 0.
ShapePtr MakeHalfSpace(const glm::dvec3& point_mm, const glm::dvec3& unit_normal);

ShapePtr MakeUnion(ShapePtr a, ShapePtr b);
ShapePtr MakeIntersection(ShapePtr a, ShapePtr b);
ShapePtr MakeDifference(ShapePtr a, ShapePtr b);  // a minus b
// The shape shrunk by inset_mm (its surface moved inwards by that distance;
// a negative inset grows it).
ShapePtr MakeInset(ShapePtr a, double inset_mm);

// Approximate signed distance (mm) to the ellipse with semi-axes `semi_mm`
// centred at the origin, at the 2D point `q_mm`.
double EllipseDistance(const glm::dvec2& q_mm, const glm::dvec2& semi_mm);

// Polyline helpers (mm), used to place landmarks on vessel centrelines.
double PolylineLength(std::span<const glm::dvec3> points_mm);
// The point at arc length s_mm from the first point (clamped to the ends).
glm::dvec3 PointAtArcLength(std::span<const glm::dvec3> points_mm, double s_mm);

}  // namespace vpm::phantom
