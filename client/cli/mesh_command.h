// `vpm mesh --volume SRC [mesh flags] [--json OUT.json] [--vtu OUT.vtu]`:
// builds the volume proxy mesh offline (or, with the global --server, on a
// vpm-server) and prints its stage timings.
#pragma once

#include <CLI/CLI.hpp>

#include "client/common/server_connection.h"

namespace vpm::cli {

// `server`: the global server flags; an address sends the build to that server.
void AddMeshCommand(CLI::App& app, const ServerFlags* server, int* exit_code);

}  // namespace vpm::cli
