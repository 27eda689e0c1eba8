// The server's replies as the JSON the `vpm` server commands print:
// VolumeInfo, MeshInfo and SessionInfo with the proto's field names.
#pragma once

#include <nlohmann/json.hpp>

#include "vpm/v3/vpm.pb.h"

namespace vpm::cli {

nlohmann::json VolumeJson(const v3::VolumeInfo& volume);
nlohmann::json MeshJson(const v3::MeshInfo& mesh);
nlohmann::json SessionJson(const v3::SessionInfo& session);
// Writes `j` to stdout, indented by 2.
void PrintJson(const nlohmann::json& j);

}  // namespace vpm::cli
