#include "client/cli/health_command.h"

#include <chrono>
#include <fstream>
#include <iostream>
#include <iterator>
#include <memory>
#include <tuple>

#include <grpcpp/grpcpp.h>

#include "client/cli/command_status.h"
#include "grpc/health/v1/health.grpc.pb.h"

namespace vpm::cli {
namespace {

using grpc::health::v1::HealthCheckRequest;
using grpc::health::v1::HealthCheckResponse;

// A plain channel: no token, no message-size arguments, nothing a health
// call needs. TLS when --tls-ca names the CA that signed the server, with a
// client certificate (--tls-cert, --tls-key) for a server that asks for one.
Result<std::shared_ptr<grpc::Channel>> HealthChannel(const ServerFlags& flags) {
  if (flags.address.empty()) return absl::InvalidArgumentError("--server HOST:PORT is required");
  if (flags.tls_cert.empty() != flags.tls_key.empty() ||
      (!flags.tls_cert.empty() && flags.tls_ca.empty())) {
    return absl::InvalidArgumentError("--tls-cert and --tls-key go together, with --tls-ca");
  }
  if (flags.tls_ca.empty()) {
    return grpc::CreateChannel(flags.address, grpc::InsecureChannelCredentials());
  }
  grpc::SslCredentialsOptions ssl;
  const std::tuple<const char*, const std::string&, std::string&> pem_files[] = {
      {"--tls-ca", flags.tls_ca, ssl.pem_root_certs},
      {"--tls-cert", flags.tls_cert, ssl.pem_cert_chain},
      {"--tls-key", flags.tls_key, ssl.pem_private_key}};
  for (const auto& [flag, path, pem] : pem_files) {
    if (path.empty()) continue;
    std::ifstream file(path);
    if (!file) return absl::InvalidArgumentError(StrCat(flag, " ", path, ": cannot read"));
    pem.assign(std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>());
  }
  return grpc::CreateChannel(flags.address, grpc::SslCredentials(ssl));
}

// OK when `service` ("" for the whole server) answers SERVING within
// `timeout_s` seconds; otherwise an error naming what was seen.
Status CheckServing(const ServerFlags& flags, const std::string& service, double timeout_s) {
  if (!(timeout_s > 0)) return absl::InvalidArgumentError("--timeout-s must be > 0 seconds");
  ASSIGN_OR_RETURN(std::shared_ptr<grpc::Channel> channel, HealthChannel(flags));
  auto stub = grpc::health::v1::Health::NewStub(channel);
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() +
                       std::chrono::milliseconds(int64_t(timeout_s * 1000)));
  HealthCheckRequest request;
  request.set_service(service);
  HealthCheckResponse response;
  const grpc::Status call = stub->Check(&context, request, &response);
  const std::string what =
      StrCat(flags.address, service.empty() ? "" : StrCat(" (service \"", service, "\")"));
  switch (call.error_code()) {
    case grpc::OK:
      break;
    case grpc::NOT_FOUND:
      return absl::NotFoundError(StrCat(what, ": the server does not report this service"));
    case grpc::DEADLINE_EXCEEDED:
      return absl::DeadlineExceededError(
          StrCat(what, ": no health answer within ", timeout_s, " s"));
    default:
      return Status(static_cast<absl::StatusCode>(call.error_code()),
                    StrCat(what, ": health check failed: ", call.error_message()));
  }
  const std::string serving = HealthCheckResponse::ServingStatus_Name(response.status());
  if (response.status() != HealthCheckResponse::SERVING) {
    return absl::UnavailableError(StrCat(what, ": ", serving));
  }
  std::cout << what << ": " << serving << "\n";
  return absl::OkStatus();
}

}  // namespace

void AddHealthCommand(CLI::App& app, ServerFlags* flags, int* exit_code) {
  struct HealthArgs {
    std::string service;
    double timeout_s = 5;
  };
  auto a = std::make_shared<HealthArgs>();
  CLI::App* health = app.add_subcommand(
      "health", "server: grpc.health.v1 Check; exit 0 when SERVING, 1 otherwise (a probe)");
  health->add_option("--server", flags->address, "HOST:PORT of the vpm-server");
  health->add_option("--tls-ca", flags->tls_ca, "CA certificate (PEM) of a TLS server");
  health->add_option("--tls-cert", flags->tls_cert, "client certificate (PEM) for mutual TLS");
  health->add_option("--tls-key", flags->tls_key, "client private key (PEM) for mutual TLS");
  health->add_option("--service", a->service, "service to ask about (default: the whole server)");
  health->add_option("--timeout-s", a->timeout_s, "deadline of the check, seconds")
      ->capture_default_str();
  health->callback([flags, exit_code, a] {
    *exit_code = ExitWith(CheckServing(*flags, a->service, a->timeout_s));
  });
}

}  // namespace vpm::cli
