// `vpm case list|show|open|rename|notes|delete|share|undo|redo|export|import`:
// the cases of a vpm-server started with --state-dir or --state
// (docs/CASES.md).
#pragma once

#include <CLI/CLI.hpp>

#include "client/common/server_connection.h"

namespace vpm::cli {

void AddCaseCommands(CLI::App& app, const ServerFlags* flags, int* exit_code);

}  // namespace vpm::cli
