// A MonotoneMinQueue whose next few keys can be read ahead of popping them,
// so that step 2's removal loop (docs/ALGORITHM.md, `spread` mode) can prefetch
// the vertex records of the removals to come: that loop waits on memory far
// more than it computes (docs/MESH.md).
//
// The smallest keys are held in a sorted window popped from the queue (in
// runs: MonotoneMinQueue::PopRun), every window key at most every queued
// key. A key pushed below the window's largest is inserted into the window;
// any other goes to the queue, which then still sees only keys at least its
// last popped one. Pops come out in exactly MonotoneMinQueue's order, (cost,
// item) ascending.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include "server/mesh/monotone_min_queue.h"

namespace vpm {

class LookaheadMinQueue {
 public:
  using Entry = MonotoneMinQueue::Entry;

  bool empty() const { return front_ == window_.size() && queue_.empty(); }
  int64_t size() const { return static_cast<int64_t>(window_.size() - front_) + queue_.size(); }

  // cost must be finite, >= 0 and, with item, not below the last popped key.
  void Push(double cost, int32_t item) {
    const Entry e{cost, item};
    if (front_ < window_.size() && Less(e, window_.back())) {
      window_.insert(std::upper_bound(window_.begin() + front_, window_.end(), e, Less), e);
    } else {
      queue_.Push(cost, item);
    }
  }

  // The k-th smallest key (0: the smallest), or nullptr if fewer than k + 1
  // are queued. A hint for prefetching only: a later Push may come before it.
  const Entry* Ahead(size_t k) {
    while (window_.size() - front_ <= k) {
      if (queue_.empty()) return nullptr;
      queue_.PopRun(&window_);
    }
    return &window_[front_ + k];
  }

  // The smallest key; the queue must not be empty.
  const Entry& Top() { return *Ahead(0); }

  void Pop() {
    Ahead(0);
    if (++front_ == window_.size()) {
      window_.clear();
      front_ = 0;
    } else if (front_ >= kCompactAt) {
      window_.erase(window_.begin(), window_.begin() + static_cast<std::ptrdiff_t>(front_));
      front_ = 0;
    }
  }

 private:
  static constexpr size_t kCompactAt = 256;  // entries consumed before the window is shifted
  static bool Less(const Entry& a, const Entry& b) {
    // -0 and +0 are one cost, as in MonotoneMinQueue.
    return a.cost < b.cost || (a.cost == b.cost && a.item < b.item);
  }

  MonotoneMinQueue queue_;
  std::vector<Entry> window_;  // [front_, end): the smallest keys, ascending
  size_t front_ = 0;
};

}  // namespace vpm
