#include "server/service/proto_convert.h"

#include <algorithm>
#include <cmath>
#include <tuple>

#include "proto/render_tf_convert.h"
#include "server/common/valid_utf8.h"
#include "server/raycast/render_preset_from_tf.h"

namespace vpm::service {

glm::dvec3 PointFromApi(const v3::Vec3& world_mm, const VolumeGeometry& geometry) {
  return geometry.WorldToPhysical(FromProto(world_mm));
}

glm::dvec3 VectorFromApi(const v3::Vec3& world, const VolumeGeometry& geometry) {
  return geometry.WorldVectorToPhysical(FromProto(world));
}

v3::Vec3 PointToApi(const glm::dvec3& physical_mm, const VolumeGeometry& geometry) {
  return ToProto(geometry.PhysicalToWorld(physical_mm));
}

void FillVolumeInfo(const VolumeEntry& entry, v3::VolumeInfo* info) {
  const Volume& volume = entry.volume;
  const VolumeGeometry& g = volume.geometry();
  info->set_volume_id(entry.id);
  info->set_source(volume.source());
  info->clear_dims();
  for (int64_t d : g.dims) info->add_dims(d);
  *info->mutable_spacing_mm() = ToProto(g.spacing_mm);
  *info->mutable_origin_lps_mm() = ToProto(g.origin_mm);
  info->clear_direction();
  for (int c = 0; c < 3; ++c) {
    for (int r = 0; r < 3; ++r) info->add_direction(g.direction[c][r]);
  }
  const std::array<glm::dvec3, 2> box = g.WorldBox();
  *info->mutable_box_lo_lps_mm() = ToProto(box[0]);
  *info->mutable_box_hi_lps_mm() = ToProto(box[1]);
  info->set_min_value(volume.min_value());
  info->set_max_value(volume.max_value());
  info->clear_landmarks();
  for (const Landmark& l : volume.landmarks()) {
    v3::Landmark* out = info->add_landmarks();
    // Names, descriptions and notes come from files (a file name in a note,
    // a landmark named in Latin-1): valid UTF-8, as a proto string must be.
    out->set_name(ValidUtf8(l.name));
    *out->mutable_position_mm() = PointToApi(l.position_mm, g);
    out->set_description(ValidUtf8(l.description));
  }
  info->set_bytes(entry.bytes);
  info->set_voxel_encoding(VoxelEncodingName(volume.encoding()));
  for (const std::string& note : volume.notes()) info->add_notes(ValidUtf8(note));
  info->clear_stacks();
  for (const std::string& label : volume.stacks()) info->add_stacks(ValidUtf8(label));
  info->set_stack(volume.stack());
  info->set_sessions(entry.sessions.load());
  info->set_owner(entry.owner);
}

void FillMeshInfo(const MeshEntry& entry, v3::MeshInfo* info) {
  info->set_mesh_id(entry.id);
  info->set_volume_id(entry.volume->id);
  const ProxyMesh& mesh = entry.mesh;
  v3::MeshStats* s = info->mutable_stats();
  s->set_vertices(static_cast<int64_t>(mesh.vertices.size()));
  s->set_tets(static_cast<int64_t>(mesh.tets.size()));
  s->set_hard(mesh.stats.hard);
  s->set_refined(mesh.stats.refined);
  s->set_boundary(mesh.stats.boundary);
  s->set_boundary_ms(mesh.stats.boundary_ms);
  s->set_steiner(mesh.stats.steiner);
  s->set_steiner_ms(mesh.stats.steiner_ms);
  s->set_h_mm(mesh.stats.h_mm);
  s->set_r_mm(mesh.stats.R_mm);
  s->set_min_dihedral_deg(mesh.quality.min_dihedral_deg);
  s->set_min_radius_ratio(mesh.quality.min_radius_ratio);
  s->set_evaluate_ms(mesh.stats.evaluate_ms);
  s->set_decimate_ms(mesh.stats.decimate_ms);
  s->set_classify_ms(mesh.stats.classify_ms);
  s->set_refine_ms(mesh.stats.refine_ms);
  s->set_tetrahedralize_ms(mesh.stats.tetrahedralize_ms);
  for (int32_t g : mesh.stats.grid) s->add_grid(g);
  s->set_lattice_vertices(mesh.stats.lattice_vertices);
  s->set_kept_lattice(mesh.stats.kept_lattice);
  s->set_anchors(mesh.stats.anchors);
  s->set_mean_min_dihedral_deg(mesh.quality.mean_min_dihedral_deg);
  s->set_mean_radius_ratio(mesh.quality.mean_radius_ratio);
  s->set_removed_zero_volume(mesh.quality.removed_zero_volume);
  s->set_total_ms(mesh.stats.total_ms);
  s->set_evaluated_on(mesh.stats.evaluated_on);
}

namespace {

v3::VertexKind KindToProto(VertexKind kind) {
  switch (kind) {
    case VertexKind::kLattice: return v3::VERTEX_KIND_LATTICE;
    case VertexKind::kAnchor: return v3::VERTEX_KIND_ANCHOR;
    case VertexKind::kRefined: return v3::VERTEX_KIND_REFINED;
    case VertexKind::kBoundary: return v3::VERTEX_KIND_BOUNDARY;
    case VertexKind::kSteiner: return v3::VERTEX_KIND_STEINER;
  }
  return v3::VERTEX_KIND_UNSPECIFIED;
}

}  // namespace

Result<FrameEncoding> ToFrameEncoding(v3::Encoding encoding, int32_t jpeg_quality,
                                      std::string_view prefix) {
  FrameEncoding out;
  switch (encoding) {
    case v3::ENCODING_UNSPECIFIED:
    case v3::ENCODING_JPEG: out.png = false; break;
    case v3::ENCODING_PNG: out.png = true; break;
    default:
      return absl::InvalidArgumentError(
          StrCat(prefix, "encoding: ", encoding, " is not an Encoding"));
  }
  if (jpeg_quality < 0 || jpeg_quality > 100) {
    return absl::InvalidArgumentError(
        StrCat(prefix, "jpeg_quality: ", jpeg_quality, " is outside 1..100 (0: 85)"));
  }
  out.jpeg_quality = jpeg_quality == 0 ? 85 : jpeg_quality;
  return out;
}

Status ToSliceRequests(const v3::RenderSettings& in, const Volume& volume, int max_side,
                       std::vector<SliceRequest>* out) {
  if (in.slices_size() > kMaxSlicesPerFrame) {
    return absl::InvalidArgumentError(StrCat("settings.slices: ", in.slices_size(),
                                             " slices; at most ", kMaxSlicesPerFrame));
  }
  for (int i = 0; i < in.slices_size(); ++i) {
    ASSIGN_OR_RETURN(SliceRequest slice, ToSliceRequest(in.slices(i), volume, max_side,
                                                        StrCat("settings.slices[", i, "]")));
    for (const SliceRequest& earlier : *out) {
      if (earlier.view == slice.view) {
        return absl::InvalidArgumentError(
            StrCat("settings.slices[", i, "].view: '", slice.view, "' is used twice"));
      }
    }
    out->push_back(std::move(slice));
  }
  return absl::OkStatus();
}

void FillMeshGeometry(const ProxyMesh& mesh, const VolumeGeometry& geometry,
                      v3::GetMeshResponse* response) {
  for (const MeshVertex& v : mesh.vertices) {
    v3::MeshVertex* out = response->add_vertices();
    *out->mutable_position_mm() = PointToApi(v.position_mm, geometry);
    out->set_lattice_id(v.lattice_id);
    out->set_kind(KindToProto(v.kind));
    out->set_hard(v.hard);
    out->set_skeleton(v.skeleton);
    out->set_cost(v.cost);
  }
  for (const auto& t : mesh.tets) {
    v3::Tet* out = response->add_tets();
    out->set_a(t[0]);
    out->set_b(t[1]);
    out->set_c(t[2]);
    out->set_d(t[3]);
  }
}

v3::MeshParams MeshParamsToApi(const MeshParams& p, const VolumeGeometry& geometry) {
  v3::MeshParams out;
  for (int a = 0; a < 3; ++a) out.add_grid(p.grid[a]);
  out.set_target(p.target);
  out.set_footprint(p.footprint == Footprint::kCell ? v3::FOOTPRINT_CELL : v3::FOOTPRINT_POINT);
  out.set_density_mode(p.density_mode == DensityMode::kPaper ? v3::DENSITY_MODE_PAPER
                                                             : v3::DENSITY_MODE_SPREAD);
  out.set_wg(p.wg);
  out.set_wd(p.wd);
  out.set_radius_factor(p.radius_factor);
  out.set_tf(p.tf);
  out.set_bone_threshold(p.classify.bone_threshold);
  out.set_influence_threshold(p.classify.influence_threshold);
  out.set_influence_factor(p.classify.influence_factor);
  if (p.refine_at_mm) *out.mutable_refine_at_mm() = PointToApi(*p.refine_at_mm, geometry);
  out.set_roi_factor(p.roi_radius_factor);
  out.set_refine_count(p.refine_count);
  return out;
}

Result<MeshParams> ToMeshParams(const v3::MeshParams& in, const VolumeGeometry& geometry) {
  MeshParams p;
  if (in.grid_size() != 0) {
    if (in.grid_size() != 3) {
      return absl::InvalidArgumentError(
          StrCat("params.grid: takes 3 values (GX GY GZ), got ", in.grid_size()));
    }
    for (int a = 0; a < 3; ++a) {
      if (in.grid(a) < 2 || in.grid(a) > 256) {
        return absl::InvalidArgumentError(
            StrCat("params.grid: ", in.grid(a), " is outside 2..256"));
      }
      p.grid[a] = in.grid(a);
    }
  }
  if (in.target() < 0) return absl::InvalidArgumentError("params.target: negative");
  if (in.target() > 0) p.target = in.target();
  switch (in.footprint()) {
    case v3::FOOTPRINT_UNSPECIFIED: break;
    case v3::FOOTPRINT_POINT: p.footprint = Footprint::kPoint; break;
    case v3::FOOTPRINT_CELL: p.footprint = Footprint::kCell; break;
    default:
      return absl::InvalidArgumentError(
          StrCat("params.footprint: ", in.footprint(), " is not a Footprint"));
  }
  switch (in.density_mode()) {
    case v3::DENSITY_MODE_UNSPECIFIED: break;
    case v3::DENSITY_MODE_SPREAD: p.density_mode = DensityMode::kSpread; break;
    case v3::DENSITY_MODE_PAPER: p.density_mode = DensityMode::kPaper; break;
    default:
      return absl::InvalidArgumentError(
          StrCat("params.density_mode: ", in.density_mode(), " is not a DensityMode"));
  }
  if (in.has_wg()) p.wg = in.wg();
  if (in.has_wd()) p.wd = in.wd();
  if (in.has_radius_factor()) {
    if (!(in.radius_factor() > 0)) {
      return absl::InvalidArgumentError("params.radius_factor: must be > 0");
    }
    p.radius_factor = in.radius_factor();
  }
  if (!in.tf().empty()) p.tf = in.tf();
  if (in.has_bone_threshold()) p.classify.bone_threshold = in.bone_threshold();
  if (in.has_influence_threshold()) p.classify.influence_threshold = in.influence_threshold();
  if (in.has_influence_factor()) p.classify.influence_factor = in.influence_factor();
  if (in.has_refine_at_mm()) p.refine_at_mm = PointFromApi(in.refine_at_mm(), geometry);
  if (in.has_roi_factor()) p.roi_radius_factor = in.roi_factor();
  if (in.has_refine_count()) {
    if (in.refine_count() < 0) return absl::InvalidArgumentError("params.refine_count: negative");
    p.refine_count = in.refine_count();
  }
  return p;
}

namespace {

// settings.mode, the preset or render_tf, and the MIP window, into `view`.
Status ToLook(const v3::RenderSettings& in, const Volume& volume, SceneView& view) {
  switch (in.mode()) {
    case v3::RENDER_MODE_UNSPECIFIED:
    case v3::RENDER_MODE_DVR:
      view.mode = RenderMode::kDvr;
      break;
    case v3::RENDER_MODE_MIP:
      view.mode = RenderMode::kMip;
      break;
    default:
      return absl::InvalidArgumentError(StrCat("settings.mode: ", in.mode(), " is not a RenderMode"));
  }
  if (in.has_render_tf() && !in.preset().empty()) {
    return absl::InvalidArgumentError("settings: give preset or render_tf, not both");
  }
  auto preset = in.has_render_tf() ? RenderPresetFromTf(FromProto(in.render_tf()), volume)
                                   : MakeRenderPreset(in.preset(), volume);
  if (!preset.ok()) {
    return absl::InvalidArgumentError(StrCat(in.has_render_tf() ? "settings.render_tf: "
                                                                : "settings.preset: ",
                                             preset.status().message()));
  }
  view.preset = *std::move(preset);
  if (in.has_mip_window()) {
    const v3::WindowLevel& w = in.mip_window();
    if (!std::isfinite(w.level()) || !std::isfinite(w.width()) || !(w.width() > 0.0)) {
      return absl::InvalidArgumentError(StrCat("settings.mip_window: width ", w.width(),
                                               ", level ", w.level(),
                                               ": needs a finite level and width > 0"));
    }
    view.preset.mip_window = {w.level(), w.width()};
  }
  return absl::OkStatus();
}

// settings.interactive_quality (unset: kDefaultInteractiveQuality).
Result<InteractiveQuality> ToInteractiveQuality(v3::InteractiveQuality in) {
  switch (in) {
    case v3::INTERACTIVE_QUALITY_UNSPECIFIED:
      return kDefaultInteractiveQuality;
    case v3::INTERACTIVE_QUALITY_FAST:
      return InteractiveQuality::kFast;
    case v3::INTERACTIVE_QUALITY_BALANCED:
      return InteractiveQuality::kBalanced;
    case v3::INTERACTIVE_QUALITY_SHARP:
      return InteractiveQuality::kSharp;
    default:
      return absl::InvalidArgumentError(
          StrCat("settings.interactive_quality: ", in, " is not an InteractiveQuality"));
  }
}

}  // namespace

Result<StreamSettings> ToStreamSettings(const v3::RenderSettings& in, const Volume& volume,
                                        int max_side) {
  StreamSettings out;
  RETURN_IF_ERROR(ToLook(in, volume, out.view));
  for (auto [name, value, target] :
       {std::tuple{"settings.width", in.width(), &out.view.width},
        std::tuple{"settings.height", in.height(), &out.view.height}}) {
    if (value < 0 || value > max_side) {
      return absl::InvalidArgumentError(
          StrCat(name, ": ", value, " is outside 1..", max_side, " pixels (0: 512)"));
    }
    *target = value == 0 ? std::min(512, max_side) : value;
  }
  out.view.overlay = in.overlay();
  ASSIGN_OR_RETURN(out.view.interactive_quality, ToInteractiveQuality(in.interactive_quality()));
  if (in.has_crop()) {
    out.view.clip.crop = CropBox{FromProto(in.crop().lo_mm()), FromProto(in.crop().hi_mm())};
  }
  for (const v3::ClipPlane& plane : in.clip()) {
    out.view.clip.planes.push_back(ClipPlane{FromProto(plane.normal()), plane.offset_mm()});
  }
  if (Status clip = ValidateClipRegion(out.view.clip); !clip.ok()) {
    return absl::InvalidArgumentError(StrCat("settings.crop/clip: ", clip.message()));
  }
  out.view.view_cut = in.view_cut();
  ASSIGN_OR_RETURN(const FrameEncoding encoding,
                   ToFrameEncoding(in.encoding(), in.jpeg_quality(), "settings."));
  out.png = encoding.png;
  out.jpeg_quality = encoding.jpeg_quality;
  RETURN_IF_ERROR(ToSliceRequests(in, volume, max_side, &out.slices));
  return out;
}

Result<Camera> ToCamera(const v3::Camera& in, const VolumeGeometry& geometry) {
  Camera camera = Camera::ForVolume(geometry);
  Camera::Pose pose = camera.pose();
  pose.azimuth_deg = in.azimuth_deg();
  pose.elevation_deg = in.elevation_deg();
  if (in.distance_mm() < 0) {
    return absl::InvalidArgumentError("camera.distance_mm: negative (0 fits the volume)");
  }
  if (in.distance_mm() > 0) pose.distance_mm = in.distance_mm();
  pose.pan_mm = {in.pan_mm().x(), in.pan_mm().y()};
  camera.set_pose(pose);
  Status valid = camera.Validate();
  if (!valid.ok()) return absl::InvalidArgumentError(StrCat("camera: ", valid.message()));
  return camera;
}

v3::Camera FromCamera(const Camera& camera) {
  v3::Camera out;
  out.set_azimuth_deg(camera.pose().azimuth_deg);
  out.set_elevation_deg(camera.pose().elevation_deg);
  out.set_distance_mm(camera.pose().distance_mm);
  out.mutable_pan_mm()->set_x(camera.pose().pan_mm.x);
  out.mutable_pan_mm()->set_y(camera.pose().pan_mm.y);
  return out;
}

}  // namespace vpm::service
