#include "server/service/worker_pool.h"

#include <algorithm>
#include <cmath>

#include "server/common/clock.h"

namespace vpm::service {
namespace {

void DropAll(std::vector<Job>& jobs) {
  for (Job& job : jobs) {
    if (job.drop) job.drop();
  }
  jobs.clear();
}

}  // namespace

Result<std::unique_ptr<WorkerPool>> WorkerPool::Create(const Options& options) {
  if (options.threads < 1 || options.threads > 256) {
    return absl::InvalidArgumentError(
        StrCat(options.name, " threads: ", options.threads, " is outside 1..256"));
  }
  std::unique_ptr<WorkerPool> pool(new WorkerPool(options));
  for (int i = 0; i < options.threads; ++i) pool->threads_.emplace_back([p = pool.get()] { p->Run(); });
  return pool;
}

WorkerPool::~WorkerPool() { Shutdown(std::chrono::steady_clock::now()); }

Status WorkerPool::Submit(Job job) {
  std::vector<Job> dropped;
  Status status;
  {
    std::lock_guard lock(mutex_);
    if (!accepting_) return absl::UnavailableError("the server is shutting down");
    status = queue_.Push(std::move(job), &dropped);
  }
  if (status.ok()) wake_.notify_one();
  DropAll(dropped);
  return status;
}

bool WorkerPool::Post(std::function<void()> task) {
  return Submit(Job{.lane = "", .run = std::move(task), .capped = false}).ok();
}

bool WorkerPool::PostAfter(std::chrono::milliseconds delay, std::function<void()> task) {
  {
    std::lock_guard lock(mutex_);
    if (!accepting_) return false;
    delayed_.emplace(std::chrono::steady_clock::now() + delay, std::move(task));
  }
  wake_.notify_all();
  return true;
}

int64_t WorkerPool::queued() const {
  std::lock_guard lock(mutex_);
  return queue_.size() + static_cast<int64_t>(delayed_.size());
}

int64_t WorkerPool::RetryAfterMs(const std::string& lane) const {
  std::lock_guard lock(mutex_);
  const double jobs = double(queue_.lane_size(lane)) + 1.0;
  return std::max<int64_t>(1, std::llround(jobs * mean_job_ms_ / options_.threads));
}

int64_t WorkerPool::Shutdown(std::chrono::steady_clock::time_point deadline) {
  std::vector<Job> left;
  {
    std::unique_lock lock(mutex_);
    if (stopping_ && threads_.empty()) return 0;
    accepting_ = false;
    delayed_.clear();
    idle_.wait_until(lock, deadline, [this] { return queue_.size() == 0 && running_ == 0; });
    left = queue_.TakeAll();
    stopping_ = true;
  }
  const int64_t dropped = static_cast<int64_t>(left.size());
  DropAll(left);
  wake_.notify_all();
  for (std::thread& t : threads_) {
    if (t.joinable()) t.join();
  }
  threads_.clear();
  return dropped;
}

void WorkerPool::Run() {
  std::unique_lock lock(mutex_);
  while (true) {
    const auto now = std::chrono::steady_clock::now();
    std::vector<Job> purged;
    while (!delayed_.empty() && delayed_.begin()->first <= now) {
      // Uncapped: a due task is never refused (a lost still check would
      // leave its stream without its still frame for good), and it purges
      // nothing. (When lane "" was capped, a due task met a full queue,
      // purged the gone callers' jobs and never dropped them: their calls
      // were never answered, and gRPC's shutdown waited for them forever.)
      const Status pushed = queue_.Push(
          Job{.lane = "", .run = std::move(delayed_.begin()->second), .capped = false}, &purged);
      (void)pushed;  // uncapped: always OK
      delayed_.erase(delayed_.begin());
    }
    if (!purged.empty()) {  // never, as above; were it to happen, each is answered
      lock.unlock();
      DropAll(purged);
      lock.lock();
      continue;
    }
    Job job;
    if (!stopping_ && queue_.Pop(&job)) {
      ++running_;
      lock.unlock();
      const auto start = std::chrono::steady_clock::now();
      job.run();
      const double ms = MsSince(start);
      const std::string lane = std::move(job.lane);
      const bool capped = job.capped;
      job = Job{};  // release what the job held before taking the lock
      lock.lock();
      --running_;
      queue_.Finished(lane, capped);
      // A job of this lane may wait for its running cap: another worker
      // may take it now.
      if (queue_.size() > 0) wake_.notify_one();
      mean_job_ms_ = 0.9 * mean_job_ms_ + 0.1 * ms;
      if (queue_.size() == 0 && running_ == 0) idle_.notify_all();
      continue;
    }
    if (stopping_) return;
    if (delayed_.empty()) {
      wake_.wait(lock);
    } else {
      // A copy: wait_until reads its time point again after waking, when
      // the node holding it may be gone (Shutdown clears delayed_; ASan
      // found the use after free).
      const std::chrono::steady_clock::time_point next = delayed_.begin()->first;
      wake_.wait_until(lock, next);
    }
  }
}

}  // namespace vpm::service
