// `vpm health [--server HOST:PORT] [--service NAME] [--timeout-s S]`: one
// grpc.health.v1.Health/Check call to a vpm-server, the probe that the
// Docker image's HEALTHCHECK runs. Exit status 0 when the answer is SERVING;
// 1 when it is anything else (NOT_SERVING while the server drains, an
// unknown service, no answer within the timeout, nothing listening); 2 for a
// usage error. Health calls need no token (the server exempts them).
#pragma once

#include <CLI/CLI.hpp>

#include "client/common/server_connection.h"

namespace vpm::cli {

// Adds `vpm health` to `app`. `flags` are the global server flags; the
// command also takes --server and --tls-* after its name, as probes write
// them (`vpm health --server 127.0.0.1:50051`).
void AddHealthCommand(CLI::App& app, ServerFlags* flags, int* exit_code);

}  // namespace vpm::cli
