// `vpm data ls [PATH] [--json]`: ListDataRoot, the folders and volume files
// under a vpm-server's --data-root (for users the server's users file gives
// browse-data-root). What it lists opens with `vpm volume load SOURCE`.
#pragma once

#include <CLI/CLI.hpp>

#include "client/common/server_connection.h"

namespace vpm::cli {

void AddDataRootCommands(CLI::App& app, const ServerFlags* flags, int* exit_code);

}  // namespace vpm::cli
