#include "client/cli/remote_pipeline.h"

#include <chrono>
#include <fstream>
#include <future>

#include "proto/enum_names.h"
#include "proto/vec3_convert.h"

namespace vpm::cli {
namespace {

Result<VertexKind> KindOf(v3::VertexKind kind) {
  switch (kind) {
    case v3::VERTEX_KIND_LATTICE: return VertexKind::kLattice;
    case v3::VERTEX_KIND_ANCHOR: return VertexKind::kAnchor;
    case v3::VERTEX_KIND_REFINED: return VertexKind::kRefined;
    case v3::VERTEX_KIND_BOUNDARY: return VertexKind::kBoundary;
    case v3::VERTEX_KIND_STEINER: return VertexKind::kSteiner;
    default: return absl::DataLossError(StrCat("server sent a vertex of unknown kind ", kind));
  }
}

MeshStats StatsOf(const v3::MeshStats& s) {
  MeshStats out;
  for (int i = 0; i < 3 && i < s.grid_size(); ++i) out.grid[i] = s.grid(i);
  out.lattice_vertices = s.lattice_vertices();
  out.kept_lattice = s.kept_lattice();
  out.anchors = s.anchors();
  out.refined = s.refined();
  out.boundary = s.boundary();
  out.boundary_ms = s.boundary_ms();
  out.steiner = s.steiner();
  out.steiner_ms = s.steiner_ms();
  out.hard = s.hard();
  out.tets = s.tets();
  out.h_mm = s.h_mm();
  out.R_mm = s.r_mm();
  out.evaluate_ms = s.evaluate_ms();
  out.decimate_ms = s.decimate_ms();
  out.classify_ms = s.classify_ms();
  out.refine_ms = s.refine_ms();
  out.tetrahedralize_ms = s.tetrahedralize_ms();
  out.total_ms = s.total_ms();
  out.evaluated_on = s.evaluated_on();
  return out;
}

}  // namespace

// 32 hex digits from /dev/urandom: a progress_id no other client picks.
std::string RandomProgressId() {
  std::ifstream in("/dev/urandom", std::ios::binary);
  unsigned char bytes[16] = {};
  in.read(reinterpret_cast<char*>(bytes), sizeof(bytes));
  static constexpr char kHex[] = "0123456789abcdef";
  std::string id;
  for (unsigned char b : bytes) id += {kHex[b >> 4], kHex[b & 15]};
  return id;
}

Result<v3::VolumeInfo> LoadVolumeOnServer(const ServerConnection& server,
                                          const std::string& source, const ProgressFn& progress) {
  v3::LoadVolumeRequest request;
  request.set_source(source);
  if (progress) request.set_progress_id(RandomProgressId());
  auto load = std::async(std::launch::async, [&server, request] {
    v3::VolumeInfo info;
    const grpc::Status status = server.stub().LoadVolume(server.Context().get(), request, &info);
    return std::make_pair(status, info);
  });
  while (progress &&
         load.wait_for(std::chrono::milliseconds(100)) != std::future_status::ready) {
    v3::GetLoadProgressRequest poll;
    poll.set_progress_id(request.progress_id());
    v3::LoadProgress state;
    // NotFound until the server starts the load: keep polling.
    if (server.stub().GetLoadProgress(server.Context().get(), poll, &state).ok()) {
      progress(state.fraction(), state.stage());
    }
  }
  auto [status, info] = load.get();
  RETURN_IF_ERROR(FromGrpc(status));
  if (progress) progress(1.0, "done");
  return info;
}

Result<glm::dvec3> FindLandmark(const v3::VolumeInfo& volume, const std::string& name) {
  std::string names;
  for (const v3::Landmark& l : volume.landmarks()) {
    if (l.name() == name) return FromProto(l.position_mm());
    names += (names.empty() ? "" : ", ") + l.name();
  }
  return absl::NotFoundError(StrCat("landmark '", name, "' is not in ", volume.source(),
                                    names.empty() ? " (it has none)" : " (it has: " + names + ")"));
}

Result<v3::MeshParams> ToProtoMeshParams(const MeshFlags& f, const v3::VolumeInfo& volume) {
  v3::MeshParams p;
  for (int64_t g : f.grid) p.add_grid(g);
  p.set_target(f.target);
  const auto footprint = FootprintFromName(f.footprint);
  if (!footprint) {
    return absl::InvalidArgumentError(StrCat("--footprint: '", f.footprint, "' is not point or cell"));
  }
  p.set_footprint(*footprint);
  const auto density_mode = DensityModeFromName(f.density_mode);
  if (!density_mode) {
    return absl::InvalidArgumentError(
        StrCat("--density-mode: '", f.density_mode, "' is not spread or paper"));
  }
  p.set_density_mode(*density_mode);
  p.set_wg(f.wg);
  p.set_wd(f.wd);
  p.set_radius_factor(f.radius_factor);
  p.set_tf(f.tf);
  p.set_bone_threshold(f.bone);
  p.set_influence_threshold(f.influence_threshold);
  p.set_influence_factor(f.influence_factor);
  p.set_roi_factor(f.roi_factor);
  p.set_refine_count(f.refine_count);
  if (!f.refine_at.empty() && !f.refine_at_landmark.empty()) {
    return absl::InvalidArgumentError("give --refine-at or --refine-at-landmark, not both");
  }
  if (!f.refine_at.empty()) {
    if (f.refine_at.size() != 3) return absl::InvalidArgumentError("--refine-at takes X Y Z");
    *p.mutable_refine_at_mm() = ToProto({f.refine_at[0], f.refine_at[1], f.refine_at[2]});
  }
  if (!f.refine_at_landmark.empty()) {
    ASSIGN_OR_RETURN(glm::dvec3 at, FindLandmark(volume, f.refine_at_landmark));
    *p.mutable_refine_at_mm() = ToProto(at);
  }
  return p;
}

Result<ProxyMesh> FetchMesh(const ServerConnection& server, const std::string& mesh_id) {
  v3::GetMeshRequest request;
  request.set_mesh_id(mesh_id);
  request.set_include_geometry(true);
  v3::GetMeshResponse response;
  RETURN_IF_ERROR(FromGrpc(server.stub().GetMesh(server.Context().get(), request, &response)));
  ProxyMesh mesh;
  mesh.vertices.reserve(response.vertices_size());
  for (const v3::MeshVertex& v : response.vertices()) {
    MeshVertex out;
    out.position_mm = FromProto(v.position_mm());  // world LPS, as the API gives it
    out.lattice_id = v.lattice_id();
    ASSIGN_OR_RETURN(out.kind, KindOf(v.kind()));
    out.hard = v.hard();
    out.skeleton = v.hard() && v.skeleton();
    out.cost = v.cost();
    mesh.vertices.push_back(out);
  }
  const int32_t n = static_cast<int32_t>(mesh.vertices.size());
  for (const v3::Tet& t : response.tets()) {
    const std::array<int32_t, 4> tet{t.a(), t.b(), t.c(), t.d()};
    for (int32_t i : tet) {
      if (i < 0 || i >= n) return absl::DataLossError(StrCat("server sent a tet with vertex ", i));
    }
    mesh.tets.push_back(tet);
  }
  const v3::MeshStats& s = response.info().stats();
  mesh.stats = StatsOf(s);
  mesh.quality.min_dihedral_deg = s.min_dihedral_deg();
  mesh.quality.mean_min_dihedral_deg = s.mean_min_dihedral_deg();
  mesh.quality.min_radius_ratio = s.min_radius_ratio();
  mesh.quality.mean_radius_ratio = s.mean_radius_ratio();
  mesh.quality.removed_zero_volume = s.removed_zero_volume();
  return mesh;
}

Result<RemoteMesh> BuildMeshOnServer(const ServerConnection& server, const std::string& source,
                                     const MeshFlags& flags) {
  RemoteMesh out;
  ASSIGN_OR_RETURN(out.volume, LoadVolumeOnServer(server, source));
  v3::BuildMeshRequest request;
  request.set_volume_id(out.volume.volume_id());
  ASSIGN_OR_RETURN(*request.mutable_params(), ToProtoMeshParams(flags, out.volume));
  RETURN_IF_ERROR(FromGrpc(server.stub().BuildMesh(server.Context().get(), request, &out.info)));
  ASSIGN_OR_RETURN(out.mesh, FetchMesh(server, out.info.mesh_id()));
  return out;
}

}  // namespace vpm::cli
