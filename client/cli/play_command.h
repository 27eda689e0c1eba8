// `vpm play SCRIPT.json`: replays an interaction script over a session's
// Interact stream (the script format is in client/common/script_player.h),
// saves the frames and prints and writes a timing report.
#pragma once

#include <CLI/CLI.hpp>

#include "client/common/server_connection.h"

namespace vpm::cli {

void AddPlayCommand(CLI::App& app, const ServerFlags* flags, int* exit_code);

}  // namespace vpm::cli
