// `vpm slice --volume SRC [mesh flags | --mesh-json M] [--grab X Y Z |
//   --grab-landmark NAME] [--drag DX DY DZ | --pull FX FY FZ]
//   --plane axial|coronal|sagittal|oblique [--at MM | --at-landmark NAME]
//   [--normal NX NY NZ] [--window W L] [--pixel MM] [--overlay] --out slice.png`:
// a slice of the (optionally deformed) volume, offline, through the same
// backward map as `vpm render`. Without --at the plane passes through the
// grabbed tissue where the drag moved it (else the volume's centre).
// With --server ADDR --session ID (and no --volume): the same plane flags
// as a RenderSlice of that session's current deformation.
#pragma once

#include <CLI/CLI.hpp>

#include "client/common/server_connection.h"

namespace vpm::cli {

void AddSliceCommand(CLI::App& app, const ServerFlags* server_flags, int* exit_code);

}  // namespace vpm::cli
