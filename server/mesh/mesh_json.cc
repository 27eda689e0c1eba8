#include "server/mesh/mesh_json.h"

#include <cmath>
#include <fstream>
#include <sstream>

#include "server/common/write_file.h"
#include "server/mesh/tet_quality.h"

namespace vpm {
namespace {

using nlohmann::json;

// Checked access to the fields of one JSON object; `where` names it.
class FieldReader {
 public:
  FieldReader(const json& object, std::string where) : object_(object), where_(std::move(where)) {}

  Status Object() const {
    return object_.is_object() ? absl::OkStatus() : Error("", "must be an object");
  }
  Result<const json*> Field(const char* name) const {
    if (!object_.is_object()) return Error("", "must be an object");
    auto it = object_.find(name);
    if (it == object_.end()) return Error(name, "is missing");
    return &*it;
  }
  Result<double> Double(const char* name) const {
    ASSIGN_OR_RETURN(const json* f, Field(name));
    if (!f->is_number() || !std::isfinite(f->get<double>())) {
      return Error(name, "must be a finite number");
    }
    return f->get<double>();
  }
  Result<int64_t> Int(const char* name, int64_t min_value) const {
    ASSIGN_OR_RETURN(const json* f, Field(name));
    if (!f->is_number_integer() || (f->is_number_unsigned() && f->get<uint64_t>() > INT64_MAX) ||
        f->get<int64_t>() < min_value) {
      return Error(name, StrCat("must be an integer >= ", min_value));
    }
    return f->get<int64_t>();
  }
  Result<bool> Bool(const char* name) const {
    ASSIGN_OR_RETURN(const json* f, Field(name));
    if (!f->is_boolean()) return Error(name, "must be true or false");
    return f->get<bool>();
  }
  Result<glm::dvec3> Vec3(const char* name) const {
    ASSIGN_OR_RETURN(const json* f, Field(name));
    if (!f->is_array() || f->size() != 3) return Error(name, "must be an array of 3 numbers");
    glm::dvec3 v;
    for (int a = 0; a < 3; ++a) {
      if (!(*f)[a].is_number() || !std::isfinite((*f)[a].get<double>())) {
        return Error(name, "must be an array of 3 finite numbers");
      }
      v[a] = (*f)[a].get<double>();
    }
    return v;
  }
  Status Error(std::string_view field, std::string_view problem) const {
    return absl::InvalidArgumentError(
        StrCat(where_, field.empty() ? "" : ".", field, " ", problem));
  }

 private:
  const json& object_;
  std::string where_;
};

json QualityToJson(const TetQuality& q) {
  return {{"min_dihedral_deg", q.min_dihedral_deg},
          {"mean_min_dihedral_deg", q.mean_min_dihedral_deg},
          {"min_radius_ratio", q.min_radius_ratio},
          {"mean_radius_ratio", q.mean_radius_ratio},
          {"removed_zero_volume", q.removed_zero_volume}};
}

json StatsToJson(const MeshStats& s, const TetQuality& q) {
  return {{"grid", {s.grid[0], s.grid[1], s.grid[2]}},
          {"lattice_vertices", s.lattice_vertices},
          {"kept_lattice", s.kept_lattice},
          {"anchors", s.anchors},
          {"refined", s.refined},
          {"boundary", s.boundary},
          {"steiner", s.steiner},
          {"hard", s.hard},
          {"tets", s.tets},
          {"h_mm", s.h_mm},
          {"R_mm", s.R_mm},
          {"evaluate_ms", s.evaluate_ms},
          {"decimate_ms", s.decimate_ms},
          {"classify_ms", s.classify_ms},
          {"refine_ms", s.refine_ms},
          {"tetrahedralize_ms", s.tetrahedralize_ms},
          {"total_ms", s.total_ms},
          {"quality", QualityToJson(q)}};
}

Result<VertexKind> KindFromName(const json& value, const FieldReader& where) {
  if (value.is_string()) {
    for (VertexKind kind : {VertexKind::kLattice, VertexKind::kAnchor, VertexKind::kRefined,
                            VertexKind::kBoundary, VertexKind::kSteiner}) {
      if (value.get<std::string>() == VertexKindName(kind)) return kind;
    }
  }
  return where.Error("kind", "must be \"lattice\", \"anchor\", \"refined\", \"boundary\" or \"steiner\"");
}

Status ReadVertices(const json& array, std::vector<MeshVertex>& vertices) {
  if (!array.is_array()) return absl::InvalidArgumentError("vertices must be an array");
  vertices.resize(array.size());
  for (size_t v = 0; v < array.size(); ++v) {
    const FieldReader r(array[v], StrCat("vertices[", v, "]"));
    RETURN_IF_ERROR(r.Object());
    MeshVertex& out = vertices[v];
    ASSIGN_OR_RETURN(out.lattice_id, r.Int("lattice_id", -1));
    ASSIGN_OR_RETURN(const json* kind, r.Field("kind"));
    ASSIGN_OR_RETURN(out.kind, KindFromName(*kind, r));
    if (out.kind == VertexKind::kLattice && out.lattice_id < 0) {
      return r.Error("lattice_id", "must be >= 0 for a lattice vertex");
    }
    ASSIGN_OR_RETURN(out.position_mm, r.Vec3("position_mm"));
    ASSIGN_OR_RETURN(out.hard, r.Bool("hard"));
    // Absent in meshes written before the skeleton rule: every hard vertex
    // was fixed then.
    out.skeleton = out.hard;
    if (array[v].contains("skeleton")) {
      ASSIGN_OR_RETURN(const bool skeleton, r.Bool("skeleton"));
      out.skeleton = out.hard && skeleton;
    }
    ASSIGN_OR_RETURN(out.cost, r.Double("cost"));
  }
  return absl::OkStatus();
}

Status ReadTets(const json& array, const std::vector<MeshVertex>& vertices,
                std::vector<std::array<int32_t, 4>>& tets) {
  if (!array.is_array()) return absl::InvalidArgumentError("tets must be an array");
  const int64_t count = static_cast<int64_t>(vertices.size());
  tets.resize(array.size());
  for (size_t t = 0; t < array.size(); ++t) {
    const json& item = array[t];
    if (!item.is_array() || item.size() != 4) {
      return absl::InvalidArgumentError(StrCat("tets[", t, "] must be an array of 4 indices"));
    }
    for (int c = 0; c < 4; ++c) {
      if (!item[c].is_number_integer() || item[c].get<int64_t>() < 0 ||
          item[c].get<int64_t>() >= count) {
        return absl::InvalidArgumentError(
            StrCat("tets[", t, "][", c, "] must be a vertex index in [0, ", count, ")"));
      }
      tets[t][c] = static_cast<int32_t>(item[c].get<int64_t>());
    }
    const auto& q = tets[t];
    if (q[0] == q[1] || q[0] == q[2] || q[0] == q[3] || q[1] == q[2] || q[1] == q[3] ||
        q[2] == q[3]) {
      return absl::InvalidArgumentError(StrCat("tets[", t, "] repeats a vertex"));
    }
    if (!(SignedVolume(vertices[q[0]].position_mm, vertices[q[1]].position_mm,
                       vertices[q[2]].position_mm, vertices[q[3]].position_mm) > 0.0)) {
      return absl::InvalidArgumentError(StrCat("tets[", t, "] has no positive signed volume"));
    }
  }
  return absl::OkStatus();
}

Status ReadQuality(const json& object, TetQuality& q) {
  const FieldReader r(object, "stats.quality");
  RETURN_IF_ERROR(r.Object());
  ASSIGN_OR_RETURN(q.min_dihedral_deg, r.Double("min_dihedral_deg"));
  ASSIGN_OR_RETURN(q.mean_min_dihedral_deg, r.Double("mean_min_dihedral_deg"));
  ASSIGN_OR_RETURN(q.min_radius_ratio, r.Double("min_radius_ratio"));
  ASSIGN_OR_RETURN(q.mean_radius_ratio, r.Double("mean_radius_ratio"));
  ASSIGN_OR_RETURN(q.removed_zero_volume, r.Int("removed_zero_volume", 0));
  return absl::OkStatus();
}

Status ReadStats(const json& object, MeshStats& s, TetQuality& q) {
  const FieldReader r(object, "stats");
  RETURN_IF_ERROR(r.Object());
  ASSIGN_OR_RETURN(const json* grid, r.Field("grid"));
  if (!grid->is_array() || grid->size() != 3) return r.Error("grid", "must be [gx, gy, gz]");
  for (int a = 0; a < 3; ++a) {
    const json& g = (*grid)[a];
    if (!g.is_number_integer() || g.get<int64_t>() < 0 || g.get<int64_t>() > INT32_MAX) {
      return r.Error("grid", "must hold 3 non-negative integers");
    }
    s.grid[a] = static_cast<int32_t>(g.get<int64_t>());
  }
  ASSIGN_OR_RETURN(s.lattice_vertices, r.Int("lattice_vertices", 0));
  ASSIGN_OR_RETURN(s.kept_lattice, r.Int("kept_lattice", 0));
  ASSIGN_OR_RETURN(s.anchors, r.Int("anchors", 0));
  ASSIGN_OR_RETURN(s.refined, r.Int("refined", 0));
  // Files from before boundary vertices (tests/data/meshes) have none.
  if (object.contains("boundary")) {
    ASSIGN_OR_RETURN(s.boundary, r.Int("boundary", 0));
  }
  // Files from before Steiner points have none.
  if (object.contains("steiner")) {
    ASSIGN_OR_RETURN(s.steiner, r.Int("steiner", 0));
  }
  ASSIGN_OR_RETURN(s.hard, r.Int("hard", 0));
  ASSIGN_OR_RETURN(s.tets, r.Int("tets", 0));
  ASSIGN_OR_RETURN(s.h_mm, r.Double("h_mm"));
  ASSIGN_OR_RETURN(s.R_mm, r.Double("R_mm"));
  ASSIGN_OR_RETURN(s.evaluate_ms, r.Double("evaluate_ms"));
  ASSIGN_OR_RETURN(s.decimate_ms, r.Double("decimate_ms"));
  ASSIGN_OR_RETURN(s.classify_ms, r.Double("classify_ms"));
  ASSIGN_OR_RETURN(s.refine_ms, r.Double("refine_ms"));
  ASSIGN_OR_RETURN(s.tetrahedralize_ms, r.Double("tetrahedralize_ms"));
  ASSIGN_OR_RETURN(s.total_ms, r.Double("total_ms"));
  ASSIGN_OR_RETURN(const json* quality, r.Field("quality"));
  return ReadQuality(*quality, q);
}

// JSON has no NaN or infinity: nlohmann would write null and the reader
// would reject the file.
Status CheckFinite(const ProxyMesh& mesh) {
  for (size_t v = 0; v < mesh.vertices.size(); ++v) {
    const MeshVertex& x = mesh.vertices[v];
    if (!std::isfinite(x.position_mm.x) || !std::isfinite(x.position_mm.y) ||
        !std::isfinite(x.position_mm.z) || !std::isfinite(x.cost)) {
      return absl::InvalidArgumentError(StrCat("vertex ", v, " has a non-finite position or cost"));
    }
  }
  const MeshStats& s = mesh.stats;
  const TetQuality& q = mesh.quality;
  for (double d : {s.h_mm, s.R_mm, s.evaluate_ms, s.decimate_ms, s.classify_ms, s.refine_ms,
                   s.tetrahedralize_ms, s.total_ms, q.min_dihedral_deg, q.mean_min_dihedral_deg,
                   q.min_radius_ratio, q.mean_radius_ratio}) {
    if (!std::isfinite(d)) return absl::InvalidArgumentError("a stats number is not finite");
  }
  return absl::OkStatus();
}

}  // namespace

json MeshToJson(const ProxyMesh& mesh) {
  json vertices = json::array();
  for (const MeshVertex& v : mesh.vertices) {
    vertices.push_back({{"lattice_id", v.lattice_id},
                        {"kind", VertexKindName(v.kind)},
                        {"position_mm", {v.position_mm.x, v.position_mm.y, v.position_mm.z}},
                        {"hard", v.hard},
                        {"skeleton", v.skeleton},
                        {"cost", v.cost}});
  }
  json tets = json::array();
  for (const auto& t : mesh.tets) tets.push_back({t[0], t[1], t[2], t[3]});
  return {{"vertices", std::move(vertices)},
          {"tets", std::move(tets)},
          {"stats", StatsToJson(mesh.stats, mesh.quality)}};
}

Result<ProxyMesh> MeshFromJson(const json& json_mesh) {
  const FieldReader r(json_mesh, "mesh");
  RETURN_IF_ERROR(r.Object());
  ProxyMesh mesh;
  ASSIGN_OR_RETURN(const json* vertices, r.Field("vertices"));
  RETURN_IF_ERROR(ReadVertices(*vertices, mesh.vertices));
  ASSIGN_OR_RETURN(const json* tets, r.Field("tets"));
  RETURN_IF_ERROR(ReadTets(*tets, mesh.vertices, mesh.tets));
  ASSIGN_OR_RETURN(const json* stats, r.Field("stats"));
  RETURN_IF_ERROR(ReadStats(*stats, mesh.stats, mesh.quality));
  return mesh;
}

Status WriteMeshJson(const ProxyMesh& mesh, const std::string& path) {
  const Status finite = CheckFinite(mesh);
  if (!finite.ok()) {
    return absl::InvalidArgumentError(StrCat("WriteMeshJson(", path, "): ", finite.message()));
  }
  return WriteFile(path, MeshToJson(mesh).dump() + '\n');
}

Result<ProxyMesh> ReadMeshJson(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return absl::NotFoundError(StrCat("ReadMeshJson: cannot open ", path));
  json parsed = json::parse(in, nullptr, /*allow_exceptions=*/false);
  if (parsed.is_discarded()) {
    return absl::InvalidArgumentError(StrCat("ReadMeshJson(", path, "): not valid JSON"));
  }
  Result<ProxyMesh> mesh = MeshFromJson(parsed);
  if (!mesh.ok()) {
    return absl::Status(mesh.status().code(),
                        StrCat("ReadMeshJson(", path, "): ", mesh.status().message()));
  }
  return mesh;
}

}  // namespace vpm
