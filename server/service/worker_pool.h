// A fixed set of threads running queued jobs, lanes in turn
// (fair_job_queue.h), plus delayed tasks (PostAfter). gRPC callbacks post
// their heavy work here and return at once. Each stream keeps at most one
// render job queued (frame_stream.h) in its own lane, and each user's unary
// calls share one lane, so a burst of calls from one client waits behind
// itself. Shutdown stops taking jobs, lets the queue run until a deadline,
// then drops what is left (each dropped job's `drop` answers its caller).
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "server/common/status.h"
#include "server/service/fair_job_queue.h"

namespace vpm::service {

class WorkerPool {
 public:
  struct Options {
    int threads = 2;
    std::string name = "workers";
    FairJobQueue::Limits limits;  // queued jobs per lane and in all
  };
  static Result<std::unique_ptr<WorkerPool>> Create(const Options& options);
  ~WorkerPool();  // Shutdown(now)
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  // Queues `job`. Unavailable once shutting down; ResourceExhausted when its
  // lane or the pool is full (RetryAfterMs() says when to come back).
  Status Submit(Job job);
  // The server's own task (uncapped, lane "", no drop handling): false
  // only once shutting down. Delayed tasks are queued the same way when due.
  bool Post(std::function<void()> task);
  bool PostAfter(std::chrono::milliseconds delay, std::function<void()> task);
  // Stops taking jobs, runs the queue until `deadline`, drops what is left
  // (calling each job's drop), drops the delayed tasks, joins the threads
  // (a job that is running is waited for: the service's jobs poll their
  // call's CancelToken, which ends them at `deadline`). Returns the number
  // dropped.
  int64_t Shutdown(std::chrono::steady_clock::time_point deadline);
  int64_t queued() const;
  // A client refused for a full lane should wait about this long (ms): the
  // lane's queue times the mean job time, over the threads.
  int64_t RetryAfterMs(const std::string& lane) const;

 private:
  explicit WorkerPool(const Options& options) : options_(options), queue_(options.limits) {}
  void Run();

  Options options_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::condition_variable idle_;  // the queue emptied and nothing runs
  FairJobQueue queue_;
  std::multimap<std::chrono::steady_clock::time_point, std::function<void()>> delayed_;
  int running_ = 0;
  double mean_job_ms_ = 1.0;  // moving average of run times
  bool accepting_ = true;
  bool stopping_ = false;
  std::vector<std::thread> threads_;
};

}  // namespace vpm::service
