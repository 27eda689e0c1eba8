// Where a slice of the deformed volume lies and how its pixels map to space.
//
// Planes are named in the patient's (world, LPS) frame and shown as a
// radiologist reads them:
//  - axial (normal S, `at` = world z): image right = patient left (+x),
//    image down = posterior (+y), seen from the feet;
//  - coronal (normal P, `at` = world y): right = patient left (+x), down =
//    inferior (-z), seen from the front;
//  - sagittal (normal L, `at` = world x): right = posterior (+y), down =
//    inferior (-z), seen from the patient's left;
//  - oblique: any unit normal through a world point; right = the normal
//    crossed with the superior axis (or, for a plane facing S, +x), down =
//    right crossed with the normal... chosen so that an oblique plane close
//    to a named one is shown like it.
// The image covers the projection of the volume's whole box (its 8 world
// corners) onto the plane, one pixel per `pixel_mm`.
#pragma once

#include <string_view>

#include <glm/glm.hpp>

#include "server/common/status.h"
#include "server/volume/volume.h"

namespace vpm {

enum class SliceOrientation { kAxial, kCoronal, kSagittal, kOblique };

// "axial", "coronal", "sagittal", "oblique"; nullopt-like InvalidArgument otherwise.
Result<SliceOrientation> SliceOrientationFromName(std::string_view name);
std::string_view SliceOrientationName(SliceOrientation orientation);

struct SlicePlane {
  SliceOrientation orientation = SliceOrientation::kAxial;
  // Named planes: the world coordinate along their normal axis (mm).
  double at_mm = 0.0;
  // Oblique planes: a world point on the plane and its normal (any length > 0).
  glm::dvec3 point_mm{0.0};
  glm::dvec3 normal{0.0, 0.0, 1.0};
};

// Pixel (i, j), row 0 at the top, samples physical point
// origin_mm + (i + 0.5) * step_u_mm + (j + 0.5) * step_v_mm (physical voxel
// space, mm: where the volume and its backward map live).
struct SliceGrid {
  glm::dvec3 origin_mm{0.0};
  glm::dvec3 step_u_mm{1.0, 0.0, 0.0};  // one pixel to the right
  glm::dvec3 step_v_mm{0.0, 1.0, 0.0};  // one pixel down
  int width = 0;
  int height = 0;
  // The same in world (LPS) terms, for overlays and clients.
  glm::dvec3 world_origin_mm{0.0};
  glm::dvec3 world_u{1.0, 0.0, 0.0};  // unit
  glm::dvec3 world_v{0.0, 1.0, 0.0};  // unit
  glm::dvec3 world_normal{0.0, 0.0, 1.0};
  double pixel_mm = 1.0;

  glm::dvec3 PixelCentreMm(double i, double j) const {
    return origin_mm + (i + 0.5) * step_u_mm + (j + 0.5) * step_v_mm;
  }
};

inline constexpr int kMaxSliceSide = 4096;

// pixel_mm 0: the smallest voxel spacing. InvalidArgument for a non-finite
// or zero normal, a plane that misses the volume's box, or an image over
// kMaxSliceSide pixels on a side (pixel_mm too small for the box).
Result<SliceGrid> MakeSliceGrid(const SlicePlane& plane, const VolumeGeometry& geometry,
                                double pixel_mm = 0.0);

}  // namespace vpm
