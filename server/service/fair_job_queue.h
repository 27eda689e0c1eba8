// The queue behind a worker pool: jobs wait in lanes (one per stream, one per
// user for that user's unary calls), and the lanes take turns, so one
// client's burst of calls waits behind its own lane and never starves
// another's stream. Bounded: a lane and the whole queue have caps, and a
// job refused there gets a retry hint. The server's own work for what it
// has already admitted (a stream's events and frames, its still check, an
// upload's completion) is bounded by the streams that exist and is never
// refused for room: refusing it would leave an admitted call unanswered. Jobs whose caller is gone (cancelled,
// past its deadline) are purged to make room before anything is refused.
// A lane also has a cap on its callers' jobs running at once (the server's
// own work, `capped = false`, is never held back: a stream's FEM and its
// frame run side by side): one user's long calls (mesh builds, loads) leave
// the other workers to the other lanes.
// Not thread-safe: the pool holds its mutex around every call.
#pragma once

#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <list>
#include <map>
#include <string>
#include <vector>

#include "server/common/status.h"

namespace vpm::service {

struct Job {
  std::string lane;              // fair-share key; "" is a lane too
  std::function<void()> run;
  // Optional: true once nobody waits for the result (checked under the
  // pool's lock: must be cheap and must not block).
  std::function<bool()> gone;
  // Optional: called (without the lock) instead of `run` when the job is
  // dropped: purged as gone, or still queued when the pool stops.
  std::function<void()> drop;
  // False for the server's own work on admitted calls: counted, never
  // refused by the caps (callers' requests keep the default, true).
  bool capped = true;
};

class FairJobQueue {
 public:
  struct Limits {
    int64_t max_per_lane = 0;          // queued; 0: no cap
    int64_t max_total = 0;             // queued; 0: no cap
    int64_t max_running_per_lane = 0;  // capped jobs taken, not yet Finished; 0: no cap
  };
  explicit FairJobQueue(Limits limits) : limits_(limits) {}

  // Queues `job`, or refuses it (ResourceExhausted, job untouched) when its
  // lane or the queue is full even after purging gone jobs; the purged jobs
  // are appended to `dropped` for the caller to drop outside its lock.
  Status Push(Job&& job, std::vector<Job>* dropped);
  // The next job, lanes in turn (round robin over the lanes with work whose
  // next job may run: uncapped, or its lane under the running cap); false
  // when none may run now. The caller calls Finished(job) once it has run.
  bool Pop(Job* job);
  void Finished(const std::string& lane, bool capped);
  // Everything queued, oldest lane first, running caps aside (for a
  // shutdown that drops it).
  std::vector<Job> TakeAll();

  int64_t size() const { return size_; }
  int64_t lane_size(const std::string& lane) const;
  int64_t lanes() const { return static_cast<int64_t>(lanes_.size()); }
  int64_t running(const std::string& lane) const;

 private:
  void PurgeGone(std::deque<Job>& lane, std::vector<Job>* dropped);

  Limits limits_;
  std::map<std::string, std::deque<Job>> lanes_;  // lanes with work only
  std::list<std::string> turn_;                   // lanes with work, next first
  std::map<std::string, int64_t> running_;        // capped jobs running, by lane (> 0 only)
  int64_t size_ = 0;
};

}  // namespace vpm::service
