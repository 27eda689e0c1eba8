// vpm-server's command line: every ServerOptions field as a documented flag.
#pragma once

#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "server/service/server_options.h"

namespace vpm::service {

void AddServerFlags(CLI::App& app, ServerOptions* options);
// The token from VPM_TOKEN when neither --token nor --token-file was given.
void ApplyEnvironment(ServerOptions* options);

// A line for each per-user cap that is not below its server-wide cap (then
// one user at their cap can fill the server's and leave others nothing),
// e.g. "--max-volumes-per-user 4 is not below --max-volumes 4: ...";
// vpm-server prints them as warnings at start.
std::vector<std::string> FairShareWarnings(const ServerOptions& options);

}  // namespace vpm::service
