#include "client/cli/proto_json.h"

#include <iostream>
#include <vector>

namespace vpm::cli {

using nlohmann::json;

json VolumeJson(const v2::VolumeInfo& v) {
  json j{{"volume_id", v.volume_id()}, {"source", v.source()}, {"bytes", v.bytes()},
         {"sessions", v.sessions()}, {"min_value", v.min_value()}, {"max_value", v.max_value()},
         {"owner", v.owner()}};
  j["dims"] = std::vector<int64_t>(v.dims().begin(), v.dims().end());
  j["spacing_mm"] = {v.spacing_mm().x(), v.spacing_mm().y(), v.spacing_mm().z()};
  j["origin_lps_mm"] = {v.origin_lps_mm().x(), v.origin_lps_mm().y(), v.origin_lps_mm().z()};
  j["direction"] = std::vector<double>(v.direction().begin(), v.direction().end());
  j["voxel_encoding"] = v.voxel_encoding();
  j["notes"] = std::vector<std::string>(v.notes().begin(), v.notes().end());
  for (const auto& l : v.landmarks()) {
    j["landmarks"].push_back({{"name", l.name()},
                              {"position_mm", {l.position_mm().x(), l.position_mm().y(),
                                               l.position_mm().z()}}});
  }
  return j;
}

json MeshJson(const v2::MeshInfo& m) {
  const auto& s = m.stats();
  return {{"mesh_id", m.mesh_id()}, {"volume_id", m.volume_id()},
          {"vertices", s.vertices()}, {"tets", s.tets()}, {"hard", s.hard()},
          {"refined", s.refined()}, {"h_mm", s.h_mm()}, {"min_dihedral_deg", s.min_dihedral_deg()}};
}

json SessionJson(const v2::SessionInfo& s) {
  return {{"session_id", s.session_id()}, {"volume_id", s.volume_id()},
          {"mesh_id", s.mesh_id()},       {"viewers", s.viewers()},
          {"idle_s", s.idle_s()},         {"owner", s.owner()},
          {"shared_with", std::vector<std::string>(s.shared_with().begin(), s.shared_with().end())}};
}

void PrintJson(const json& j) { std::cout << j.dump(2) << "\n"; }

}  // namespace vpm::cli
