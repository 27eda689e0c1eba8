// Whether the caller of a long operation (a mesh build, a refinement, a
// load, a render) still wants its result. The caller builds the token (the
// service from its gRPC call: cancelled, past its deadline, or the server's
// grace period over); library code takes it as a parameter, polls Check()
// between stages and every thousand or so iterations of a long loop, and
// returns the status it gives (Cancelled, DeadlineExceeded or Unavailable)
// at once, so that work nobody waits for stops within milliseconds.
//
// A default token never cancels. Check() may be called from any thread
// (helpers splitting a loop poll the same token).
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>

#include "server/common/status.h"

namespace vpm {

class CancelToken {
 public:
  // OK while the work is wanted; otherwise the status to return.
  using Poll = std::function<Status()>;

  CancelToken() = default;
  explicit CancelToken(Poll poll) : poll_(std::move(poll)) {}

  Status Check() const { return poll_ ? poll_() : absl::OkStatus(); }
  bool can_cancel() const { return static_cast<bool>(poll_); }

  // A token that a test (or a caller without a gRPC call) cancels by hand.
  class Source {
   public:
    Source() : cancelled_(std::make_shared<std::atomic<bool>>(false)) {}
    void Cancel() { cancelled_->store(true); }
    CancelToken token() const {
      return CancelToken([c = cancelled_] {
        return c->load() ? absl::CancelledError("the operation was cancelled")
                         : absl::OkStatus();
      });
    }

   private:
    std::shared_ptr<std::atomic<bool>> cancelled_;
  };

 private:
  Poll poll_;
};

// Polls a token once every `stride` calls of Tick(), for loops whose
// iterations take microseconds (a poll costs about as much as a
// clock read and an atomic load).
class CancelCheckpoint {
 public:
  explicit CancelCheckpoint(const CancelToken& token, int64_t stride = 1024)
      : token_(token), stride_(stride) {}
  Status Tick() {
    if (!token_.can_cancel() || ++count_ < stride_) return absl::OkStatus();
    count_ = 0;
    return token_.Check();
  }

 private:
  const CancelToken& token_;
  const int64_t stride_;
  int64_t count_ = 0;
};

}  // namespace vpm
