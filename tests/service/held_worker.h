// Holds one worker of a WorkerPool busy from construction until Release()
// (or destruction, so that a failed assertion never leaves a pool, or the
// server owning it, unable to stop): jobs queued meanwhile wait, which lets
// a test decide what is queued when the worker is free again.
#pragma once

#include <future>
#include <memory>

#include "server/service/worker_pool.h"

namespace vpm::service::testing {

class HeldWorker {
 public:
  // Returns once the worker holds (posted() false: the pool refused).
  explicit HeldWorker(WorkerPool& pool) : released_(release_.get_future().share()) {
    auto holding = std::make_shared<std::promise<void>>();
    std::future<void> held = holding->get_future();
    posted_ = pool.Post([released = released_, holding] {
      holding->set_value();
      released.wait();
    });
    if (posted_) held.wait();
  }
  ~HeldWorker() { Release(); }
  HeldWorker(const HeldWorker&) = delete;
  HeldWorker& operator=(const HeldWorker&) = delete;

  bool posted() const { return posted_; }
  void Release() {
    if (!done_) release_.set_value();
    done_ = true;
  }

 private:
  std::promise<void> release_;
  std::shared_future<void> released_;
  bool posted_ = false;
  bool done_ = false;
};

}  // namespace vpm::service::testing
