// The client side of `--server HOST:PORT --token TOKEN`: a channel, a stub,
// per-call contexts carrying the token, and gRPC statuses turned back into
// vpm's Status values.
#pragma once

#include <memory>
#include <string>

#include <grpcpp/grpcpp.h>

#include "server/common/status.h"
#include "vpm/v2/vpm.grpc.pb.h"

namespace vpm::cli {

struct ServerFlags {
  std::string address;   // HOST:PORT; empty: offline
  std::string token;     // default: env VPM_TOKEN
  std::string tls_ca;    // PEM of the CA that signed the server: turns TLS on
  std::string tls_cert;  // client certificate chain (PEM) for mutual TLS
  std::string tls_key;   // its private key (PEM)
  double deadline_s = 300;
};

class ServerConnection {
 public:
  static Result<ServerConnection> Connect(const ServerFlags& flags);

  v2::Vpm::Stub& stub() const { return *stub_; }
  // For other services on the same server (grpc.health.v1).
  std::shared_ptr<grpc::Channel> channel() const { return channel_; }
  // A context with the token and, unless streaming, a deadline.
  std::unique_ptr<grpc::ClientContext> Context(bool streaming = false) const;

 private:
  ServerFlags flags_;
  std::shared_ptr<grpc::Channel> channel_;
  std::shared_ptr<v2::Vpm::Stub> stub_;
};

inline Status FromGrpc(const grpc::Status& status) {
  if (status.ok()) return absl::OkStatus();
  return Status(static_cast<absl::StatusCode>(status.error_code()), status.error_message());
}

}  // namespace vpm::cli
