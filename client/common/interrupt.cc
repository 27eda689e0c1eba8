#include "client/common/interrupt.h"

#include <algorithm>
#include <atomic>
#include <csignal>
#include <thread>

namespace vpm::cli {
namespace {

std::atomic<bool> interrupted{false};

void OnInterrupt(int) { interrupted.store(true); }

}  // namespace

void CatchInterrupts() {
  struct sigaction action = {};
  action.sa_handler = OnInterrupt;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESETHAND;  // a second signal takes the default action
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

bool Interrupted() { return interrupted.load(); }

bool SleepUnlessInterrupted(std::chrono::microseconds duration) {
  const auto end = std::chrono::steady_clock::now() + duration;
  constexpr std::chrono::microseconds kSlice(20000);
  while (!Interrupted()) {
    const auto left = end - std::chrono::steady_clock::now();
    if (left <= std::chrono::microseconds(0)) return true;
    std::this_thread::sleep_for(std::min<std::chrono::steady_clock::duration>(left, kSlice));
  }
  return false;
}

}  // namespace vpm::cli
