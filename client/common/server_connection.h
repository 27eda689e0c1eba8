// The client side of `--server HOST:PORT --token TOKEN`: a channel, a stub,
// per-call contexts carrying the token and the affinity key
// (`x-vpm-session`, session_key.h), and gRPC statuses turned back into vpm's
// Status values.
#pragma once

#include <memory>
#include <string>

#include <grpcpp/grpcpp.h>

#include "server/common/status.h"
#include "vpm/v3/vpm.grpc.pb.h"

namespace vpm::cli {

struct ServerFlags {
  std::string address;   // HOST:PORT; empty: offline
  std::string token;     // default: env VPM_TOKEN
  std::string tls_ca;    // PEM of the CA that signed the server: turns TLS on
  std::string tls_cert;  // client certificate chain (PEM) for mutual TLS
  std::string tls_key;   // its private key (PEM)
  std::string session_key;  // x-vpm-session of every call; default: DefaultSessionKey()
  double deadline_s = 300;
};

class ServerConnection {
 public:
  static Result<ServerConnection> Connect(const ServerFlags& flags);

  v3::Vpm::Stub& stub() const { return *stub_; }
  // For other services on the same server (grpc.health.v1).
  std::shared_ptr<grpc::Channel> channel() const { return channel_; }
  const std::string& session_key() const { return flags_.session_key; }
  // A context with the token, the session key and, unless streaming, a deadline.
  std::unique_ptr<grpc::ClientContext> Context(bool streaming = false) const;
  // CloseSession, its outcome ignored: for a client leaving sessions it
  // opened (one already gone is NOT_FOUND, which changes nothing; the
  // server evicts idle sessions anyway).
  void CloseSessionQuietly(const std::string& session_id) const;

 private:
  ServerFlags flags_;
  std::shared_ptr<grpc::Channel> channel_;
  std::shared_ptr<v3::Vpm::Stub> stub_;
};

inline Status FromGrpc(const grpc::Status& status) {
  if (status.ok()) return absl::OkStatus();
  return Status(static_cast<absl::StatusCode>(status.error_code()), status.error_message());
}

// The end of a stream as a Status. A balancer that loses the replica behind
// a stream (HAProxy when a vpm-server dies) ends the stream without gRPC
// trailers, which gRPC reports as UNKNOWN "No status received", or resets it
// (CANCELLED "Received RST_STREAM ..."): either becomes UNAVAILABLE saying so.
Status FromStreamEnd(const grpc::Status& status);

// True when the session is gone with its replica, or out of reach: the
// replica (or the balancer) is unavailable or stopping, or the call reached
// a replica that does not hold the session (NOT_FOUND). A client that can
// reload its volume reopens a session then; the balancer sends it to a
// replica that is up.
bool SessionLost(const Status& status);

}  // namespace vpm::cli
