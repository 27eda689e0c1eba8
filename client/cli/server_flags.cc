#include "client/cli/server_flags.h"

namespace vpm::cli {

void AddServerFlags(CLI::App& app, ServerFlags* flags) {
  app.add_option("--server", flags->address, "HOST:PORT of a vpm-server (server commands)");
  app.add_option("--token", flags->token, "bearer token (default: env VPM_TOKEN)");
  app.add_option("--tls-ca", flags->tls_ca, "CA certificate (PEM) of a TLS server: turns TLS on");
  app.add_option("--tls-cert", flags->tls_cert, "client certificate (PEM) for mutual TLS");
  app.add_option("--tls-key", flags->tls_key, "client private key (PEM) for mutual TLS");
  app.add_option("--session-key", flags->session_key,
                 "x-vpm-session of every call: a balancer keeps the calls of one key on one "
                 "vpm-server replica (default: env VPM_SESSION_KEY, else one key per user and "
                 "host)");
  app.add_option("--deadline-s", flags->deadline_s, "deadline of unary calls, seconds")
      ->capture_default_str();
}

}  // namespace vpm::cli
