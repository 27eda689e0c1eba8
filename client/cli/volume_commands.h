// `vpm volume info SRC [--json]` and `vpm volume export SRC OUT.nii[.gz]`.
#pragma once

#include <CLI/CLI.hpp>

namespace vpm::cli {

// Registers the subcommands; *exit_code receives the command's exit status.
void AddVolumeCommands(CLI::App& app, int* exit_code);

}  // namespace vpm::cli
