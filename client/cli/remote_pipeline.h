// The offline commands' work sent to a vpm-server instead: `vpm --server
// ADDR mesh ...` and `vpm --server ADDR render ...` take the same flags as
// offline and turn them into LoadVolume / BuildMesh / GetMesh (and, for
// render, OpenSession / Manipulate / Render / CloseSession) calls.
#pragma once

#include <optional>
#include <string>

#include <glm/glm.hpp>

#include "client/cli/mesh_flags.h"
#include "client/common/server_connection.h"
#include "server/common/progress.h"
#include "server/common/status.h"
#include "server/mesh/proxy_mesh.h"

namespace vpm::cli {

// LoadVolume: `source` is a path under the server's data root or phantom:NAME.
// With `progress`, the load carries a random progress_id and this polls
// GetLoadProgress every 100 ms while it runs, reporting what it says.
Result<v3::VolumeInfo> LoadVolumeOnServer(const ServerConnection& server,
                                          const std::string& source,
                                          const ProgressFn& progress = {});

// The mesh flags as the API's MeshParams; --refine-at-landmark is resolved
// with the landmarks the server reports for `volume` (NOT_FOUND if absent).
Result<v3::MeshParams> ToProtoMeshParams(const MeshFlags& flags, const v3::VolumeInfo& volume);

// A named landmark of `volume` (world LPS, mm); NOT_FOUND lists
// the volume's landmarks.
Result<glm::dvec3> FindLandmark(const v3::VolumeInfo& volume, const std::string& name);

// GetMesh with geometry, as the ProxyMesh the offline commands write: world
// LPS positions (voxel indices are not sent by the API and stay 0).
Result<ProxyMesh> FetchMesh(const ServerConnection& server, const std::string& mesh_id);

// LoadVolume + BuildMesh + FetchMesh.
struct RemoteMesh {
  v3::VolumeInfo volume;
  v3::MeshInfo info;
  ProxyMesh mesh;
};
Result<RemoteMesh> BuildMeshOnServer(const ServerConnection& server, const std::string& source,
                                     const MeshFlags& flags);

}  // namespace vpm::cli
