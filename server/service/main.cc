// vpm-server: the vpm gRPC service (see `vpm-server --help`). Stops on
// SIGTERM or SIGINT: health turns NOT_SERVING for --drain-s seconds while
// calls on existing sessions go on (a second signal cuts the drain short),
// then streams finish and calls get --shutdown-grace-s seconds.
// `vpm-server --hash-token NAME` reads a token on stdin and prints the
// users-file line for it (users_file.h).
#include <cmath>
#include <csignal>
#include <cstdio>
#include <ctime>
#include <iostream>
#include <iterator>
#include <string>

#include <CLI/CLI.hpp>
#include <absl/debugging/failure_signal_handler.h>
#include <absl/debugging/symbolize.h>

#include "server/service/server_flags.h"
#include "server/service/users_file.h"
#include "server/service/vpm_server.h"

namespace {

// --hash-token NAME: the users-file line for the token on stdin.
int PrintUsersLine(const std::string& user) {
  std::string token(std::istreambuf_iterator<char>(std::cin), {});
  while (!token.empty() && (token.back() == '\n' || token.back() == '\r')) token.pop_back();
  auto line = vpm::service::UsersFileLine(user, token);
  if (!line.ok()) {
    std::fprintf(stderr, "vpm-server: --hash-token: %s\n",
                 std::string(line.status().message()).c_str());
    return 2;
  }
  std::printf("%s\n", line->c_str());
  return 0;
}

void PrintListening(vpm::service::VpmServer& server, const vpm::service::ServerOptions& o) {
  std::printf("vpm-server listening on port %d%s%s\n", server.port(), o.no_auth ? " (no auth)" : "",
              server.metrics().metrics_port() > 0
                  ? (" metrics on port " + std::to_string(server.metrics().metrics_port())).c_str()
                  : "");
  if (const auto* pacs = server.context().pacs; pacs != nullptr && pacs->listen_port() > 0) {
    std::printf("vpm-server DICOM node on port %d\n", pacs->listen_port());
  }
  std::fflush(stdout);
}

// After the first signal: the drain (health NOT_SERVING, new sessions
// refused) until --drain-s has passed or a second signal comes, then the
// shutdown with its grace.
void DrainAndStop(vpm::service::VpmServer& server, const vpm::service::ServerOptions& options,
                  const sigset_t& signals, int signal) {
  if (options.drain_s > 0) {
    std::printf(
        "vpm-server: signal %d, health NOT_SERVING for %.1f s (drain), new sessions "
        "refused\n",
        signal, options.drain_s);
    std::fflush(stdout);
    server.BeginDrain();
    const double whole = std::floor(options.drain_s);
    const timespec drain{static_cast<time_t>(whole),
                         static_cast<long>((options.drain_s - whole) * 1e9)};
    if (sigtimedwait(&signals, nullptr, &drain) > 0) {
      std::printf("vpm-server: second signal, drain cut short\n");
    }
  }
  std::printf("vpm-server: signal %d, stopping (%.1f s grace)\n", signal, options.shutdown_grace_s);
  std::fflush(stdout);
  server.Shutdown(std::chrono::milliseconds(int64_t(options.shutdown_grace_s * 1000)));
  std::printf(
      "vpm-server: stopped; %.0f streams opened, %.0f released, %.0f frames, %.0f superseded\n",
      server.metrics().streams_opened(), server.metrics().streams_closed(),
      server.metrics().frames(), server.metrics().superseded());
  std::fflush(stdout);  // the work is done: say so before the process's own teardown
}

}  // namespace

int main(int argc, char** argv) {
  absl::InitializeSymbolizer(argv[0]);
  CLI::App app{"vpm-server: volume proxy meshes, FEM deformation and ray-cast frames over gRPC"};
  vpm::service::ServerOptions options;
  vpm::service::AddServerFlags(app, &options);
  std::string hash_token_user;
  app.add_option("--hash-token", hash_token_user,
                 "print the --users line of user NAME, the token read from stdin "
                 "(one line; the newline is dropped), and exit");
  CLI11_PARSE(app, argc, argv);
  if (!hash_token_user.empty()) return PrintUsersLine(hash_token_user);
  vpm::service::ApplyEnvironment(&options);
  for (const std::string& warning : vpm::service::FairShareWarnings(options)) {
    std::fprintf(stderr, "vpm-server: warning: %s\n", warning.c_str());
  }

  // Signals are taken synchronously by sigwait on this thread: no handler
  // runs in an arbitrary thread.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  // Under a file size limit (RLIMIT_FSIZE) a write past it fails with EFBIG,
  // which the upload spool reports (RESOURCE_EXHAUSTED), instead of the
  // signal killing the server and every user's sessions with it.
  std::signal(SIGXFSZ, SIG_IGN);

  auto server = vpm::service::VpmServer::Create(options);
  if (!server.ok()) {
    std::fprintf(stderr, "vpm-server: %s\n", server.status().ToString().c_str());
    return 2;
  }
  // A crash (SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT) writes the faulting
  // thread's stack, function names only, to stderr before the process dies,
  // so that the log says where. Installed after the server (and the Vulkan
  // driver's LLVM, which sets handlers of its own) is up. The sanitizer
  // builds keep their own reports.
#if !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)
  absl::InstallFailureSignalHandler({});
#endif
  PrintListening(**server, options);
  int signal = 0;
  sigwait(&signals, &signal);
  DrainAndStop(**server, options, signals, signal);
  return 0;
}
