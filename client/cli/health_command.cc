#include "client/cli/health_command.h"

#include <chrono>
#include <iostream>
#include <memory>

#include <grpcpp/grpcpp.h>

#include "client/common/command_status.h"
#include "grpc/health/v1/health.grpc.pb.h"

namespace vpm::cli {
namespace {

using grpc::health::v1::HealthCheckRequest;
using grpc::health::v1::HealthCheckResponse;

// OK when `service` ("" for the whole server) answers SERVING within
// `timeout_s` seconds; otherwise an error naming what was seen.
Status CheckServing(const ServerFlags& flags, const std::string& service, double timeout_s) {
  if (!(timeout_s > 0)) return absl::InvalidArgumentError("--timeout-s must be > 0 seconds");
  // The `vpm` connection (TLS when --tls-ca is given); health needs no token.
  ASSIGN_OR_RETURN(ServerConnection connection, ServerConnection::Connect(flags));
  auto stub = grpc::health::v1::Health::NewStub(connection.channel());
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
