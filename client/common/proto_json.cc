#include "client/common/proto_json.h"

#include <iostream>
#include <vector>

namespace vpm::cli {

using nlohmann::json;

namespace {

json Vec(const v3::Vec3& v) { return {v.x(), v.y(), v.z()}; }

}  // namespace

json VolumeJson(const v3::VolumeInfo& v) {
  json j{{"volume_id", v.volume_id()}, {"source", v.source()}, {"bytes", v.bytes()},
         {"sessions", v.sessions()}, {"min_value", v.min_value()}, {"max_value", v.max_value()},
         {"owner", v.owner()}};
  j["dims"] = std::vector<int64_t>(v.dims().begin(), v.dims().end());
  // The world geometry, as `vpm volume info --json` gives it (world LPS, mm).
  j["spacing_mm"] = Vec(v.spacing_mm());
  j["origin_lps_mm"] = Vec(v.origin_lps_mm());
  if (v.direction_size() == 9) {
    j["direction_columns_lps"] = {{v.direction(0), v.direction(1), v.direction(2)},
                                  {v.direction(3), v.direction(4), v.direction(5)},
                                  {v.direction(6), v.direction(7), v.direction(8)}};
  }
  j["box_lps_mm"] = {Vec(v.box_lo_lps_mm()), Vec(v.box_hi_lps_mm())};
  j["voxel_encoding"] = v.voxel_encoding();
  j["notes"] = std::vector<std::string>(v.notes().begin(), v.notes().end());
  j["stacks"] = std::vector<std::string>(v.stacks().begin(), v.stacks().end());
  j["stack"] = v.stack();
  j["landmarks"] = json::array();
  for (const auto& l : v.landmarks()) {
    j["landmarks"].push_back({{"name", l.name()}, {"position_mm", Vec(l.position_mm())},
                              {"description", l.description()}});
  }
  return j;
}

json MeshJson(const v3::MeshInfo& m) {
  const auto& s = m.stats();
  return {{"mesh_id", m.mesh_id()}, {"volume_id", m.volume_id()},
          {"vertices", s.vertices()}, {"tets", s.tets()}, {"hard", s.hard()},
          {"refined", s.refined()}, {"h_mm", s.h_mm()}, {"min_dihedral_deg", s.min_dihedral_deg()}};
}

json SessionJson(const v3::SessionInfo& s) {
  return {{"session_id", s.session_id()}, {"volume_id", s.volume_id()},
          {"mesh_id", s.mesh_id()},       {"viewers", s.viewers()},
          {"idle_s", s.idle_s()},         {"owner", s.owner()},
          {"case_id", s.case_id()},
          {"shared_with", std::vector<std::string>(s.shared_with().begin(), s.shared_with().end())}};
}

void PrintJson(const json& j) { std::cout << j.dump(2) << "\n"; }

}  // namespace vpm::cli
