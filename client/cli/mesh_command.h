// `vpm mesh --volume SRC [mesh flags] [--json OUT.json] [--vtu OUT.vtu]`:
// builds the volume proxy mesh offline and prints its stage timings.
#pragma once

#include <CLI/CLI.hpp>

namespace vpm::cli {

void AddMeshCommand(CLI::App& app, int* exit_code);

}  // namespace vpm::cli
