#include "server/service/slice_request.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "proto/vec3_convert.h"
#include "server/common/finite_vec3.h"
#include "server/raycast/frame_encoder.h"

namespace vpm::service {
namespace {

Result<SliceOrientation> OrientationFromProto(v3::SliceOrientation o, std::string_view path) {
  switch (o) {
    case v3::SLICE_ORIENTATION_AXIAL:
      return SliceOrientation::kAxial;
    case v3::SLICE_ORIENTATION_CORONAL:
      return SliceOrientation::kCoronal;
    case v3::SLICE_ORIENTATION_SAGITTAL:
      return SliceOrientation::kSagittal;
    case v3::SLICE_ORIENTATION_OBLIQUE:
      return SliceOrientation::kOblique;
    default:
      return absl::InvalidArgumentError(
          StrCat(path, ".orientation: ", static_cast<int>(o),
                 " is not a plane; use SLICE_ORIENTATION_AXIAL, _CORONAL, _SAGITTAL or _OBLIQUE"));
  }
}

v3::SliceOrientation OrientationToProto(SliceOrientation o) {
  switch (o) {
    case SliceOrientation::kAxial:
      return v3::SLICE_ORIENTATION_AXIAL;
    case SliceOrientation::kCoronal:
      return v3::SLICE_ORIENTATION_CORONAL;
    case SliceOrientation::kSagittal:
      return v3::SLICE_ORIENTATION_SAGITTAL;
    case SliceOrientation::kOblique:
      return v3::SLICE_ORIENTATION_OBLIQUE;
  }
  return v3::SLICE_ORIENTATION_UNSPECIFIED;
}

// Where the spec places the plane, world LPS mm: a landmark or a point.
Status PlacePoint(const v3::SliceSpec& spec, const Volume& volume, std::string_view path,
                  SliceRequest* out) {
  const int placed =
      int(spec.has_at_mm()) + int(!spec.at_landmark().empty()) + int(spec.has_point_lps_mm());
  if (placed > 1) {
    return absl::InvalidArgumentError(
        StrCat(path, ": give at most one of at_mm, at_landmark and point_lps_mm"));
  }
  if (spec.has_at_mm()) {
    if (out->orientation == SliceOrientation::kOblique) {
      return absl::InvalidArgumentError(
          StrCat(path,
                 ".at_mm: places named planes; place an oblique one by point_lps_mm or "
                 "at_landmark"));
    }
    if (!std::isfinite(spec.at_mm())) {
      return absl::InvalidArgumentError(StrCat(path, ".at_mm: not a finite number (mm)"));
    }
    out->at_mm = spec.at_mm();
  }
  if (!spec.at_landmark().empty()) {
    const auto& landmarks = volume.landmarks();
    auto it = std::find_if(landmarks.begin(), landmarks.end(),
                           [&](const Landmark& l) { return l.name == spec.at_landmark(); });
    if (it == landmarks.end()) {
      return absl::InvalidArgumentError(StrCat(path, ".at_landmark: '",
                                               spec.at_landmark().substr(0, 64),
                                               "' is not a landmark of ", volume.source()));
    }
    out->point_world_mm = volume.geometry().PhysicalToWorld(it->position_mm);
  }
  if (spec.has_point_lps_mm()) {
    const glm::dvec3 p = FromProto(spec.point_lps_mm());
    if (!IsFinite(p)) {
      return absl::InvalidArgumentError(StrCat(path, ".point_lps_mm: not finite"));
    }
    out->point_world_mm = p;
  }
  return absl::OkStatus();
}

}  // namespace

Result<SliceRequest> ToSliceRequest(const v3::SliceSpec& spec, const Volume& volume, int max_side,
                                    std::string_view path) {
  SliceRequest out;
  ASSIGN_OR_RETURN(out.orientation, OrientationFromProto(spec.orientation(), path));
  if (spec.view().size() > kMaxSliceViewChars) {
    return absl::InvalidArgumentError(
        StrCat(path, ".view: longer than ", kMaxSliceViewChars, " characters"));
  }
  out.view = spec.view();
  RETURN_IF_ERROR(PlacePoint(spec, volume, path, &out));
  if (out.orientation == SliceOrientation::kOblique) {
    const glm::dvec3 n = FromProto(spec.normal());
    if (!IsFinite(n) || !(glm::length(n) > 1e-9)) {
      return absl::InvalidArgumentError(
          StrCat(path, ".normal: an oblique plane needs a finite, non-zero normal (world LPS)"));
    }
    out.normal = n;
  } else if (spec.has_normal()) {
    return absl::InvalidArgumentError(
        StrCat(path, ".normal: only for SLICE_ORIENTATION_OBLIQUE (named planes have theirs)"));
  }
  if (spec.has_window()) {
    const MipWindow w{spec.window().level(), spec.window().width()};
    if (!std::isfinite(w.level) || !std::isfinite(w.width) || !(w.width > 0.0)) {
      return absl::InvalidArgumentError(StrCat(path, ".window: width ", w.width, ", level ",
                                               w.level, ": needs a finite level and width > 0"));
    }
    out.window = w;
  }
  if (!std::isfinite(spec.pixel_mm()) || spec.pixel_mm() < 0.0) {
    return absl::InvalidArgumentError(
        StrCat(path, ".pixel_mm: ", spec.pixel_mm(), " (0: the smallest voxel spacing; > 0 mm)"));
  }
  out.pixel_mm = spec.pixel_mm();
  out.overlay = spec.overlay();
  // The plane as a frame without a grab would place it; one through the
  // grabbed tissue always meets the volume and has the same size.
  const SliceView view = PlaceSlice(out, volume.geometry(), std::nullopt);
  auto grid = MakeSliceGrid(view.plane, volume.geometry(), view.pixel_mm);
  if (!grid.ok()) return absl::InvalidArgumentError(StrCat(path, ": ", grid.status().message()));
  if (grid->width > max_side || grid->height > max_side) {
    return absl::InvalidArgumentError(StrCat(path, ".pixel_mm: the slice would be ", grid->width,
                                             " x ", grid->height, " pixels, over the server's ",
                                             max_side, " a side; use a larger pixel"));
  }
  return out;
}

SliceView PlaceSlice(const SliceRequest& request, const VolumeGeometry& geometry,
                     const std::optional<glm::dvec3>& grabbed_mm) {
  const glm::dvec3 point = request.point_world_mm ? *request.point_world_mm
                           : grabbed_mm           ? geometry.PhysicalToWorld(*grabbed_mm)
                                        : geometry.PhysicalToWorld(0.5 * geometry.extent_mm());
  SliceView view;
  view.plane.orientation = request.orientation;
  switch (request.orientation) {
    case SliceOrientation::kAxial:
      view.plane.at_mm = request.at_mm.value_or(point.z);
      break;
    case SliceOrientation::kCoronal:
      view.plane.at_mm = request.at_mm.value_or(point.y);
      break;
    case SliceOrientation::kSagittal:
      view.plane.at_mm = request.at_mm.value_or(point.x);
      break;
    case SliceOrientation::kOblique:
      view.plane.point_mm = point;
      view.plane.normal = request.normal;
      break;
  }
  view.pixel_mm = request.pixel_mm;
  view.window = request.window;
  view.overlay = request.overlay;
  return view;
}

v3::SliceGeometry ToProtoSliceGeometry(const SliceFrame& frame, SliceOrientation orientation,
                                       const VolumeGeometry& geometry) {
  const SliceGrid& g = frame.grid;
  v3::SliceGeometry out;
  out.set_orientation(OrientationToProto(orientation));
  *out.mutable_origin_mm() = ToProto(g.world_origin_mm);
  *out.mutable_step_u_mm() = ToProto(geometry.PhysicalVectorToWorld(g.step_u_mm));
  *out.mutable_step_v_mm() = ToProto(geometry.PhysicalVectorToWorld(g.step_v_mm));
  *out.mutable_world_u() = ToProto(g.world_u);
  *out.mutable_world_v() = ToProto(g.world_v);
  *out.mutable_world_normal() = ToProto(g.world_normal);
  out.set_pixel_mm(g.pixel_mm);
  out.set_offset_mm(glm::dot(g.world_normal, g.world_origin_mm));
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  const glm::dvec3 extent = geometry.extent_mm();
  for (int c = 0; c < 8; ++c) {
    const glm::dvec3 corner(c & 1 ? extent.x : 0.0, c & 2 ? extent.y : 0.0, c & 4 ? extent.z : 0.0);
    const double along = glm::dot(g.world_normal, geometry.PhysicalToWorld(corner));
    lo = std::min(lo, along);
    hi = std::max(hi, along);
  }
  out.set_min_offset_mm(lo);
  out.set_max_offset_mm(hi);
  out.mutable_window()->set_width(frame.window.width);
  out.mutable_window()->set_level(frame.window.level);
  out.set_cut_tets(frame.cut_tets);
  return out;
}

Result<v3::SliceImage> EncodeSliceImage(const SliceFrame& frame, const SliceRequest& request,
                                        const VolumeGeometry& geometry, bool png,
                                        int jpeg_quality) {
  const int w = frame.grid.width, h = frame.grid.height;
  ASSIGN_OR_RETURN(std::vector<uint8_t> bytes,
                   png ? EncodePng(frame.rgba, w, h) : EncodeJpeg(frame.rgba, w, h, jpeg_quality));
  v3::SliceImage out;
  out.set_view(request.view);
  out.set_image(bytes.data(), bytes.size());
  out.set_encoding(png ? v3::ENCODING_PNG : v3::ENCODING_JPEG);
  out.set_width(w);
  out.set_height(h);
  *out.mutable_geometry() = ToProtoSliceGeometry(frame, request.orientation, geometry);
  return out;
}

}  // namespace vpm::service
