// `vpm render --volume SRC [--mesh-json M.json | mesh flags] [--camera AZ EL DIST]
//   [--mode dvr|mip] [--preset NAME] [--grab X Y Z | --grab-landmark NAME
//   --drag DX DY DZ | --pull FX FY FZ] [--size W H] [--overlay] --out frame.png|jpg`:
// one frame of the (optionally deformed) volume, offline; with the global
// --server the same request goes to a vpm-server.
#pragma once

#include <CLI/CLI.hpp>

#include "client/common/server_connection.h"

namespace vpm::cli {

void AddRenderCommand(CLI::App& app, const ServerFlags* server, int* exit_code);

}  // namespace vpm::cli
