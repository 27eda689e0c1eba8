#include "client/common/server_connection.h"

#include "client/common/session_key.h"
#include "server/common/read_text_file.h"

#include <cstdlib>

namespace vpm::cli {

Result<ServerConnection> ServerConnection::Connect(const ServerFlags& flags) {
  if (flags.address.empty()) return absl::InvalidArgumentError("--server HOST:PORT is required");
  ServerConnection c;
  c.flags_ = flags;
  if (c.flags_.token.empty()) {
    if (const char* token = std::getenv("VPM_TOKEN")) c.flags_.token = token;
  }
  if (c.flags_.session_key.empty()) c.flags_.session_key = DefaultSessionKey();
  std::shared_ptr<grpc::ChannelCredentials> credentials = grpc::InsecureChannelCredentials();
  if (flags.tls_cert.empty() != flags.tls_key.empty() ||
      (!flags.tls_cert.empty() && flags.tls_ca.empty())) {
    return absl::InvalidArgumentError(
        "--tls-cert and --tls-key go together (mutual TLS), with --tls-ca (the server's CA)");
  }
  if (!flags.tls_ca.empty()) {
    grpc::SslCredentialsOptions ssl;
    ASSIGN_OR_RETURN(ssl.pem_root_certs, ReadTextFile(flags.tls_ca, "--tls-ca"));
    if (!flags.tls_cert.empty()) {
      ASSIGN_OR_RETURN(ssl.pem_cert_chain, ReadTextFile(flags.tls_cert, "--tls-cert"));
      ASSIGN_OR_RETURN(ssl.pem_private_key, ReadTextFile(flags.tls_key, "--tls-key"));
    }
    credentials = grpc::SslCredentials(ssl);
  }
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(64 << 20);
  c.channel_ = grpc::CreateCustomChannel(flags.address, credentials, args);
  c.stub_ = v3::Vpm::NewStub(c.channel_);
  return c;
}

std::unique_ptr<grpc::ClientContext> ServerConnection::Context(bool streaming) const {
  auto context = std::make_unique<grpc::ClientContext>();
  if (!flags_.token.empty()) context->AddMetadata("authorization", "Bearer " + flags_.token);
  context->AddMetadata(kSessionKeyHeader, flags_.session_key);
  if (!streaming) {
    context->set_deadline(std::chrono::system_clock::now() +
                          std::chrono::milliseconds(int64_t(flags_.deadline_s * 1000)));
  }
  return context;
}

Status FromStreamEnd(const grpc::Status& status) {
  const bool no_trailers = status.error_code() == grpc::StatusCode::UNKNOWN &&
                           status.error_message() == "No status received";
  const bool reset = status.error_code() == grpc::StatusCode::CANCELLED &&
                     status.error_message().starts_with("Received RST_STREAM");
  if (no_trailers || reset) {
    return absl::UnavailableError(
        "the stream ended without a status: the vpm-server replica behind the balancer went "
        "away");
  }
  return FromGrpc(status);
}

bool SessionLost(const Status& status) {
  return absl::IsUnavailable(status) || absl::IsNotFound(status);
}

void ServerConnection::CloseSessionQuietly(const std::string& session_id) const {
  v3::CloseSessionRequest request;
  request.set_session_id(session_id);
  v3::CloseSessionResponse response;
  (void)stub_->CloseSession(Context().get(), request, &response);
}

}  // namespace vpm::cli
