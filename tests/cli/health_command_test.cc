// `vpm health`, the probe of the Docker HEALTHCHECK: its exit status and
// message against a real vpm-server (out of process), against a gRPC server
// in this process whose health status the test sets (NOT_SERVING, named
// services), against a closed port and against a peer that never answers.
#include <netinet/in.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <memory>
#include <string>

#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>
#include <gtest/gtest.h>

#include "tests/cli/command_run.h"
#include "vpm/v3/vpm.grpc.pb.h"

extern char** environ;

namespace {

using vpm::testing::CommandRun;
using vpm::testing::RunCommand;

// Appended, not `std::string(VPM_CLI) + " " + args`: GCC 12 warns falsely
// (-Warray-bounds) on that concatenation once inlined.
CommandRun Vpm(const std::string& args) {
  std::string command = VPM_CLI;
  command += ' ';
  command += args;
  return RunCommand(command);
}

// vpm-server as a child process on 127.0.0.1 with an ephemeral port, without
// a token (health calls need none either way); SIGTERM on Stop().
class ServerProcess {
 public:
  ServerProcess() {
    int out[2];
    if (pipe(out) != 0) return;
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, out[1], STDOUT_FILENO);
    posix_spawn_file_actions_addclose(&actions, out[0]);
    const char* argv[] = {VPM_SERVER, "--listen", "127.0.0.1:0", "--no-auth",
                          "--shutdown-grace-s", "1", nullptr};
    if (posix_spawn(&pid_, VPM_SERVER, &actions, nullptr, const_cast<char**>(argv), environ) != 0) {
      pid_ = -1;
    }
    posix_spawn_file_actions_destroy(&actions);
    close(out[1]);
    // The first line on stdout: "vpm-server listening on port N ...". The
    // pipe stays open until Stop(): the server writes again when it drains.
    stdout_of_server_ = fdopen(out[0], "r");
    char line[512];
    while (pid_ > 0 && fgets(line, sizeof line, stdout_of_server_) != nullptr) {
      if (std::sscanf(line, "vpm-server listening on port %d", &port_) == 1) break;
    }
  }
  ~ServerProcess() { Stop(); }

  std::string address() const { return "127.0.0.1:" + std::to_string(port_); }
  int port() const { return port_; }
  // SIGTERM, then waits until the process is gone (the port is closed).
  void Stop() {
    if (pid_ <= 0) return;
    kill(pid_, SIGTERM);
    char line[512];
    while (fgets(line, sizeof line, stdout_of_server_) != nullptr) {
    }
    int status = 0;
    waitpid(pid_, &status, 0);
    pid_ = -1;
    fclose(stdout_of_server_);
  }

 private:
  pid_t pid_ = -1;
  int port_ = 0;
  FILE* stdout_of_server_ = nullptr;
};

// A gRPC server in this process with grpc.health.v1 (the same default
// service vpm-server enables), so the test sets its status. The vpm.v3.Vpm
// base service (every method UNIMPLEMENTED) is there because gRPC polls
// the default health service only on a server with synchronous methods.
class HealthOnlyServer {
 public:
  HealthOnlyServer() {
    grpc::EnableDefaultHealthCheckService(true);
    grpc::ServerBuilder builder;
    builder.AddListeningPort("127.0.0.1:0", grpc::InsecureServerCredentials(), &port_);
    builder.RegisterService(&unimplemented_);
    server_ = builder.BuildAndStart();
  }
  ~HealthOnlyServer() { server_->Shutdown(std::chrono::system_clock::now()); }

  std::string address() const { return "127.0.0.1:" + std::to_string(port_); }
  grpc::HealthCheckServiceInterface& health() { return *server_->GetHealthCheckService(); }

 private:
  int port_ = 0;
  vpm::v3::Vpm::Service unimplemented_;
  std::unique_ptr<grpc::Server> server_;
};

// A TCP port that accepts connections and never says a word: a hung peer.
class SilentListener {
 public:
  SilentListener() {
    fd_ = socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t size = sizeof address;
    bind(fd_, reinterpret_cast<sockaddr*>(&address), size);
    listen(fd_, 4);
    getsockname(fd_, reinterpret_cast<sockaddr*>(&address), &size);
    port_ = ntohs(address.sin_port);
  }
  ~SilentListener() { close(fd_); }
  std::string address() const { return "127.0.0.1:" + std::to_string(port_); }

 private:
  int fd_ = -1;
  int port_ = 0;
};

TEST(HealthCommand, RunningVpmServerIsServingThenItsClosedPortFails) {
  ServerProcess server;
  ASSERT_GT(server.port(), 0) << "vpm-server did not start";
  const CommandRun serving = Vpm("health --server " + server.address());
  EXPECT_EQ(serving.exit_code, 0) << serving.output;
  EXPECT_NE(serving.output.find("SERVING"), std::string::npos) << serving.output;
  // The global flag before the command works as well.
  EXPECT_EQ(Vpm("--server " + server.address() + " health").exit_code, 0);

  server.Stop();
  const CommandRun stopped = Vpm("health --server " + server.address() + " --timeout-s 2");
  EXPECT_EQ(stopped.exit_code, 1) << stopped.output;
  EXPECT_NE(stopped.output.find("UNAVAILABLE"), std::string::npos) << stopped.output;
  EXPECT_NE(stopped.output.find(server.address()), std::string::npos) << stopped.output;
}

TEST(HealthCommand, NotServingExitsOneNamingTheStatus) {
  HealthOnlyServer server;
  server.health().SetServingStatus(false);  // what vpm-server does while it drains
  const CommandRun draining = Vpm("health --server " + server.address());
  EXPECT_EQ(draining.exit_code, 1) << draining.output;
  EXPECT_NE(draining.output.find("NOT_SERVING"), std::string::npos) << draining.output;

  server.health().SetServingStatus(true);
  EXPECT_EQ(Vpm("health --server " + server.address()).exit_code, 0);
}

TEST(HealthCommand, NamedServiceIsCheckedAndAnUnknownOneFails) {
  HealthOnlyServer server;
  server.health().SetServingStatus("vpm.v3.Vpm", true);
  const CommandRun known = Vpm("health --server " + server.address() + " --service vpm.v3.Vpm");
  EXPECT_EQ(known.exit_code, 0) << known.output;
  EXPECT_NE(known.output.find("vpm.v3.Vpm"), std::string::npos) << known.output;

  const CommandRun unknown = Vpm("health --server " + server.address() + " --service no.such.Service");
  EXPECT_EQ(unknown.exit_code, 1) << unknown.output;
  EXPECT_NE(unknown.output.find("does not report this service"), std::string::npos) << unknown.output;
}

TEST(HealthCommand, SilentPeerFailsAfterTheTimeout) {
  SilentListener peer;
  const auto start = std::chrono::steady_clock::now();
  const CommandRun run = Vpm("health --server " + peer.address() + " --timeout-s 0.5");
  const double elapsed_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_NE(run.output.find("no health answer within 0.5 s"), std::string::npos) << run.output;
  EXPECT_LT(elapsed_s, 10.0);  // bounded by the timeout, not by gRPC's 20 s handshake
}

TEST(HealthCommand, UsageErrorsExitTwo) {
  const CommandRun no_server = Vpm("health");
  EXPECT_EQ(no_server.exit_code, 2) << no_server.output;
  EXPECT_NE(no_server.output.find("--server HOST:PORT is required"), std::string::npos);
  const CommandRun bad_ca = Vpm("health --server 127.0.0.1:1 --tls-ca /no/such/ca.pem");
  EXPECT_EQ(bad_ca.exit_code, 2) << bad_ca.output;
  EXPECT_NE(bad_ca.output.find("/no/such/ca.pem"), std::string::npos) << bad_ca.output;
  EXPECT_EQ(Vpm("health --server 127.0.0.1:1 --timeout-s 0").exit_code, 2);
  const CommandRun key_alone = Vpm("health --server 127.0.0.1:1 --tls-key /tmp/key.pem");
  EXPECT_EQ(key_alone.exit_code, 2) << key_alone.output;
  EXPECT_NE(key_alone.output.find("go together"), std::string::npos) << key_alone.output;
}

}  // namespace
