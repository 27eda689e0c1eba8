// vpm-server's command line: every ServerOptions field as a documented flag.
#pragma once

#include <CLI/CLI.hpp>

#include "server/service/server_options.h"

namespace vpm::service {

void AddServerFlags(CLI::App& app, ServerOptions* options);
// The token from VPM_TOKEN when neither --token nor --token-file was given.
void ApplyEnvironment(ServerOptions* options);

}  // namespace vpm::service
