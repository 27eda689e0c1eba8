// A fixed set of threads running posted tasks in FIFO order, plus delayed
// tasks (PostAfter). gRPC callbacks post their heavy work here and return at
// once. Each stream keeps at most one render task queued (frame_stream.h),
// so FIFO order shares the workers, and the GPU queue behind them, fairly
// between sessions.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "server/common/status.h"

namespace vpm::service {

class WorkerPool {
 public:
  struct Options {
    int threads = 2;
    std::string name = "workers";
  };
  static Result<std::unique_ptr<WorkerPool>> Create(const Options& options);
  ~WorkerPool();  // Shutdown()
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  // False once shut down (the task is dropped).
  bool Post(std::function<void()> task);
  bool PostAfter(std::chrono::milliseconds delay, std::function<void()> task);
  // Runs what is queued (not the delayed tasks), then joins the threads.
  void Shutdown();
  int64_t queued() const;

 private:
  explicit WorkerPool(const Options& options) : options_(options) {}
  void Run();

  Options options_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<std::function<void()>> tasks_;
  std::multimap<std::chrono::steady_clock::time_point, std::function<void()>> delayed_;
  bool stopping_ = false;
  std::vector<std::thread> threads_;
};

}  // namespace vpm::service
