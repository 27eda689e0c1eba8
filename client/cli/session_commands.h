// The session commands of a vpm-server: `vpm session open|list|get|share|close`,
// `vpm snapshot` (Render one still frame), `vpm manipulate` (one grab, drag,
// pull or release), `vpm set-camera` and `vpm watch` (a session's frames).
#pragma once

#include <CLI/CLI.hpp>

#include "client/common/server_connection.h"

namespace vpm::cli {

void AddSessionCommands(CLI::App& app, const ServerFlags* flags, int* exit_code);

}  // namespace vpm::cli
