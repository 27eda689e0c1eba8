#include "server/raycast/slice_grid.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vpm {
namespace {

struct Axes {
  glm::dvec3 normal, u, v;  // world, unit
};

Axes NamedAxes(SliceOrientation o) {
  switch (o) {
    case SliceOrientation::kCoronal: return {{0, 1, 0}, {1, 0, 0}, {0, 0, -1}};
    case SliceOrientation::kSagittal: return {{1, 0, 0}, {0, 1, 0}, {0, 0, -1}};
    default: return {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}};
  }
}

// Right = normal x S for planes that are not near-axial (so a coronal-like
// plane keeps patient left to the right), else +x projected into the plane.
Axes ObliqueAxes(const glm::dvec3& normal) {
  const glm::dvec3 n = glm::normalize(normal);
  const glm::dvec3 superior(0.0, 0.0, 1.0);
  glm::dvec3 u;
  if (std::abs(n.z) < 0.9) {
    u = glm::normalize(glm::cross(superior, n));
    if (glm::dot(u, glm::dvec3(1.0, 1.0, 0.0)) < 0.0) u = -u;  // left or posterior to the right
  } else {
    u = glm::normalize(glm::dvec3(1.0, 0.0, 0.0) - n.x * n);
  }
  glm::dvec3 v = glm::cross(n, u);
  if (std::abs(n.z) < 0.9 ? v.z > 0.0 : v.y < 0.0) v = -v;  // inferior (or posterior) down
  return {n, u, v};
}

// The plane's own numbers: an oblique plane's point and normal, a named
// plane's position.
Status CheckSlicePlane(const SlicePlane& plane) {
  if (plane.orientation == SliceOrientation::kOblique) {
    const glm::dvec3& n = plane.normal;
    const glm::dvec3& p = plane.point_mm;
    if (!(std::isfinite(n.x) && std::isfinite(n.y) && std::isfinite(n.z) &&
          glm::length(n) > 1e-12 && std::isfinite(p.x) && std::isfinite(p.y) &&
          std::isfinite(p.z))) {
      return absl::InvalidArgumentError(
          "oblique slice: the point and a non-zero normal must be finite");
    }
  } else if (!std::isfinite(plane.at_mm)) {
    return absl::InvalidArgumentError("slice position must be a finite number (mm)");
  }
  return absl::OkStatus();
}

// The volume box's world corners projected on the axes: their spread along
// the normal (lo_n..hi_n, mm) says whether the plane meets the box, their
// spread along u and v (lo..hi, mm) sizes the image.
struct BoxProjection {
  double lo_n = std::numeric_limits<double>::infinity();
  double hi_n = -std::numeric_limits<double>::infinity();
  glm::dvec2 lo{std::numeric_limits<double>::infinity()};
  glm::dvec2 hi{-std::numeric_limits<double>::infinity()};
};

BoxProjection ProjectBox(const Axes& axes, const VolumeGeometry& geometry) {
  const glm::dvec3 extent = geometry.extent_mm();
  BoxProjection p;
  for (int c = 0; c < 8; ++c) {
    const glm::dvec3 corner(c & 1 ? extent.x : 0.0, c & 2 ? extent.y : 0.0, c & 4 ? extent.z : 0.0);
    const glm::dvec3 w = geometry.PhysicalToWorld(corner);
    const double along = glm::dot(axes.normal, w);
    p.lo_n = std::min(p.lo_n, along);
    p.hi_n = std::max(p.hi_n, along);
    const glm::dvec2 uv(glm::dot(axes.u, w), glm::dot(axes.v, w));
    p.lo = glm::min(p.lo, uv);
    p.hi = glm::max(p.hi, uv);
  }
  return p;
}

}  // namespace

Result<SliceOrientation> SliceOrientationFromName(std::string_view name) {
  if (name == "axial") return SliceOrientation::kAxial;
  if (name == "coronal") return SliceOrientation::kCoronal;
  if (name == "sagittal") return SliceOrientation::kSagittal;
  if (name == "oblique") return SliceOrientation::kOblique;
  return absl::InvalidArgumentError(
      StrCat("plane '", name, "': use axial, coronal, sagittal or oblique"));
}

std::string_view SliceOrientationName(SliceOrientation orientation) {
  switch (orientation) {
    case SliceOrientation::kAxial: return "axial";
    case SliceOrientation::kCoronal: return "coronal";
    case SliceOrientation::kSagittal: return "sagittal";
    case SliceOrientation::kOblique: return "oblique";
  }
  return "?";
}

Result<SliceGrid> MakeSliceGrid(const SlicePlane& plane, const VolumeGeometry& geometry,
                                double pixel_mm) {
  RETURN_IF_ERROR(CheckSlicePlane(plane));
  if (pixel_mm == 0.0) {
    const glm::dvec3& s = geometry.spacing_mm;
    pixel_mm = std::min({s.x, s.y, s.z});
  }
  if (!std::isfinite(pixel_mm) || pixel_mm <= 0.0) {
    return absl::InvalidArgumentError(StrCat("slice pixel size ", pixel_mm, " mm: must be > 0"));
  }
  const bool oblique = plane.orientation == SliceOrientation::kOblique;
  const Axes axes = oblique ? ObliqueAxes(plane.normal) : NamedAxes(plane.orientation);
  const glm::dvec3 on_plane = oblique ? plane.point_mm : plane.at_mm * axes.normal;
  const double offset = glm::dot(axes.normal, on_plane);
  const BoxProjection box = ProjectBox(axes, geometry);
  const glm::dvec2 lo = box.lo, hi = box.hi;
  const double tolerance = 1e-6 * (1.0 + std::abs(box.lo_n) + std::abs(box.hi_n));
  if (offset < box.lo_n - tolerance || offset > box.hi_n + tolerance) {
    return absl::InvalidArgumentError(StrCat(SliceOrientationName(plane.orientation), " slice at ",
                                             offset, " mm misses the volume, which spans ",
                                             box.lo_n, " to ", box.hi_n,
                                             " mm along the plane's normal"));
  }
  const glm::dvec2 size = (hi - lo) / pixel_mm;
  if (size.x + 1.0 > kMaxSliceSide || size.y + 1.0 > kMaxSliceSide) {
    return absl::InvalidArgumentError(StrCat("slice of ", hi.x - lo.x, " x ", hi.y - lo.y,
                                             " mm at ", pixel_mm, " mm per pixel exceeds ",
                                             kMaxSliceSide, " pixels a side"));
  }
  SliceGrid grid;
  grid.width = std::max(1, int(std::ceil(size.x)));
  grid.height = std::max(1, int(std::ceil(size.y)));
  grid.pixel_mm = pixel_mm;
  grid.world_u = axes.u;
  grid.world_v = axes.v;
  grid.world_normal = axes.normal;
  // Centre the pixel grid on the box's projection.
  const glm::dvec2 centre = 0.5 * (lo + hi);
  const glm::dvec2 half = 0.5 * pixel_mm * glm::dvec2(grid.width, grid.height);
  grid.world_origin_mm = offset * axes.normal + (centre.x - half.x) * axes.u +
                         (centre.y - half.y) * axes.v;
  const glm::dmat3 to_physical = glm::transpose(geometry.direction);
  grid.origin_mm = geometry.WorldToPhysical(grid.world_origin_mm);
  grid.step_u_mm = pixel_mm * (to_physical * axes.u);
  grid.step_v_mm = pixel_mm * (to_physical * axes.v);
  return grid;
}

}  // namespace vpm
