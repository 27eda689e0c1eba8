// The global flags of the server commands (--server, --token, --tls-*,
// --session-key, --deadline-s) and WithServer, which runs a command on a connection and
// turns its Status into the process's exit code.
#pragma once

#include <functional>

#include <CLI/CLI.hpp>

#include "client/common/command_status.h"
#include "client/common/server_connection.h"

namespace vpm::cli {

// Adds --server, --token, --tls-ca, --tls-cert, --tls-key, --session-key,
// --deadline-s to
// `app` (global: before the command).
void AddServerFlags(CLI::App& app, ServerFlags* flags);

// A CLI11 callback that connects with *flags and runs fn(connection); the
// command's exit code from its Status.
template <typename Fn>
std::function<void()> WithServer(const ServerFlags* flags, int* exit_code, Fn fn) {
  return [flags, exit_code, fn] {
    auto server = ServerConnection::Connect(*flags);
    *exit_code = ExitWith(server.ok() ? fn(*server) : server.status());
  };
}

}  // namespace vpm::cli
