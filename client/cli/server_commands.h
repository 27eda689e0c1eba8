// The `vpm` commands that talk to a vpm-server (global --server HOST:PORT
// --token TOKEN): one per RPC, plus `vpm play SCRIPT.json`.
//   vpm volume load SOURCE | upload FILE | list | get ID | delete ID
//   vpm mesh-build --volume-id ID [mesh flags] | mesh-get ID [--geometry] [--json F] | mesh-refine ID X Y Z
//   vpm session open --volume-id ID [--mesh-id ID] | list | close ID
//   vpm snapshot --session ID [--camera AZ EL DIST] [--size W H] --out F   (Render)
//   vpm manipulate --session ID (--grab X Y Z | --drag DX DY DZ | --pull FX FY FZ | --release)
//   vpm set-camera --session ID AZ EL [DIST]
//   vpm watch --session ID [--frames N] [--out-dir D]
//   vpm play SCRIPT.json [--session ID] [--out-dir D] [--report F]
#pragma once

#include <CLI/CLI.hpp>

#include "client/cli/server_connection.h"

namespace vpm::cli {

// Adds --server, --token, --tls-ca to `app` (global: before the command).
void AddServerFlags(CLI::App& app, ServerFlags* flags);
// Adds the commands; the volume subcommands join `vpm volume`.
void AddServerCommands(CLI::App& app, const ServerFlags* flags, int* exit_code);

}  // namespace vpm::cli
