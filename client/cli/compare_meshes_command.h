// `vpm compare-meshes --volume SRC [mesh flags]`: the section-6 measures of a
// regular lattice and of the optimized mesh per density mode and footprint,
// all with the same vertex budget, as a table.
#pragma once

#include <CLI/CLI.hpp>

namespace vpm::cli {

void AddCompareMeshesCommand(CLI::App& app, int* exit_code);

}  // namespace vpm::cli
