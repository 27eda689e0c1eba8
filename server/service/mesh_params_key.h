// A canonical text key of (volume, mesh parameters): two BuildMesh calls
// with equal keys build the same mesh, so the store hands back the one it
// has. Doubles are written exactly (hexadecimal floating point).
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "server/mesh/build_proxy_mesh.h"

namespace vpm::service {

// nullopt when the parameters carry hardness overrides (not part of the key:
// such meshes are never shared).
std::optional<std::string> MeshParamsKey(std::string_view volume_id, const MeshParams& params);

}  // namespace vpm::service
