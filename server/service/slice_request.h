// Slices over the API (RenderSlice, RenderSettings.slices): a SliceSpec
// checked once into a SliceRequest, placed on the scene at each frame (the
// grabbed tissue moves), and the rendered SliceFrame as the wire's
// SliceImage / SliceGeometry.
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include <glm/glm.hpp>

#include "server/common/status.h"
#include "server/scene/slice_view.h"
#include "server/volume/volume.h"
#include "vpm/v3/vpm.pb.h"

namespace vpm::service {

inline constexpr int kMaxSlicesPerFrame = 3;
inline constexpr size_t kMaxSliceViewChars = 32;

struct SliceRequest {
  std::string view;  // the client's tag, echoed
  SliceOrientation orientation = SliceOrientation::kAxial;
  std::optional<double> at_mm;               // named planes: world coordinate along the normal
  std::optional<glm::dvec3> point_world_mm;  // a landmark's or point_lps_mm, world LPS mm
  glm::dvec3 normal{0.0, 0.0, 1.0};          // oblique, world
  std::optional<MipWindow> window;
  double pixel_mm = 0.0;  // 0: the smallest spacing
  bool overlay = false;
};

// Checks `spec` against `volume`: InvalidArgument naming the field under
// `path` (e.g. "settings.slices[1].normal: ...") for an unset orientation,
// non-finite numbers, a zero normal, an unknown landmark, a bad window, a
// plane that misses the volume or an image over `max_side` pixels a side
// (as placed without a grab; a grab point is always inside the volume).
Result<SliceRequest> ToSliceRequest(const v3::SliceSpec& spec, const Volume& volume, int max_side,
                                    std::string_view path);

// The view of `request` at this moment: `grabbed_mm` (physical mm, the
// grabbed tissue where the drag moved it) places a plane that nothing else
// places; without it the volume's centre does.
SliceView PlaceSlice(const SliceRequest& request, const VolumeGeometry& geometry,
                     const std::optional<glm::dvec3>& grabbed_mm);

v3::SliceGeometry ToProtoSliceGeometry(const SliceFrame& frame, SliceOrientation orientation,
                                       const VolumeGeometry& geometry);

// The frame's pixels encoded (PNG, or JPEG at `jpeg_quality`) with its geometry.
Result<v3::SliceImage> EncodeSliceImage(const SliceFrame& frame, const SliceRequest& request,
                                        const VolumeGeometry& geometry, bool png, int jpeg_quality);

}  // namespace vpm::service
