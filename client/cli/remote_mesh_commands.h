// `vpm mesh-build|mesh-get|mesh-refine|mesh-delete`: the mesh RPCs of a
// vpm-server (BuildMesh, GetMesh with --json for the geometry, RefineMesh,
// DeleteMesh).
#pragma once

#include <CLI/CLI.hpp>

#include "client/common/server_connection.h"

namespace vpm::cli {

void AddRemoteMeshCommands(CLI::App& app, const ServerFlags* flags, int* exit_code);

}  // namespace vpm::cli
